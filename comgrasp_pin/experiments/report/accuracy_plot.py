"""Experiment 1's figure: accuracy per tilt bin, ours beside the paper's method."""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from comgrasp_pin.experiments import paper
from comgrasp_pin.experiments.report.common import (
    C_LINE,
    C_OURS,
    LINE_LABEL,
    NOT_RECORDED,
    PAPER_RANGE_DEG,
    PUBLISHED_MARKER,
    abs_tilts,
    column_values,
    compress_tilt,
    describe,
    estimator_label,
    expand_tilt,
    load_pyplot,
    object_groups,
    recorded,
    rows_of,
    without_errors,
)
from comgrasp_pin.experiments.stats import (
    THETA_BINS_DEG,
    bin_series,
)


def accuracy_series(rows: Sequence[dict], column: str = "accuracy", edges=THETA_BINS_DEG):
    """Per-|θ|-bin mean of ``column`` (%) with its 95 % t interval (capped at 100 %), nan in
    empty bins: the curve of the accuracy figure (``stats.BinSeries``)."""
    rows = without_errors(rows)
    series = bin_series(abs_tilts(rows), 100.0 * column_values(rows, column), edges)
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
    plt = load_pyplot()
    ok = without_errors(rows)
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
    series = {o: {"ours": accuracy_series(rows_of(ok, [o]))} for o in paper_objs + extra}
    if has_line:
        for o in series:
            series[o]["line"] = accuracy_series(rows_of(ok, [o]), "accuracy_line")
    curves: dict[str, dict] = {}
    for sub, (group, objs) in zip(subfigs, groups):
        low = _lowest(group, [series[o] for o in objs])
        axes = _group_axes(sub, group, math.ceil(len(objs) / ncols), ncols)
        for k, ax in enumerate(axes.flat):
            if k >= len(objs):
                ax.set_visible(False)
                continue
            curves[objs[k]] = _object_panel(ax, objs[k], rows, series[objs[k]], low, group)
            _label_edges(ax, k, ncols, len(objs))
    _legend(fig, ok, has_line, bool(paper_objs))
    return fig, curves


def _lowest(group: str, group_series: list[dict]) -> float:
    """Where the group's shared y axis starts (%): below every bin mean of its objects'
    ``group_series`` and every paper value (a wide interval of a bin of two or three
    grasps may run off it: it is cut at the axis)."""
    candidates = [90.0]
    for curves in group_series:
        for c in curves.values():
            candidates += [v for v in c.mean if np.isfinite(v)]
    if group == "paper":
        candidates += [min(v) for v in paper.ACCURACY_PERCENT.values()]
    return max(0.0, 5.0 * math.floor((min(candidates) - 2.0) / 5.0))


def _group_axes(sub, group: str, nrows: int, ncols: int):
    """The group's panels, (nrows, ncols) sharing their axes, under its title."""
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
    return axes


def _object_panel(ax, obj: str, rows: Sequence[dict], series: dict, low: float, group: str):
    """One object's panel: its grasps, its curves (``series``: "ours" and, if recorded,
    "line"), the paper's published values for a paper object; its curves as Line2Ds."""
    sel = rows_of(without_errors(rows), [obj])  # the grasps that gave an estimate
    failed = len(rows_of(rows, [obj])) - len(sel)
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
    ax.set_xscale("function", functions=(compress_tilt, expand_tilt))
    ax.axvspan(PAPER_RANGE_DEG, 90.0, color="0.93", zorder=0, lw=0)
    _grasp_dots(ax, sel, low, "line" in series)
    curves = {"ours": _plot_curve(ax, series["ours"], C_OURS, "-", "o", True, -0.12)}
    if "line" in series:
        curves["line"] = _plot_curve(ax, series["line"], C_LINE, "--", "s", False, 0.12)
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
    return curves


def _grasp_dots(ax, sel: Sequence[dict], low: float, has_line: bool) -> None:
    """Every grasp faint, ours and (``has_line``) the paper's method's; a grasp below the
    axis' bottom ``low`` (%) as a small arrow at that edge."""
    theta = abs_tilts(sel)
    for column, colour, marker in (
        ("accuracy", C_OURS, "o"),
        ("accuracy_line", C_LINE, "s"),
    ):
        if column == "accuracy_line" and not has_line:
            continue
        y = 100.0 * column_values(sel, column)
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


def _label_edges(ax, k: int, ncols: int, n_panels: int) -> None:
    """The y label on the left column's panel ``k``, the x label on the bottom row's."""
    if k % ncols == 0:
        ax.set_ylabel("CoM accuracy (%)", fontsize=9)
    if k >= n_panels - ncols:
        ax.set_xlabel("tilt in the jaws, 0–90° from level (deg)", fontsize=8.5)
        ax.tick_params(labelbottom=True)


def _legend(fig, ok: Sequence[dict], has_line: bool, paper_objects: bool) -> None:
    """The figure's legend below its panels, with the note on what the lines are."""
    from matplotlib.lines import Line2D

    handles = [
        Line2D([], [], color=C_OURS, ls="-", marker="o", mfc=C_OURS, label=estimator_label(ok))
    ]
    handles.append(
        Line2D([], [], color=C_LINE, ls="--", marker="s", mfc="white", mew=1.3, label=LINE_LABEL)
        if has_line
        else Line2D([], [], ls="none", label=f"paper's method in our world: {NOT_RECORDED}")
    )
    if paper_objects:
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
        "Lines: mean per tilt bin with its 95 % t interval (a gap where a bin has no grasp); "
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


def accuracy_figure(rows: Sequence[dict], path: Path) -> Path:
    """Accuracy (%) against |θ| (deg), one panel per object (extra objects in panels of
    their own): ours and the paper's method in our world, bin means with 95 % t intervals,
    every grasp faint, and the paper's published obj1 and obj6 values as markers."""
    plt = load_pyplot()
    fig, _ = _accuracy_plot(rows)
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return Path(path)
