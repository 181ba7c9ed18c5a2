"""The realistic sensors against the ideal ones, side by side (``comgrasp reproduce``).

One table over the paper's six objects: each measure of the headline run (realistic
sensors) beside the same measure of the ideal run (the paper's world), same seeds, same
scenes; and the perception errors each run refused with, by kind.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Sequence

import numpy as np

from comgrasp_pin.experiments.report.calibration import calibration_z
from comgrasp_pin.experiments.report.common import (
    abs_tilts,
    column_values,
    paper_objects,
    recorded,
    rows_of,
    without_errors,
)
from comgrasp_pin.experiments.report.regrasp import success_rates
from comgrasp_pin.experiments.stats import calibration, mean_ci, wilson_interval

UP_TO_DEG = 30.0
"""The paper's range of tilts in the jaws (deg from level): the accuracy measures below it."""


def _mean_cell(values: np.ndarray) -> str:
    values = values[np.isfinite(values)]
    if not len(values):
        return "–"
    ci = mean_ci(100 * values)
    interval = f" [{ci.lo:.1f}, {ci.hi:.1f}]" if np.isfinite(ci.lo) else ""
    return f"{ci.mean:.1f}{interval} (n {ci.n})"


def _rate_cell(successes: int, n: int) -> str:
    if not n:
        return "–"
    lo, hi = wilson_interval(successes, n)
    return f"{100 * successes / n:.1f} [{100 * lo:.0f}, {100 * hi:.0f}] ({successes}/{n})"


def _accuracy_measures(acc: Sequence[dict]) -> dict[str, str]:
    acc = rows_of(acc, paper_objects())
    ok = without_errors(acc)
    low = abs_tilts(ok) < UP_TO_DEG
    cal = calibration(calibration_z(ok))
    return {
        f"mean accuracy below {UP_TO_DEG:g}°, ours (%)": _mean_cell(
            column_values(ok, "accuracy")[low]
        ),
        f"mean accuracy below {UP_TO_DEG:g}°, the paper's method (%)": _mean_cell(
            column_values(ok, "accuracy_line")[low]
        ),
        f"mean accuracy below {UP_TO_DEG:g}°, wrist sensor's wrench (%)": _mean_cell(
            column_values(ok, "accuracy_wrench")[low]
            if recorded(ok, "accuracy_wrench")
            else low[:0]
        ),
        "worst grasp below 30°, ours (%)": (
            f"{100 * np.nanmin(column_values(ok, 'accuracy')[low]):.1f}" if low.any() else "–"
        ),
        "95 % interval covers the truth (%)": _rate_cell(cal.inside95, cal.n),
        "rms z (1 when the error bars are right)": f"{cal.rms:.2f}" if cal.n else "–",
        "accuracy grasps refused or failed": f"{len(acc) - len(ok)} of {len(acc)}",
    }


def _measures(acc: Sequence[dict], reg: Sequence[dict]) -> dict[str, str]:
    objects = paper_objects()
    rates = success_rates(rows_of(reg, objects))

    def total(method: str) -> tuple[int, int]:
        return tuple(sum(rates.get((o, method), (0, 0))[i] for o in objects) for i in (0, 1))

    return {
        **_accuracy_measures(acc),
        "pick-and-place, regrasp planner (%)": _rate_cell(*total("regrasp")),
        "pick-and-place, geometric-centre baseline (%)": _rate_cell(*total("baseline")),
    }


def _errors(rows: Sequence[dict]) -> Counter:
    return Counter(str(r["error"]).split(":")[0].rsplit(".", 1)[-1] for r in rows if r.get("error"))


def sensors_comparison(
    acc: Sequence[dict], reg: Sequence[dict], acc_ideal: Sequence[dict], reg_ideal: Sequence[dict],
    headline: str,
) -> str:  # fmt: skip
    """Markdown: the measures of the ``headline`` preset's run beside the ideal run's
    (the paper's six objects), then the errors each run's failed trials ended in."""
    ours, ideal = _measures(acc, reg), _measures(acc_ideal, reg_ideal)
    lines = [f"| measure | {headline} sensors | ideal sensors |", "|---|---|---|"]
    lines += [f"| {name} | {ours[name]} | {ideal[name]} |" for name in ours]
    kinds = _errors([*acc, *reg])
    ideal_kinds = _errors([*acc_ideal, *reg_ideal])
    if kinds or ideal_kinds:
        lines += ["", f"| failed trials ended in | {headline} | ideal |", "|---|---|---|"]
        for kind in sorted(set(kinds) | set(ideal_kinds)):
            lines.append(f"| {kind} | {kinds.get(kind, 0)} | {ideal_kinds.get(kind, 0)} |")
    return "\n".join(lines)


def sources_table(runs: dict[str, Sequence[dict]]) -> str:
    """Markdown: one row per sensor preset (``runs``: preset name -> its accuracy rows, the
    same grasps), the accuracy measures on the paper's objects as columns."""
    measures = {name: _accuracy_measures(rows) for name, rows in runs.items()}
    columns = list(next(iter(measures.values())))
    lines = ["| sensors | " + " | ".join(columns) + " |", "|---" * (len(columns) + 1) + "|"]
    for name, m in measures.items():
        lines.append(f"| {name} | " + " | ".join(m[c] for c in columns) + " |")
    return "\n".join(lines)


def sources_figure(runs: dict[str, Sequence[dict]], path) -> None:
    """PNG: mean accuracy below 30 deg per sensor preset (ours and the paper's method, 95 %
    t intervals), the share of grasps refused or failed written on each bar."""
    from comgrasp_pin.experiments.report.common import C_LINE, C_OURS, load_pyplot

    plt = load_pyplot()
    names = list(runs)
    selected = {name: rows_of(runs[name], paper_objects()) for name in names}
    fig, ax = plt.subplots(figsize=(8.5, 4.2), layout="constrained")
    for k, (column, colour, label) in enumerate(
        (("accuracy", C_OURS, "ours"), ("accuracy_line", C_LINE, "the paper's method"))
    ):
        stats = []
        for name in names:
            ok = without_errors(selected[name])
            values = 100 * column_values(ok, column)[abs_tilts(ok) < UP_TO_DEG]
            stats.append(mean_ci(values[np.isfinite(values)]))
        x = np.arange(len(names)) + (k - 0.5) * 0.38
        means = np.array([c.mean for c in stats])
        err = np.array([[c.mean - c.lo, c.hi - c.mean] for c in stats]).T
        ax.bar(x, means, 0.36, color=colour, label=label,
               yerr=np.nan_to_num(np.clip(err, 0, None)), capsize=3)  # fmt: skip
    for i, name in enumerate(names):
        rows = selected[name]
        failed = len(rows) - len(without_errors(rows))
        ax.text(i, 80.5, f"{failed}/{len(rows)}\nrefused", ha="center", fontsize=8)
    ax.set_xticks(np.arange(len(names)), [n.replace("ideal+", "+") for n in names],
                  rotation=25, ha="right")  # fmt: skip
    ax.set_ylim(80, 101)
    ax.set_ylabel(f"mean accuracy, tilt below {UP_TO_DEG:g}° (%)")
    ax.set_title("Each realistic error source alone on ideal sensors (paper's objects)", pad=24)
    ax.grid(axis="y", alpha=0.3)
    ax.legend(loc="lower center", bbox_to_anchor=(0.5, 1.0), ncol=2, frameon=False)
    fig.savefig(path, dpi=90)
    plt.close(fig)
