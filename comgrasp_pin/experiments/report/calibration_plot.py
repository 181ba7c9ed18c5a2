"""The calibration figure: z against N(0, 1), coverage and rms z per tilt bin."""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from comgrasp_pin.experiments import stats
from comgrasp_pin.experiments.report import common
from comgrasp_pin.experiments.report.calibration import calibration_table, calibration_z
from comgrasp_pin.experiments.report.common import (
    abs_tilts,
    bin_label,
    load_pyplot,
    object_groups,
    objects_in,
    recorded,
    rows_of,
    without_errors,
)

Z_SPAN = 5.0  # the histogram's z axis: -5 to 5, beyond in the end bins
Z_BIN = 0.5  # the histogram's bin width in z


def _calibration_row(axes, rows, objects, edges, colours, markers, extra: bool):
    """One row of the calibration figure: histogram of z, coverage per bin, rms z per bin."""
    ax_h, ax_c, ax_r = axes
    positions = np.arange(len(edges))  # the bins and "all"
    labels = [bin_label(lo, hi) for lo, hi in zip(edges[:-1], edges[1:])] + ["all"]
    n_tick = [[] for _ in positions]
    groups = [("paper's six", objects)] if not extra else [(o, [o]) for o in objects]
    total = 0
    for g, (name, objs) in enumerate(groups):
        sel = rows_of(rows, objs)
        z, theta = calibration_z(sel), abs_tilts(sel)
        good = np.isfinite(z)
        z, theta = z[good], theta[good]
        total += len(z)
        colour, marker = colours[g % len(colours)], markers[g % len(markers)]
        _z_histogram(ax_h, z, name, colour, extra)
        per_bin = stats.binned_calibration(theta, z, edges) + [(0, 0, stats.calibration(z))]
        dodge = 0.0 if not extra else (g - 0.5 * (len(groups) - 1)) * 0.25
        _coverage_points(ax_c, positions + dodge, per_bin, name, colour, marker, extra)
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
    _finish_histogram(ax_h, total / max(1, len(groups)))
    _finish_coverage(ax_c)
    _finish_rms(ax_r)
    ticks = [f"{lab}\nn={'/'.join(ns)}" for lab, ns in zip(labels, n_tick)]
    for ax in (ax_c, ax_r):
        _tilt_bin_axis(ax, positions, ticks, objects if extra else None)
    for ax in axes:
        ax.grid(alpha=0.3, lw=0.6)
        ax.tick_params(labelsize=8)


def _z_histogram(ax, z: np.ndarray, name: str, colour: str, extra: bool) -> None:
    """One group's z as a histogram, |z| beyond Z_SPAN in the end bins (said in its label);
    filled for the pooled paper objects, a step line for each extra object."""
    span = Z_SPAN
    clipped = np.clip(z, -span + 1e-9, span - 1e-9)
    out_lo, out_hi = int(np.sum(z <= -span)), int(np.sum(z >= span))
    label = f"{name}, n = {len(z)}"
    if out_lo or out_hi:
        label += f"\n({out_lo} below −{span:g}, {out_hi} above +{span:g}: in the end bins)"
    ax.hist(
        clipped,
        bins=np.arange(-span, span + 1e-9, Z_BIN),
        histtype="stepfilled" if not extra else "step",
        color=colour,
        alpha=0.55 if not extra else 1.0,
        lw=1.5,
        label=label,
    )


def _coverage_points(ax, xs, per_bin: list, name: str, colour: str, marker: str, extra: bool):
    """One group's share of grasps inside ±1.96σ and ±1σ per tilt bin (``per_bin``: the
    bins' and "all"'s (lo, hi, Calibration) at ``xs``), with their 95 % Wilson intervals."""
    for level, (attr, mk, filled) in enumerate(
        (("inside95", marker, True), ("inside68", "o" if not extra else marker, False))
    ):
        x_drawn, ps, lo_err, hi_err = [], [], [], []
        for x, (_, _, c) in zip(xs, per_bin):
            if not c.n:
                continue
            k = getattr(c, attr)
            lo, hi = stats.wilson_interval(k, c.n)
            x_drawn.append(x + (0.0 if level == 0 else 0.12))
            ps.append(100 * k / c.n)
            lo_err.append(max(0.0, 100 * k / c.n - 100 * lo))
            hi_err.append(max(0.0, 100 * hi - 100 * k / c.n))
        ax.errorbar(
            x_drawn,
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


def _finish_histogram(ax, n_ref: float) -> None:
    """The N(0, 1) curve for ``n_ref`` grasps a group, the axes' labels and legend."""
    grid = np.linspace(-Z_SPAN, Z_SPAN, 400)
    ax.plot(
        grid,
        n_ref * Z_BIN * np.exp(-0.5 * grid**2) / math.sqrt(2 * math.pi),
        "k--",
        lw=1.3,
        label=f"N(0, 1) for n = {n_ref:.0f}",
    )
    ax.set_xlim(-Z_SPAN, Z_SPAN)
    ax.set_xlabel("z = (pos_esti − pos_real) / pos_std", fontsize=9)
    ax.set_ylabel("grasps per 0.5 of z", fontsize=9)
    ax.legend(fontsize=7, loc="upper left")
    ax.set_ylim(0, 1.35 * ax.get_ylim()[1])  # room for the legend
    ax.set_title("distribution of z (|z| > 5 in the end bins)", fontsize=9, loc="left")


def _finish_coverage(ax) -> None:
    """The coverage targets and N(0, 1)'s 68.3 %, the axes' labels."""
    ax.axhspan(
        100 * common.TARGET_COV95_OVERALL[0],
        100 * common.TARGET_COV95_OVERALL[1],
        color="#cfe8cf",
        zorder=0,
        label="95 % target, overall (93–97 %)",
    )
    ax.axhline(
        100 * common.TARGET_COV95_BIN,
        color="0.35",
        ls="--",
        lw=1,
        label="95 % target, every bin (≥ 90 %)",
    )
    ax.axhline(
        100 * common.N01_COV68, color="0.35", ls=":", lw=1, label="N(0, 1) inside ±1σ: 68.3 %"
    )
    ax.set_ylim(0, 103)
    ax.set_ylabel("grasps inside the interval (%)", fontsize=9)
    ax.set_title("coverage per tilt bin (95 % Wilson intervals)", fontsize=9, loc="left")


def _finish_rms(ax) -> None:
    """The rms z target band and the y axis: linear, or log with plain numbers where a
    heavy tail takes rms z above 3."""
    ax.axhspan(
        common.TARGET_RMS_Z[0],
        common.TARGET_RMS_Z[1],
        color="#cfe8cf",
        zorder=0,
        label="target 0.9–1.1",
    )
    ax.axhline(1.0, color="0.35", ls=":", lw=1)
    drawn = [v for line in ax.get_lines() for v in np.asarray(line.get_ydata(), float)]
    top = max([1.2] + [v for v in drawn if np.isfinite(v)])
    if top > 3.0:  # heavy tails: a log axis with plain numbers
        from matplotlib.ticker import FixedLocator, FuncFormatter, NullLocator

        ax.set_yscale("log")
        bottom = min(v for v in drawn if np.isfinite(v) and v > 0)
        every = (0.01, 0.02, 0.05, 0.1, 0.2, 0.5, 1, 2, 5, 10, 20, 50, 100, 200, 500, 1000)
        ticks = [t for t in every if bottom / 2.5 <= t <= 2.5 * top]
        ax.yaxis.set_major_locator(FixedLocator(ticks))
        ax.yaxis.set_minor_locator(NullLocator())
        ax.yaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
        ax.set_ylabel("rms z (log scale)", fontsize=9)
    else:
        ax.set_ylim(0, max(1.5, 1.1 * top))
        ax.set_ylabel("rms z", fontsize=9)
    ax.set_title("rms z per tilt bin", fontsize=9, loc="left")


def _tilt_bin_axis(ax, positions: np.ndarray, ticks: list, extra_objects) -> None:
    """The x axis of tilt bins (and "all", set apart) with each bin's counts in ``ticks``;
    the extra objects' names (``extra_objects``, or None) in the label; the legend below."""
    ax.set_xticks(positions, ticks, fontsize=7)
    label = "tilt in the jaws, 0–90° from level (deg)"
    ax.set_xlabel(label + (f"; n = {'/'.join(extra_objects)}" if extra_objects else ""), fontsize=9)
    ax.axvline(positions[-1] - 0.5, color="0.6", lw=0.8)
    ax.set_xlim(-0.6, positions[-1] + 0.6)
    ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.24), ncol=2, frameon=False)


def calibration_figure(rows: Sequence[dict], path: Path) -> Path:
    """z = (pos_esti − pos_real) / pos_std against N(0, 1): histogram with the N(0, 1)
    reference, coverage of the ±1σ and ±1.96σ intervals per |θ| bin with the targets, rms z
    per bin; the paper's six objects in the top row, extra objects in a row of their own."""
    plt = load_pyplot()
    ok = without_errors(rows)
    paper_objs, extra = object_groups(ok)
    groups = [
        (g, objs)
        for g, objs in (("paper", paper_objs), ("extra", extra))
        if objs and recorded(rows_of(ok, objs), "pos_std_m")
    ]
    if not groups:
        fig, ax = plt.subplots(figsize=(6, 1.6))
        ax.axis("off")
        ax.text(
            0.5,
            0.5,
            f"pos_std_m {common.NOT_RECORDED} in these rows: no calibration",
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
            _calibration_row(axes, ok, objs, stats.CALIBRATION_BINS_DEG, ["#1b4f8a"], ["s"], False)
        else:
            sub.suptitle(
                "Extra objects (not in the paper), each on its own", fontsize=11, fontweight="bold"
            )
            _calibration_row(
                axes,
                ok,
                objs,
                stats.CALIBRATION_BINS_DEG,
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
    ok = without_errors(rows)
    objects = objects_in(ok, objects)
    if not recorded(ok, "pos_std_m"):
        return (
            "`pos_std_m` (the stated standard deviation of each estimate) is "
            f"{common.NOT_RECORDED} in this run: no calibration."
        )
    calibration_figure(rows, Path(out) / "calibration.png")
    return "![calibration](calibration.png)\n\n" + calibration_table(rows, objects)


# --- experiment 2: pick and place ------------------------------------------------------------
