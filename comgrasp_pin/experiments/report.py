"""Figures (PNG) and Markdown tables of the two experiments, beside the paper's numbers.

Two groups of objects, never pooled: the paper's six rods (``PAPER_OBJECTS`` of
``comgrasp_pin.simulation.objects`` when it exists, else obj1-obj6) and extra objects
(anything else, e.g. obj7, a hammer whose head carries the CoM off the rod's axis, and
obj8, a thick rod). Tables, comparisons and verdicts take ``objects`` (default: the paper's
six that are in the rows); the figures draw extra objects in panels or places of their own.

Columns that newer runs add are used when present and reported as "not recorded" when
absent: ``pos_std_m`` (the stated standard deviation of ``pos_esti_m``), ``extra_pose``
(the planner measured at one more pose), ``estimator``.
"""

from __future__ import annotations

import functools
import math
import re
import textwrap
from collections import Counter
from collections.abc import Sequence
from pathlib import Path
from statistics import NormalDist

import numpy as np

from comgrasp_pin.experiments import paper
from comgrasp_pin.experiments.stats import (
    CALIBRATION_BINS_DEG,
    COMPARISON_RANGES_DEG,
    THETA_BINS_DEG,
    bin_masks,
    bin_series,
    binned_calibration,
    binned_mean,
    calibration,
    mean_ci,
    paired_difference,
    slope_through_origin,
    wilson_interval,
    z_scores,
)

DEFAULT_PAPER_OBJECTS = ("obj1", "obj2", "obj3", "obj4", "obj5", "obj6")
OBJECTS = DEFAULT_PAPER_OBJECTS  # kept for callers of the old name
PAPER_RANGE_DEG = 30.0  # the paper's accuracy figure stops here
NOT_RECORDED = "not recorded"

# Calibration targets (the project's issue): 95 % coverage overall and per bin, rms z.
TARGET_COV95_OVERALL = (0.93, 0.97)
TARGET_COV95_BIN = 0.90
TARGET_RMS_Z = (0.9, 1.1)
N01_COV68 = 2.0 * NormalDist().cdf(1.0) - 1.0  # 0.6827: N(0, 1) inside ±1σ
TIE_POINTS = 0.1  # method comparison: a grasp is a tie when the two differ by <= this (points)

# Colours and markers that stay apart in grey-scale too: ours dark blue, solid line, filled
# circles; the paper's method in our world orange, dashed line, hollow squares; the paper's
# published values black hollow triangles (obj1) and diamonds (obj6), no line.
C_OURS, C_LINE = "#1b4f8a", "#e0701b"
C_BASELINE, C_REGRASP = "#f4b183", "#2e75b6"
PUBLISHED_MARKER = {"obj1": "^", "obj6": "D"}

ESTIMATOR_NAMES = {
    "ipopt": "IPOPT, two poses, axis prior",
    "lstsq": "least squares, two poses",
}
LINE_LABEL = f"paper's method ({paper.METHOD}), our world"


# --- rows, columns and object groups ------------------------------------------------------


def _float(value) -> float:
    try:
        return float(value)
    except (TypeError, ValueError):
        return float("nan")


def _ok(rows: Sequence[dict]) -> list[dict]:
    return [r for r in rows if not r.get("error")]


def _column(rows: Sequence[dict], name: str) -> np.ndarray:
    return np.array([_float(r.get(name)) for r in rows], float)


def recorded(rows: Sequence[dict], name: str) -> bool:
    """Whether any row carries a finite value in column ``name``."""
    return bool(np.isfinite(_column(rows, name)).any()) if rows else False


def _natural(name: str) -> tuple:
    return tuple(int(t) if t.isdigit() else t for t in re.split(r"(\d+)", name))


@functools.lru_cache(maxsize=1)
def paper_objects() -> tuple[str, ...]:
    """The paper's six objects: ``PAPER_OBJECTS`` of the simulation when it exists."""
    try:
        from comgrasp_pin.simulation import objects as sim_objects

        names = getattr(sim_objects, "PAPER_OBJECTS", None)
    except Exception:  # no simulator here: the paper's objects are obj1-obj6
        names = None
    return tuple(names) if names else DEFAULT_PAPER_OBJECTS


def object_groups(rows: Sequence[dict]) -> tuple[list[str], list[str]]:
    """(the paper's objects, extra objects) present in ``rows``, each in a stable order."""
    present = {str(r["object"]) for r in rows if r.get("object")}
    ours = paper_objects()
    return [o for o in ours if o in present], sorted(present - set(ours), key=_natural)


def _objects(rows: Sequence[dict]) -> list[str]:
    paper_objs, extra = object_groups(rows)
    return paper_objs + extra


def _group(rows: Sequence[dict], objects: Sequence[str] | None) -> list[str]:
    """``objects`` as given, or the paper's objects in ``rows``."""
    return list(objects) if objects is not None else object_groups(rows)[0]


def _select(rows: Sequence[dict], objects: Sequence[str]) -> list[dict]:
    keep = set(objects)
    return [r for r in rows if r.get("object") in keep]


def _spec(obj: str):
    try:
        from comgrasp_pin.simulation.objects import get_object

        return get_object(obj)
    except Exception:  # unknown object or no simulator: nothing to describe
        return None


def describe(obj: str, width: int = 42) -> str:
    """The object's short description (from its model), or "" when unknown."""
    spec = _spec(obj)
    if spec is None:
        return ""
    text = str(spec.description).split(":")[0]
    return textwrap.shorten(text, width=width, placeholder="…")


def com_off_axis_m(obj: str) -> float | None:
    """Distance of the object's CoM from the handle's axis in its model (m), or None."""
    spec = _spec(obj)
    if spec is None:
        return None
    c = np.asarray(spec.com(), float)
    return float(np.hypot(c[1], c[2]))


def estimator_label(rows: Sequence[dict]) -> str:
    """Legend name of our estimate, from the rows' ``estimator`` column."""
    names = Counter(str(r["estimator"]) for r in rows if r.get("estimator"))
    if not names:
        return "ours: two poses (estimator not recorded)"
    if len(names) == 1:
        (name,) = names
        return f"ours: {ESTIMATOR_NAMES.get(name, name)}"
    return "ours: " + ", ".join(f"{ESTIMATOR_NAMES.get(k, k)} × {n}" for k, n in names.items())


def _abs_theta(rows: Sequence[dict]) -> np.ndarray:
    return np.abs(_column(rows, "theta_deg"))


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _bin_name(lo: float, hi: float) -> str:
    return f"{lo:g}–{hi:g}"


def _pct(x: float, digits: int = 1) -> str:
    return f"{100 * x:.{digits}f} %" if np.isfinite(x) else "–"


# --- experiment 1: accuracy ------------------------------------------------------------------


def _compress(x):
    """The accuracy figure's x axis: linear to 30 deg, a third as wide beyond."""
    x = np.asarray(x, float)
    return np.where(x <= PAPER_RANGE_DEG, x, PAPER_RANGE_DEG + (x - PAPER_RANGE_DEG) / 3.0)


def _expand(u):
    u = np.asarray(u, float)
    return np.where(u <= PAPER_RANGE_DEG, u, PAPER_RANGE_DEG + (u - PAPER_RANGE_DEG) * 3.0)


def accuracy_series(rows: Sequence[dict], column: str = "accuracy", edges=THETA_BINS_DEG):
    """Per-|θ|-bin mean of ``column`` (%) with its 95 % t interval (capped at 100 %), nan in
    empty bins: the curve of the accuracy figure (``stats.BinSeries``)."""
    rows = _ok(rows)
    series = bin_series(_abs_theta(rows), 100.0 * _column(rows, column), edges)
    np.minimum(series.ci_hi, 100.0, out=series.ci_hi)  # accuracy cannot exceed 100 %
    return series


def _plot_curve(ax, series, colour, style, marker, filled, dodge):
    """The bin means as one line (broken at empty bins: they are nan) with t intervals."""
    x = series.centre + dodge * (series.hi - series.lo)
    (line,) = ax.plot(
        x,
        series.mean,
        linestyle=style,
        marker=marker,
        color=colour,
        lw=1.6,
        ms=5,
        mfc=colour if filled else "white",
        mew=1.3,
        zorder=4,
    )
    have = np.isfinite(series.ci_lo)
    if have.any():
        m = series.mean[have]
        yerr = [m - series.ci_lo[have], series.ci_hi[have] - m]
        ax.errorbar(
            x[have], m, yerr=yerr, fmt="none", ecolor=colour, elinewidth=1.1, capsize=2.5, zorder=3
        )
    return line


def _accuracy_plot(rows: Sequence[dict]):
    """The accuracy figure and its curves: (fig, {object: {"ours": Line2D, "line": ...}})."""
    plt = _pyplot()
    from matplotlib.lines import Line2D

    ok = _ok(rows)
    paper_objs, extra = object_groups(rows)  # an object whose grasps all failed keeps a panel
    has_line = recorded(ok, "accuracy_line")
    groups = [(g, objs) for g, objs in (("paper", paper_objs), ("extra", extra)) if objs]
    if not groups:
        fig, ax = plt.subplots(figsize=(6, 1.6))
        ax.axis("off")
        ax.text(0.5, 0.5, "no accuracy grasps in these rows", ha="center", va="center")
        return fig, {}
    ncols = max(1, min(3, max((len(objs) for _, objs in groups), default=1)))
    heights = [math.ceil(len(objs) / ncols) for _, objs in groups] or [1]
    fig = plt.figure(figsize=(4.1 * ncols, 3.1 * sum(heights) + 1.6), layout="constrained")
    subfigs = fig.subfigures(len(heights), 1, height_ratios=heights, squeeze=False)[:, 0]

    series = {o: {"ours": accuracy_series(_select(ok, [o]))} for o in paper_objs + extra}
    if has_line:
        for o in series:
            series[o]["line"] = accuracy_series(_select(ok, [o]), "accuracy_line")

    def lowest(group: str, objs: list[str]) -> float:
        """The group's shared y axis starts below every bin mean and paper value (a wide
        interval of a bin of two or three grasps may run off it: it is cut at the axis)."""
        candidates = [90.0]
        for o in objs:
            for c in series[o].values():
                candidates += [v for v in c.mean if np.isfinite(v)]
        if group == "paper":
            candidates += [min(v) for v in paper.ACCURACY_PERCENT.values()]
        return max(0.0, 5.0 * math.floor((min(candidates) - 2.0) / 5.0))

    curves: dict[str, dict] = {}
    for sub, (group, objs) in zip(subfigs, groups):
        low = lowest(group, objs)
        nrows = math.ceil(len(objs) / ncols)
        axes = np.atleast_1d(sub.subplots(nrows, ncols, sharex=True, sharey=True, squeeze=False))
        title = (
            "The paper's six objects"
            if group == "paper"
            else "Extra objects (not in the paper; not part of the comparison with it)"
        )
        sub.suptitle(title, fontsize=11, fontweight="bold")
        sub.supxlabel(
            "grey: beyond the paper's range (> 30°), the axis compressed to a third",
            fontsize=8,
            color="0.35",
        )
        for k, ax in enumerate(axes.flat):
            if k >= len(objs):
                ax.set_visible(False)
                continue
            obj = objs[k]
            sel = _select(ok, [obj])
            failed = len(_select(rows, [obj])) - len(sel)
            if not sel:
                ax.text(
                    0.5,
                    0.5,
                    f"no grasp gave an estimate\n({failed} failed)",
                    ha="center",
                    va="center",
                    transform=ax.transAxes,
                    color="0.3",
                    zorder=6,
                    bbox={"facecolor": "white", "edgecolor": "0.6"},
                )
            ax.set_xscale("function", functions=(_compress, _expand))
            ax.axvspan(PAPER_RANGE_DEG, 90.0, color="0.93", zorder=0, lw=0)
            theta = _abs_theta(sel)
            for column, colour, marker in (
                ("accuracy", C_OURS, "o"),
                ("accuracy_line", C_LINE, "s"),
            ):
                if column == "accuracy_line" and not has_line:
                    continue
                y = 100.0 * _column(sel, column)
                below = y < low + 0.5
                ax.scatter(
                    theta[~below],
                    y[~below],
                    s=7,
                    marker=marker,
                    color=colour,
                    alpha=0.22,
                    lw=0,
                    zorder=2,
                )
                if below.any():  # grasps below the axis: a small arrow at its bottom edge
                    ax.scatter(
                        theta[below],
                        np.full(below.sum(), low + 0.6),
                        s=14,
                        marker="v",
                        color=colour,
                        alpha=0.55,
                        lw=0,
                        zorder=2,
                    )
            curves[obj] = {
                "ours": _plot_curve(ax, series[obj]["ours"], C_OURS, "-", "o", True, -0.12)
            }
            if has_line:
                curves[obj]["line"] = _plot_curve(
                    ax, series[obj]["line"], C_LINE, "--", "s", False, 0.12
                )
            if group == "paper":
                for ref, marker in PUBLISHED_MARKER.items():
                    ax.plot(
                        paper.ACCURACY_THETA_DEG,
                        paper.ACCURACY_PERCENT[ref],
                        ls="none",
                        marker=marker,
                        ms=5,
                        mfc="white",
                        mec="k",
                        mew=1.1,
                        zorder=5,
                    )
            desc = describe(obj)
            ax.set_title(
                f"{obj}"
                + (f": {desc}" if desc else "")
                + f"  (n = {len(sel)}"
                + (f", {failed} failed)" if failed else ")"),
                fontsize=8.5,
                loc="left",
            )
            ax.set_xlim(-1.0, 90.0)
            ax.set_ylim(low, 100.8)
            ax.set_xticks([0, 5, 10, 15, 20, 25, 30, 45, 60, 75, 90])
            ax.tick_params(labelsize=8)
            ax.grid(alpha=0.3, lw=0.6)
            if k % ncols == 0:
                ax.set_ylabel("CoM accuracy (%)", fontsize=9)
            if k >= len(objs) - ncols:
                ax.set_xlabel("tilt in the jaws |θ| (deg)", fontsize=8.5)
                ax.tick_params(labelbottom=True)

    handles = [
        Line2D([], [], color=C_OURS, ls="-", marker="o", mfc=C_OURS, label=estimator_label(ok))
    ]
    handles.append(
        Line2D([], [], color=C_LINE, ls="--", marker="s", mfc="white", mew=1.3, label=LINE_LABEL)
        if has_line
        else Line2D([], [], ls="none", label=f"paper's method in our world: {NOT_RECORDED}")
    )
    if paper_objs:
        for ref, marker in PUBLISHED_MARKER.items():
            handles.append(
                Line2D(
                    [],
                    [],
                    ls="none",
                    marker=marker,
                    mfc="white",
                    mec="k",
                    label=f"paper, published: {ref}",
                )
            )
    handles.append(
        Line2D([], [], ls="none", marker="v", color="0.4", label="a grasp below the axis")
    )
    note = (
        "Lines: mean per |θ| bin with its 95 % t interval (a gap where a bin has no grasp); "
        "faint dots: single grasps. Accuracy = 1 − 5·|Δx|/l."
    )
    fig.legend(
        handles=handles,
        loc="outside lower center",
        ncol=3,
        fontsize=8.5,
        frameon=False,
        title=note,
        title_fontsize=8,
    )
    return fig, curves


def accuracy_figure(rows: Sequence[dict], path: Path) -> Path:
    """Accuracy (%) against |θ| (deg), one panel per object (extra objects in panels of
    their own): ours and the paper's method in our world, bin means with 95 % t intervals,
    every grasp faint, and the paper's published obj1 and obj6 values as markers."""
    plt = _pyplot()
    fig, _ = _accuracy_plot(rows)
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return Path(path)


def accuracy_table(
    rows: Sequence[dict], objects: Sequence[str] | None = None, edges=THETA_BINS_DEG
) -> str:
    """Markdown: per |θ| bin and object, mean accuracy (%) of ours / the paper's method in
    our world (``accuracy_line``, same grasps) / the paper's published value (interpolated
    at the bin centre, "–" where the paper has none; left out for a table of extra objects
    only), and the number of grasps. Without ``objects``: the paper's six, then the extra
    objects in a table of their own."""
    if objects is None:
        paper_objs, extra = object_groups(rows)
        tables = [_accuracy_table(rows, paper_objs, edges)] if paper_objs or not extra else []
        if extra:
            tables.append("Extra objects (not in the paper), apart:")
            tables.append(_accuracy_table(rows, extra, edges))
        return "\n\n".join(tables)
    return _accuracy_table(rows, objects, edges)


def _accuracy_table(rows: Sequence[dict], objects: Sequence[str], edges) -> str:
    if not objects:
        return "No accuracy grasps in these rows."
    rows = _ok(rows)
    sel_all = _select(rows, objects)
    if not sel_all:
        return f"No grasp of {', '.join(objects)} gave an estimate."
    has_line = recorded(sel_all, "accuracy_line")
    with_paper = any(o in paper_objects() for o in objects)
    caption = "Cells: mean accuracy (%) of ours / the paper's method in our world (same grasps)"
    caption += (
        " / the paper's published value (– where it has none)" if with_paper else ""
    ) + ", and the number of grasps."
    if not has_line:
        caption += f" The paper's method in our world: {NOT_RECORDED} (n.r.)."
    lines = [
        caption,
        "",
        "| θ bin (deg) | " + " | ".join(objects) + " |",
        "|" + "---|" * (len(objects) + 1),
    ]
    per_object = {}
    for obj in objects:
        sel = _select(rows, [obj])
        masks = bin_masks(_abs_theta(sel), edges)
        ours, line = 100 * _column(sel, "accuracy"), 100 * _column(sel, "accuracy_line")
        per_object[obj] = (masks, ours, line, paper.paper_accuracy_bins(obj, edges))
    for k, (lo, hi) in enumerate(zip(edges[:-1], edges[1:])):
        cells = []
        for obj in objects:
            masks, ours, line, published = per_object[obj]
            inside, ref = masks[k][2], published[k]
            ref_cell = (" / " + (f"{ref:.1f}" if ref is not None else "–")) if with_paper else ""
            if not inside.any():
                cells.append(f"– / –{ref_cell}" if ref is not None else "–")
                continue
            values = line[inside]
            line_cell = f"{np.nanmean(values):.1f}" if np.isfinite(values).any() else "n.r."
            cells.append(
                f"{np.nanmean(ours[inside]):.1f} / {line_cell}{ref_cell} ({int(inside.sum())})"
            )
        lines.append(f"| {_bin_name(lo, hi)} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def method_comparison(
    rows: Sequence[dict], objects: Sequence[str] | None = None, edges=COMPARISON_RANGES_DEG
) -> str:
    """Markdown: ours against the paper's method measured in our world on the same grasps,
    per |θ| range: both means, the paired difference with its 95 % t interval, how many
    grasps each does better; then why, from how each one's miss grows with tan |θ|."""
    ok = _ok(rows)
    objects = _group(ok, objects)
    sel = _select(ok, objects)
    if not sel:
        return "No grasps of these objects."
    if not recorded(sel, "accuracy_line"):
        return f"The paper's method in our world (`accuracy_line`): {NOT_RECORDED}; no comparison."
    theta = _abs_theta(sel)
    ours, line = 100 * _column(sel, "accuracy"), 100 * _column(sel, "accuracy_line")
    lines = [
        f"Objects {', '.join(objects)}; ours = {estimator_label(sel).removeprefix('ours: ')}; "
        f"the paper's method = {paper.METHOD}, from the same grasps. Difference: ours − "
        f"paper's method in accuracy points, mean over the grasps with its 95 % t interval; "
        f"a tie is within {TIE_POINTS:g} points.",
        "",
        "| θ range (deg) | grasps | ours (%) | paper's method (%) | ours − paper's (points, "
        "95 % CI) | ours better | paper's better | tie |",
        "|---|---|---|---|---|---|---|---|",
    ]
    better, worse, even = [], [], []
    ranges = [(lo, hi, m) for lo, hi, m in bin_masks(theta, edges)]
    ranges.append((float(edges[0]), float(edges[-1]), np.isfinite(theta)))
    paired = np.isfinite(ours) & np.isfinite(line)  # both estimates of the same grasp
    for k, (lo, hi, inside) in enumerate(ranges):
        name = "all tilts" if k == len(ranges) - 1 else _bin_name(lo, hi)
        inside = inside & paired
        if not inside.any():
            lines.append(f"| {name} | 0 | – | – | – | – | – | – |")
            continue
        pd = paired_difference(ours[inside], line[inside], tie=TIE_POINTS)
        d = pd.diff
        ci = f" ({d.lo:+.2f} to {d.hi:+.2f})" if np.isfinite(d.lo) else " (n < 2)"
        lines.append(
            f"| {name} | {d.n} | {ours[inside].mean():.1f} | {line[inside].mean():.1f}"
            f" | {d.mean:+.2f}{ci} | {pd.a_better} | {pd.b_better} | {pd.ties} |"
        )
        if k < len(ranges) - 1:
            if np.isfinite(d.lo) and d.lo > 0:
                better.append(f"{name}° (by {d.mean:.1f} points)")
            elif np.isfinite(d.hi) and d.hi < 0:
                worse.append(f"{name}° (by {-d.mean:.1f} points)")
            else:
                even.append(f"{name}°")
    lines += [
        "",
        f"Ours is better (the 95 % interval of the difference above 0) at "
        f"{', '.join(better) or 'no range'}; "
        f"the paper's method at {', '.join(worse) or 'no range'}; "
        f"no clear difference at {', '.join(even) or 'no range'}.",
    ]
    lines += ["", _why(sel, objects)]
    return "\n".join(lines)


def _miss_slopes(rows: Sequence[dict]) -> tuple[float, float, int]:
    """(k_ours, k_line, grasps used): the least-squares k of |miss| ≈ k·|tan θ| (m) over the
    grasps at |θ| >= 10 deg (none below that: tan θ carries no information there)."""
    theta = _abs_theta(rows)
    steep = (theta >= 10.0) & (theta < 89.0)
    t = np.abs(np.tan(np.radians(theta[steep])))
    real = _column(rows, "pos_real_m")[steep]
    miss_ours = np.abs(_column(rows, "pos_esti_m")[steep] - real)
    miss_line = np.abs(_column(rows, "pos_esti_line_m")[steep] - real)
    return slope_through_origin(t, miss_ours), slope_through_origin(t, miss_line), int(steep.sum())


def _why(rows: Sequence[dict], objects: Sequence[str]) -> str:
    """Why the two differ, keyed to the data: the miss of each against tan |θ| per object,
    beside how far the CoM sits off the rod's axis in the object's model."""
    out = [
        "Why: the paper's one-pose estimate meets the rod's axis with the vertical line "
        "through the CoM. When the CoM lies h off the axis (a head taller than the handle, "
        "a weight to one side), the two meet h·tan θ along the axis from the CoM, so that "
        "estimate's miss grows with the tilt. Ours measures a second, rolled pose, which "
        "makes the CoM's height in the jaws observable. Fitted per object over the grasps "
        "at |θ| ≥ 10°, |miss| ≈ k·|tan θ|:",
        "",
        "| object | CoM off the axis, model h (mm) | grasps ≥ 10° | paper's method k (mm) "
        "| ours k (mm) |",
        "|---|---|---|---|---|",
    ]
    matched = []
    for obj in objects:
        sel = _select(rows, [obj])
        h = com_off_axis_m(obj)
        k_ours, k_line, n = (
            _miss_slopes(sel)
            if recorded(sel, "pos_esti_line_m")
            else (float("nan"), float("nan"), 0)
        )
        enough = n >= 3
        cells = [
            f"{1e3 * h:.1f}" if h is not None else "–",
            str(n),
            f"{1e3 * k_line:.1f}" if enough and np.isfinite(k_line) else "–",
            f"{1e3 * k_ours:.1f}" if enough and np.isfinite(k_ours) else "–",
        ]
        out.append(f"| {obj} | " + " | ".join(cells) + " |")
        if enough and h is not None and h > 0.003 and 0.6 <= k_line / h <= 1.5:
            matched.append(f"{obj} (k {1e3 * k_line:.1f} mm, h {1e3 * h:.1f} mm)")
    out.append("")
    if matched:
        out.append(
            "The paper's method's k is close to the model's h for "
            + ", ".join(matched)
            + ": its miss is the h·tan θ of the one-pose line."
        )
    else:
        out.append(
            "No object here has k close to its h with enough steep grasps: other errors "
            "dominate the paper's method's miss in these rows."
        )
    return "\n".join(out)


# --- calibration of the stated standard deviation ------------------------------------------


def calibration_z(rows: Sequence[dict]) -> np.ndarray:
    """z = (pos_esti_m − pos_real_m) / pos_std_m per grasp (nan where no std is recorded)."""
    return z_scores(
        _column(rows, "pos_esti_m"), _column(rows, "pos_real_m"), _column(rows, "pos_std_m")
    )


def _calibration_diagnosis(c) -> str:
    """One sentence on what the overall numbers say about the stated std, or ""."""
    lo95, hi95 = TARGET_COV95_OVERALL
    if not c.n:
        return ""
    if abs(c.mean) > 0.5:
        return (
            f" The mean z of {c.mean:+.2f} says the estimate is biased by about "
            f"{abs(c.mean):.1f} stated std."
        )
    if c.cov95 < lo95:
        return " Too few inside: the stated std is too small for these misses."
    if c.cov95 > hi95 and c.rms < TARGET_RMS_Z[0]:
        return " Too many inside and rms z below 1: the stated std is too large (cautious)."
    if c.rms > TARGET_RMS_Z[1]:
        return (
            " Coverage near its target with an rms z above 1: a few misses far out (heavy tails)."
        )
    return ""


def _cov_cell(inside: int, n: int) -> str:
    if not n:
        return "–"
    lo, hi = wilson_interval(inside, n)
    return f"{100 * inside / n:.1f} % ({100 * lo:.0f}–{100 * hi:.0f})"


def calibration_table(
    rows: Sequence[dict], objects: Sequence[str] | None = None, edges=CALIBRATION_BINS_DEG
) -> str:
    """Markdown: z = (pos_esti − pos_real) / pos_std against N(0, 1) per |θ| bin and
    overall: n, the share inside ±1σ (68 %) and ±1.96σ (95 %) with Wilson intervals, rms
    and mean z, and the targets (95 %: 93–97 % overall and ≥ 90 % per bin; rms z 0.9–1.1)."""
    ok = _ok(rows)
    objects = _group(ok, objects)
    sel = _select(ok, objects)
    if not recorded(sel, "pos_std_m"):
        return f"Calibration: `pos_std_m` {NOT_RECORDED} in these rows; no calibration."
    z, theta = calibration_z(sel), _abs_theta(sel)
    lines = [
        f"Objects {', '.join(objects)}. z = (pos_esti − pos_real) / pos_std; N(0, 1) has "
        f"{100 * N01_COV68:.1f} % inside ±1σ, 95 % inside ±1.96σ and rms 1. In brackets: "
        "95 % Wilson interval of the coverage.",
        "",
        "| θ bin (deg) | n | coverage ±1σ (68 %) | coverage ±1.96σ (95 %) | rms z | mean z "
        "| target |",
        "|---|---|---|---|---|---|---|",
    ]
    short = []
    for lo, hi, c in binned_calibration(theta, z, edges):
        if not c.n:
            lines.append(f"| {_bin_name(lo, hi)} | 0 | – | – | – | – | – |")
            continue
        ok_bin = c.cov95 >= TARGET_COV95_BIN
        verdict = "met"
        if not ok_bin:
            short.append(f"{_bin_name(lo, hi)}° ({_pct(c.cov95)}, n {c.n})")
            # a bin whose Wilson interval still reaches the target may be short by chance
            reaches = wilson_interval(c.inside95, c.n)[1] >= TARGET_COV95_BIN
            verdict = "not met (interval reaches it)" if reaches else "not met"
        lines.append(
            f"| {_bin_name(lo, hi)} | {c.n} | {_cov_cell(c.inside68, c.n)} | "
            f"{_cov_cell(c.inside95, c.n)} | {c.rms:.2f} | {c.mean:+.2f} | "
            f"95 % ≥ {100 * TARGET_COV95_BIN:.0f} %: {verdict} |"
        )
    c = calibration(z)
    lo95, hi95 = TARGET_COV95_OVERALL
    met95 = lo95 <= c.cov95 <= hi95
    met_rms = TARGET_RMS_Z[0] <= c.rms <= TARGET_RMS_Z[1]
    lines.append(
        f"| **all** | {c.n} | {_cov_cell(c.inside68, c.n)} | {_cov_cell(c.inside95, c.n)} | "
        f"{c.rms:.2f} | {c.mean:+.2f} | 95 % in {100 * lo95:.0f}–{100 * hi95:.0f} %: "
        f"{'met' if met95 else 'not met'}; rms z in {TARGET_RMS_Z[0]:g}–{TARGET_RMS_Z[1]:g}: "
        f"{'met' if met_rms else 'not met'} |"
    )
    missing = int(np.sum(~np.isfinite(z)))
    lines += [
        "",
        f"Targets: 95 % coverage {100 * lo95:.0f}–{100 * hi95:.0f} % overall "
        f"({'met' if met95 else 'not met'}: {_pct(c.cov95)}) and ≥ "
        f"{100 * TARGET_COV95_BIN:.0f} % in every bin "
        f"({'not met at ' + ', '.join(short) if short else 'met'}); rms z "
        f"{TARGET_RMS_Z[0]:g}–{TARGET_RMS_Z[1]:g} ({'met' if met_rms else 'not met'}: "
        f"{c.rms:.2f})."
        + _calibration_diagnosis(c)
        + (f" {missing} grasp(s) without a recorded std are left out." if missing else ""),
    ]
    return "\n".join(lines)


def _calibration_row(axes, rows, objects, edges, colours, markers, extra: bool):
    """One row of the calibration figure: histogram of z, coverage per bin, rms z per bin."""
    ax_h, ax_c, ax_r = axes
    span = 5.0
    grid = np.linspace(-span, span, 400)
    width = 0.5
    bins = np.arange(-span, span + 1e-9, width)
    positions = np.arange(len(edges))  # the bins and "all"
    labels = [_bin_name(lo, hi) for lo, hi in zip(edges[:-1], edges[1:])] + ["all"]
    n_tick = [[] for _ in positions]
    groups = [("paper's six", objects)] if not extra else [(o, [o]) for o in objects]
    total = 0
    for g, (name, objs) in enumerate(groups):
        sel = _select(rows, objs)
        z, theta = calibration_z(sel), _abs_theta(sel)
        good = np.isfinite(z)
        z, theta = z[good], theta[good]
        total += len(z)
        colour, marker = colours[g % len(colours)], markers[g % len(markers)]
        clipped = np.clip(z, -span + 1e-9, span - 1e-9)
        out_lo, out_hi = int(np.sum(z <= -span)), int(np.sum(z >= span))
        label = f"{name}, n = {len(z)}"
        if out_lo or out_hi:
            label += f"\n({out_lo} below −{span:g}, {out_hi} above +{span:g}: in the end bins)"
        ax_h.hist(
            clipped,
            bins=bins,
            histtype="stepfilled" if not extra else "step",
            color=colour,
            alpha=0.55 if not extra else 1.0,
            lw=1.5,
            label=label,
        )
        per_bin = binned_calibration(theta, z, edges) + [(0, 0, calibration(z))]
        dodge = 0.0 if not extra else (g - 0.5 * (len(groups) - 1)) * 0.25
        for level, (attr, mk, filled) in enumerate(
            (("inside95", marker, True), ("inside68", "o" if not extra else marker, False))
        ):
            xs, ps, lo_err, hi_err = [], [], [], []
            for p, (_, _, c) in zip(positions, per_bin):
                if not c.n:
                    continue
                k = getattr(c, attr)
                lo, hi = wilson_interval(k, c.n)
                xs.append(p + dodge + (0.0 if level == 0 else 0.12))
                ps.append(100 * k / c.n)
                lo_err.append(max(0.0, 100 * k / c.n - 100 * lo))
                hi_err.append(max(0.0, 100 * hi - 100 * k / c.n))
            ax_c.errorbar(
                xs,
                ps,
                yerr=[lo_err, hi_err],
                fmt=mk,
                color=colour,
                mfc=colour if filled else "white",
                ms=6,
                capsize=2.5,
                lw=1.0,
                label=(f"{name}: " if extra else "")
                + ("inside ±1.96σ (95 %)" if level == 0 else "inside ±1σ (68 %)"),
            )
        xs = [p + dodge for p, (_, _, c) in zip(positions, per_bin) if c.n]
        ax_r.plot(
            xs,
            [c.rms for _, _, c in per_bin if c.n],
            ls="none",
            marker=marker,
            ms=7,
            color=colour,
            label=name if extra else "rms z",
        )
        for p, (_, _, c) in zip(positions, per_bin):
            n_tick[p].append(str(c.n))
    n_ref = total / max(1, len(groups))
    ax_h.plot(
        grid,
        n_ref * width * np.exp(-0.5 * grid**2) / math.sqrt(2 * math.pi),
        "k--",
        lw=1.3,
        label=f"N(0, 1) for n = {n_ref:.0f}",
    )
    ax_h.set_xlim(-span, span)
    ax_h.set_xlabel("z = (pos_esti − pos_real) / pos_std", fontsize=9)
    ax_h.set_ylabel("grasps per 0.5 of z", fontsize=9)
    ax_h.legend(fontsize=7, loc="upper left")
    ax_h.set_ylim(0, 1.35 * ax_h.get_ylim()[1])  # room for the legend
    ax_h.set_title("distribution of z (|z| > 5 in the end bins)", fontsize=9, loc="left")
    ax_c.axhspan(
        100 * TARGET_COV95_OVERALL[0],
        100 * TARGET_COV95_OVERALL[1],
        color="#cfe8cf",
        zorder=0,
        label="95 % target, overall (93–97 %)",
    )
    ax_c.axhline(
        100 * TARGET_COV95_BIN, color="0.35", ls="--", lw=1, label="95 % target, every bin (≥ 90 %)"
    )
    ax_c.axhline(100 * N01_COV68, color="0.35", ls=":", lw=1, label="N(0, 1) inside ±1σ: 68.3 %")
    ax_c.set_ylim(0, 103)
    ax_c.set_ylabel("grasps inside the interval (%)", fontsize=9)
    ax_c.set_title("coverage per |θ| bin (95 % Wilson intervals)", fontsize=9, loc="left")
    ax_r.axhspan(
        TARGET_RMS_Z[0], TARGET_RMS_Z[1], color="#cfe8cf", zorder=0, label="target 0.9–1.1"
    )
    ax_r.axhline(1.0, color="0.35", ls=":", lw=1)
    top = max(
        [1.2]
        + [
            v
            for line in ax_r.get_lines()
            for v in np.asarray(line.get_ydata(), float)
            if np.isfinite(v)
        ]
    )
    if top > 3.0:  # heavy tails: a log axis with plain numbers
        from matplotlib.ticker import FixedLocator, FuncFormatter, NullLocator

        ax_r.set_yscale("log")
        bottom = min(
            v
            for line in ax_r.get_lines()
            for v in np.asarray(line.get_ydata(), float)
            if np.isfinite(v) and v > 0
        )
        every = (0.01, 0.02, 0.05, 0.1, 0.2, 0.5, 1, 2, 5, 10, 20, 50, 100, 200, 500, 1000)
        ticks = [t for t in every if bottom / 2.5 <= t <= 2.5 * top]
        ax_r.yaxis.set_major_locator(FixedLocator(ticks))
        ax_r.yaxis.set_minor_locator(NullLocator())
        ax_r.yaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
        ax_r.set_ylabel("rms z (log scale)", fontsize=9)
    else:
        ax_r.set_ylim(0, max(1.5, 1.1 * top))
        ax_r.set_ylabel("rms z", fontsize=9)
    ax_r.set_title("rms z per |θ| bin", fontsize=9, loc="left")
    for ax in (ax_c, ax_r):
        ticks = [f"{lab}\nn={'/'.join(ns)}" for lab, ns in zip(labels, n_tick)]
        ax.set_xticks(positions, ticks, fontsize=7)
        ax.set_xlabel("|θ| bin (deg)" + (f"; n = {'/'.join(objects)}" if extra else ""), fontsize=9)
        ax.axvline(positions[-1] - 0.5, color="0.6", lw=0.8)
        ax.set_xlim(-0.6, positions[-1] + 0.6)
        ax.legend(
            fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.24), ncol=2, frameon=False
        )
    for ax in axes:
        ax.grid(alpha=0.3, lw=0.6)
        ax.tick_params(labelsize=8)


def calibration_figure(rows: Sequence[dict], path: Path) -> Path:
    """z = (pos_esti − pos_real) / pos_std against N(0, 1): histogram with the N(0, 1)
    reference, coverage of the ±1σ and ±1.96σ intervals per |θ| bin with the targets, rms z
    per bin; the paper's six objects in the top row, extra objects in a row of their own."""
    plt = _pyplot()
    ok = _ok(rows)
    paper_objs, extra = object_groups(ok)
    groups = [
        (g, objs)
        for g, objs in (("paper", paper_objs), ("extra", extra))
        if objs and recorded(_select(ok, objs), "pos_std_m")
    ]
    if not groups:
        fig, ax = plt.subplots(figsize=(6, 1.6))
        ax.axis("off")
        ax.text(
            0.5,
            0.5,
            f"pos_std_m {NOT_RECORDED} in these rows: no calibration",
            ha="center",
            va="center",
            fontsize=11,
        )
        fig.savefig(path, dpi=120)
        plt.close(fig)
        return Path(path)
    fig = plt.figure(figsize=(16, 4.6 * len(groups)), layout="constrained")
    subfigs = fig.subfigures(len(groups), 1, squeeze=False)[:, 0]
    for sub, (group, objs) in zip(subfigs, groups):
        axes = sub.subplots(1, 3, gridspec_kw={"width_ratios": [1.0, 1.35, 1.0]})
        if group == "paper":
            sub.suptitle(
                f"The paper's six objects, pooled ({', '.join(objs)})",
                fontsize=11,
                fontweight="bold",
            )
            _calibration_row(axes, ok, objs, CALIBRATION_BINS_DEG, ["#1b4f8a"], ["s"], False)
        else:
            sub.suptitle(
                "Extra objects (not in the paper), each on its own", fontsize=11, fontweight="bold"
            )
            _calibration_row(
                axes,
                ok,
                objs,
                CALIBRATION_BINS_DEG,
                ["#7b3294", "#008837", "#a6611a"],
                ["D", "^", "P"],
                True,
            )
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return Path(path)


def calibration_section(rows: Sequence[dict], out: Path, objects=None) -> str:
    """The report's calibration text: the figure (written to ``out/calibration.png``) and
    the table, or "not recorded" when the rows carry no ``pos_std_m``."""
    ok = _ok(rows)
    objects = _group(ok, objects)
    if not recorded(ok, "pos_std_m"):
        return (
            f"`pos_std_m` (the stated standard deviation of each estimate) is {NOT_RECORDED} "
            "in this run: no calibration."
        )
    calibration_figure(rows, Path(out) / "calibration.png")
    return "![calibration](calibration.png)\n\n" + calibration_table(rows, objects)


# --- experiment 2: pick and place ------------------------------------------------------------


def success_rates(rows: Sequence[dict]) -> dict[tuple[str, str], tuple[int, int]]:
    """(object, method) -> (successes, trials); failed trials (errors) count as failures."""
    out: dict[tuple[str, str], tuple[int, int]] = {}
    for r in rows:
        key = (r["object"], r["method"])
        s, n = out.get(key, (0, 0))
        out[key] = (s + int(_succeeded(r)), n + 1)
    return out


def _succeeded(row: dict) -> bool:
    return not row.get("error") and int(_float(row.get("success")) == 1)


def regrasp_figure(rows: Sequence[dict], path: Path) -> Path:
    """Success rate (%) per object, baseline and regrasp side by side with 95 % Wilson
    intervals and the trial counts on the bars; the paper's values as diamonds; extra
    objects to the right, apart."""
    plt = _pyplot()
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    rates = success_rates(rows)
    paper_objs, extra = object_groups(rows)
    xs = {o: float(k) for k, o in enumerate(paper_objs)}
    xs.update(
        {o: len(paper_objs) + 0.8 + k for k, o in enumerate(extra)}
        if paper_objs
        else {o: float(k) for k, o in enumerate(extra)}
    )
    objects = paper_objs + extra
    fig, ax = plt.subplots(figsize=(max(6.5, 1.15 * len(objects) + 2.0), 4.8), layout="constrained")
    half = 0.2
    for offset, method, colour, hatch in (
        (-half, "baseline", C_BASELINE, "///"),
        (half, "regrasp", C_REGRASP, None),
    ):
        for obj in objects:
            s, n = rates.get((obj, method), (0, 0))
            x = xs[obj] + offset
            if not n:
                ax.text(x, 1.5, "no trials", rotation=90, ha="center", va="bottom", fontsize=7)
                continue
            p = s / n
            lo, hi = wilson_interval(s, n)
            ax.bar(x, 100 * p, 2 * half * 0.95, color=colour, hatch=hatch, edgecolor="0.25", lw=0.6)
            ax.errorbar(
                x,
                100 * p,
                yerr=[[max(0.0, 100 * (p - lo))], [max(0.0, 100 * (hi - p))]],
                fmt="none",
                ecolor="k",
                capsize=3,
                lw=1.1,
            )
            ax.text(
                x,
                1.5,
                f"{s}/{n}",
                rotation=90,
                ha="center",
                va="bottom",
                fontsize=7.5,
                bbox={"facecolor": "white", "alpha": 0.7, "lw": 0, "pad": 0.8},
            )
            ref = paper.SUCCESS_PERCENT.get(obj)
            if ref is not None:
                value = ref[0] if method == "regrasp" else ref[1]
                ax.plot(
                    x, value, ls="none", marker="D", ms=7, mfc="white", mec="k", mew=1.4, zorder=5
                )
    if paper_objs and extra:
        sep = len(paper_objs) - 0.1
        ax.axvline(sep, color="0.5", ls=":", lw=1)
        ax.text(
            sep + 0.1, 108, "extra objects\n(not in the paper)", fontsize=8, va="top", color="0.3"
        )
    ax.set_xticks([xs[o] for o in objects], objects)
    ax.set_ylabel("pick-and-place success (%)")
    ax.set_ylim(0, 110)
    ax.set_yticks(range(0, 101, 20))
    ax.grid(axis="y", alpha=0.3)
    handles = [
        Patch(
            facecolor=C_BASELINE,
            hatch="///",
            edgecolor="0.25",
            label="baseline: grasp at the geometric centre (ours)",
        ),
        Patch(facecolor=C_REGRASP, edgecolor="0.25", label="regrasp planner (ours)"),
        Line2D([], [], color="k", marker="|", ms=10, ls="none", label="95 % Wilson interval"),
    ]
    if paper_objs:
        handles.append(
            Line2D(
                [],
                [],
                ls="none",
                marker="D",
                mfc="white",
                mec="k",
                mew=1.4,
                label="paper, published (same method)",
            )
        )
    fig.legend(handles=handles, loc="outside lower center", ncol=2, fontsize=8, frameon=False)
    ax.set_title(
        "Pick-and-place success per object; on the bars: successes / trials",
        fontsize=9.5,
        loc="left",
    )
    fig.savefig(path, dpi=130)
    plt.close(fig)
    return Path(path)


def regrasp_table(rows: Sequence[dict], objects: Sequence[str] | None = None) -> str:
    """Markdown: success rates with 95 % intervals per object and method, the paper's beside.
    Without ``objects``: the paper's six, then the extra objects in rows of their own."""
    rates = success_rates(rows)
    lines = [
        "| object | baseline (ours) | regrasp (ours) | baseline (paper) | regrasp (paper) |",
        "|---|---|---|---|---|",
    ]
    if objects is None:
        paper_objs, extra = object_groups(rows)
        names = paper_objs + ([""] if paper_objs and extra else []) + extra
    else:
        names = list(objects)
    for obj in names:
        if not obj:  # the extra objects' rows follow, apart
            lines.append("| *extra objects, not in the paper:* | | | | |")
            continue
        cells = []
        for method in ("baseline", "regrasp"):
            s, n = rates.get((obj, method), (0, 0))
            lo, hi = wilson_interval(s, n)
            cells.append(
                f"{100 * s / n:.1f} % ({s}/{n}, {100 * lo:.0f}–{100 * hi:.0f})" if n else "–"
            )
        ref = paper.SUCCESS_PERCENT.get(obj)
        ref_cells = [f"{ref[1]:.1f} %", f"{ref[0]:.1f} %"] if ref else ["–", "–"]
        lines.append(f"| {obj} | " + " | ".join(cells + ref_cells) + " |")
    return "\n".join(lines)


def _scene_key(row: dict) -> tuple[str, str, str]:
    """The scene a trial saw: baseline and regrasp of the same key share it."""
    return (str(row.get("object")), str(row.get("trial")), str(row.get("seed", "")))


def extra_pose_summary(
    rows: Sequence[dict], objects: Sequence[str] | None = None, pooled: bool | None = None
) -> str:
    """Markdown: how often the regrasp planner measured at one more pose before deciding
    (``extra_pose``), and the success with and without it, beside the baseline on the same
    scenes: what the extra pose bought. "Not recorded" without the column. ``pooled``
    (default: for the paper's group only) adds a row and a sentence over all ``objects``;
    otherwise every object gets its own."""
    pooled = objects is None if pooled is None else pooled
    objects = _group(rows, objects)
    reg = [r for r in _select(rows, objects) if r.get("method") == "regrasp"]
    if not reg:
        return "No regrasp trials of these objects."
    if not recorded(reg, "extra_pose"):
        return f"Extra measurement pose (`extra_pose`): {NOT_RECORDED} in this run."
    base = {_scene_key(r): _succeeded(r) for r in rows if r.get("method") == "baseline"}
    lines = [
        "| object | regrasp trials | one more pose | success with it | success without it "
        "| baseline on the scenes with it |",
        "|---|---|---|---|---|---|",
    ]
    groups = [(o, [r for r in reg if r["object"] == o]) for o in objects]
    groups = [(o, trials) for o, trials in groups if trials]
    for name, trials in groups:
        lines.append(_extra_pose_row(name, trials, base))
    if pooled and len(groups) > 1:
        lines.append(_extra_pose_row("**all**", reg, base))
    sentences = [("", reg)] if pooled else [(f"{o}: ", trials) for o, trials in groups]
    text = [_extra_pose_sentence(prefix, trials, base) for prefix, trials in sentences]
    text.append(
        "The planner asks for the extra pose when its first estimate is in doubt, so the "
        "trials with it are the harder scenes: the baseline on the same scenes is the fair "
        "reference for what it bought, not the trials without it."
    )
    return "\n".join(lines) + "\n\n" + " ".join(text)


def _split_extra_pose(trials: list[dict]) -> tuple[list[dict], list[dict], int]:
    flag = _column(trials, "extra_pose")
    with_it = [r for r, f in zip(trials, flag) if f == 1]
    without = [r for r, f in zip(trials, flag) if f == 0]
    return with_it, without, len(trials) - len(with_it) - len(without)


def _rate_cell(trials: list[dict]) -> str:
    s, n = sum(_succeeded(r) for r in trials), len(trials)
    if not n:
        return "–"
    lo, hi = wilson_interval(s, n)
    return f"{s}/{n} ({100 * s / n:.0f} %, {100 * lo:.0f}–{100 * hi:.0f})"


def _baseline_on(trials: list[dict], base: dict) -> list[bool]:
    return [base[_scene_key(r)] for r in trials if _scene_key(r) in base]


def _extra_pose_row(name: str, trials: list[dict], base: dict) -> str:
    with_it, without, unknown = _split_extra_pose(trials)
    seen = _baseline_on(with_it, base)
    count = f"{len(with_it)} of {len(with_it) + len(without)}"
    count += f" ({unknown} n.r.)" if unknown else ""
    base_cell = f"{sum(seen)}/{len(seen)} ({100 * sum(seen) / len(seen):.0f} %)" if seen else "–"
    return (
        f"| {name} | {len(trials)} | {count} | {_rate_cell(with_it)} | "
        f"{_rate_cell(without)} | {base_cell} |"
    )


def _extra_pose_sentence(prefix: str, trials: list[dict], base: dict) -> str:
    with_it, without, _ = _split_extra_pose(trials)
    s_w, s_wo = sum(map(_succeeded, with_it)), sum(map(_succeeded, without))
    seen = _baseline_on(with_it, base)
    text = (
        f"{prefix}the planner measured at one more pose in {len(with_it)} of "
        f"{len(with_it) + len(without)} regrasp trials"
    )
    if with_it:
        text += f"; with it {s_w}/{len(with_it)} succeeded"
        if seen:
            text += f", where the baseline on the same scenes succeeded {sum(seen)}/{len(seen)}"
    if without:
        text += f"; without it {s_wo}/{len(without)}"
    acc_w = mean_ci(100 * _column(with_it, "accuracy"))
    acc_wo = mean_ci(100 * _column(without, "accuracy"))
    if acc_w.n and acc_wo.n:
        text += (
            f"; mean CoM accuracy with it {acc_w.mean:.1f} % (n {acc_w.n}), without "
            f"{acc_wo.mean:.1f} % (n {acc_wo.n})"
        )
    return (text if prefix else text[0].upper() + text[1:]) + "."


# --- verdicts -------------------------------------------------------------------------------

TARGET_BELOW_10 = 99.0  # the project's aims (issue 6): mean accuracy (%) below 10 deg ...
TARGET_UP_TO_30 = 95.0  # ... and from 10 to 30 deg
SHORTFALL = 0.95  # grasps below this accuracy get their error source named


def error_source(row: dict) -> str:
    """The error that dominates one grasp's CoM estimate, from what the trial recorded.

    In order: the side camera's tilt off by more than 1 deg (perception); the rod turned in
    the jaws between the two measurement poses (slip during the measurement); the
    estimate's own standard deviation, from the torque noise, explains the miss (torque
    noise); otherwise the rod's geometry (a thick handle or a CoM off the rod's axis seen at
    a steep tilt, where a small error of the perceived axis moves the projection).
    """
    miss = abs(float(row["pos_esti_m"]) - float(row["pos_real_m"]))
    theta_error = abs(float(row["theta_deg"]) - float(row["theta_true_deg"])) % 180.0
    if min(theta_error, 180.0 - theta_error) > 1.0:
        return "perception (tilt)"
    if int(float(row.get("rolled_slip") or 0)):
        return "slip during the measurement"
    com_std = float(row.get("com_std_m") or "nan")
    if np.isfinite(com_std) and 2.0 * com_std >= miss:
        return "torque noise"
    return "rod geometry at the tilt"


def accuracy_verdict(rows: Sequence[dict], objects: Sequence[str] | None = None) -> str:
    """Markdown: every object against the paper's obj1 curve (the better of its two) and
    the project's aims, the failed grasps, and the error behind each poor grasp."""
    objects = _group(rows, objects)
    rows = _select(rows, objects)
    ok = _ok(rows)
    lines = [
        "| object | grasps (failed) | mean θ < 10° | mean 10–30° | worst bin vs paper obj1 "
        "(≤ 30°) | above paper in every bin |",
        "|---|---|---|---|---|---|",
    ]
    for obj in objects:
        sel = [r for r in ok if r["object"] == obj]
        failed = sum(1 for r in rows if r["object"] == obj and r.get("error"))
        if not sel and not failed:
            continue
        theta = _abs_theta(sel) if sel else np.zeros(0)
        acc = 100 * _column(sel, "accuracy") if sel else np.zeros(0)
        low, mid = acc[theta < 10.0], acc[(theta >= 10.0) & (theta <= PAPER_RANGE_DEG)]
        margins = []
        for lo, hi, mean, n in binned_mean(theta, acc):
            ref = paper.paper_accuracy_at("obj1", 0.5 * (lo + hi))
            if n and hi <= PAPER_RANGE_DEG and ref is not None:
                margins.append((mean - ref, f"{lo:g}–{hi:g}°"))
        worst = min(margins) if margins else None
        cells = [
            f"{len(sel) + failed} ({failed})",
            f"{low.mean():.1f} % ({len(low)})" if len(low) else "–",
            f"{mid.mean():.1f} % ({len(mid)})" if len(mid) else "–",
            f"{worst[0]:+.1f} points at {worst[1]}" if worst else "–",
            ("yes" if worst[0] >= 0 else "no") if worst else "–",
        ]
        lines.append(f"| {obj} | " + " | ".join(cells) + " |")
    poor = [r for r in ok if float(r["accuracy"]) < SHORTFALL]
    lines.append("")
    lines.append(
        f"Aims: mean ≥ {TARGET_BELOW_10:g} % below 10° and ≥ {TARGET_UP_TO_30:g} % from 10° "
        f"to 30°. {len(poor)} of {len(ok)} grasps are below {100 * SHORTFALL:g} %"
        + (":" if poor else ".")
    )
    for source, n in Counter(error_source(r) for r in poor).most_common():
        lines.append(f"- {source}: {n}")
    errors: dict[str, int] = {}
    for r in rows:
        if r.get("error"):
            kind = str(r["error"]).split(":")[0].rsplit(".", 1)[-1]
            errors[kind] = errors.get(kind, 0) + 1
    if errors:
        text = ", ".join(f"{k} × {v}" for k, v in sorted(errors.items(), key=lambda kv: -kv[1]))
        lines.append(f"\nGrasps that gave no estimate: {text}.")
    return "\n".join(lines)


def regrasp_verdict(
    rows: Sequence[dict], aim: float = 97.0, objects: Sequence[str] | None = None
) -> str:
    """Markdown: the regrasp method against the paper and the project's aim, and why the
    failed trials failed (their recorded reason or error)."""
    objects = _group(rows, objects)
    rows = _select(rows, objects)
    if not rows:
        return "No pick-and-place trials of these objects."
    rates = success_rates(rows)
    met, short = [], []
    for obj in objects:
        s, n = rates.get((obj, "regrasp"), (0, 0))
        ref = paper.SUCCESS_PERCENT.get(obj)
        if not n or ref is None:
            continue
        rate = 100.0 * s / n
        (met if rate >= ref[0] else short).append(f"{obj} {rate:.0f} %")
    total = [rates.get((o, "regrasp"), (0, 0)) for o in objects]
    s_all, n_all = sum(t[0] for t in total), sum(t[1] for t in total)
    lines = [
        f"Regrasp overall ({', '.join(objects)}): {s_all}/{n_all}"
        + (f" ({100.0 * s_all / n_all:.1f} %, aim ≥ {aim:g} %)." if n_all else "."),
    ]
    if met or short:
        lines.append(
            f"At or above the paper: {', '.join(met) or 'none'}; "
            f"below: {', '.join(short) or 'none'}."
        )
    reasons: dict[tuple[str, str], int] = {}
    for r in rows:
        failed = r.get("error") or not int(_float(r.get("success")) == 1)
        if not failed:
            continue
        why = str(r.get("error") or r.get("reason") or "?")
        where = why.rsplit("; the rod ended ", 1)
        why = why.split(":")[0].split(";")[0].rsplit(".", 1)[-1]
        if len(where) == 2:
            why += f", rod ended {where[1]}"
        key = (r["method"], why)
        reasons[key] = reasons.get(key, 0) + 1
    if reasons:
        lines.append("")
        lines.append("Failed trials, by method and the last thing the robot did or saw:")
        for (method, why), n in sorted(reasons.items(), key=lambda kv: (kv[0][0], -kv[1])):
            lines.append(f"- {method}: {why} × {n}")
    return "\n".join(lines)


# --- the report's run summary and the extra objects' section -------------------------------


def run_summary(acc: Sequence[dict], reg: Sequence[dict], seed: int | None = None) -> str:
    """One paragraph: what the rows hold, counted from the rows themselves (so that rows of
    several runs or seeds are described as they are): grasps and trials per object and
    method, the objects in each group, the run seeds and the failures."""
    rows = list(acc) + list(reg)
    seeds = sorted(
        {int(_float(r["seed"])) // 100_000 for r in rows if np.isfinite(_float(r.get("seed")))}
    )
    if not seeds and seed is not None:
        seeds = [int(seed)]
    paper_objs, extra = object_groups(rows)
    counts = Counter((r.get("object"), r.get("method")) for r in reg)
    counts.update(Counter((r.get("object"), "accuracy") for r in acc))
    per = sorted(set(counts.values()))
    per_text = "no trials" if not per else f"{per[0]}" if len(per) == 1 else f"{per[0]}–{per[-1]}"
    failed = sum(bool(r.get("error")) for r in rows)
    seed_text = (
        f"seed {NOT_RECORDED}"
        if not seeds
        else f"seed {seeds[0]}"
        if len(seeds) == 1
        else f"seeds {', '.join(map(str, seeds))} pooled"
    )
    groups = f"the paper's objects {', '.join(paper_objs) or 'none'}"
    if extra:
        groups += f"; extra objects {', '.join(extra)}, reported apart"
    return (
        f"{len(acc)} accuracy grasps and {len(reg)} pick-and-place trials ({per_text} per "
        f"object and method; {groups}; {seed_text}); {failed} trial(s) failed with an error "
        "(listed in the CSVs' `error` column and counted as failures)."
    )


def extra_objects_section(acc: Sequence[dict], reg: Sequence[dict]) -> str:
    """Markdown for the extra objects (not in the paper), each object on its own and never
    pooled with the paper's six nor with each other: ours against the paper's method in our
    world, calibration, pick and place, the extra pose. Their accuracy and success rates are
    in the experiments' tables, apart from the paper's six."""
    extra = sorted(
        set(object_groups(list(acc))[1]) | set(object_groups(list(reg))[1]), key=_natural
    )
    if not extra:
        return "No extra objects in this run."
    names = "; ".join(f"{o}: {describe(o, 100)}" if describe(o) else o for o in extra)
    parts = [
        f"{names}. The paper has no numbers for them; they test its assumption that the CoM "
        "lies on the rod's axis and are reported apart: never pooled with the paper's six or "
        "with each other. Their accuracy and success rates are in the tables of experiments "
        "1 and 2, below the paper's six; the figures draw them in panels of their own.",
    ]
    for obj in extra:
        sel_acc = [r for r in acc if r.get("object") == obj]
        sel_reg = [r for r in reg if r.get("object") == obj]
        parts.append(f"### {obj}" + (f": {describe(obj, 100)}" if describe(obj) else ""))
        if sel_acc:
            parts += [
                "**Ours against the paper's method in our world.** "
                + method_comparison(acc, [obj]),
                "**Calibration.** " + calibration_table(acc, [obj]),
            ]
        if sel_reg:
            parts.append("**Pick and place.** " + regrasp_verdict(reg, objects=[obj]))
            parts.append(extra_pose_summary(reg, [obj], pooled=False))
    return "\n\n".join(parts)
