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
from comgrasp_pin.experiments.report.common import _abs_theta, _column, _ok, _select, paper_objects
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


def _measures(acc: Sequence[dict], reg: Sequence[dict]) -> dict[str, str]:
    objects = paper_objects()
    acc, reg = _select(acc, objects), _select(reg, objects)
    ok = _ok(acc)
    low = _abs_theta(ok) < UP_TO_DEG
    cal = calibration(calibration_z(ok))
    rates = success_rates(reg)

    def total(method: str) -> tuple[int, int]:
        return tuple(sum(rates.get((o, method), (0, 0))[i] for o in objects) for i in (0, 1))

    return {
        f"mean accuracy below {UP_TO_DEG:g}°, ours (%)": _mean_cell(_column(ok, "accuracy")[low]),
        f"mean accuracy below {UP_TO_DEG:g}°, the paper's method (%)": _mean_cell(
            _column(ok, "accuracy_line")[low]
        ),
        "worst grasp below 30°, ours (%)": (
            f"{100 * np.nanmin(_column(ok, 'accuracy')[low]):.1f}" if low.any() else "–"
        ),
        "95 % interval covers the truth (%)": _rate_cell(cal.inside95, cal.n),
        "rms z (1 when the error bars are right)": f"{cal.rms:.2f}" if cal.n else "–",
        "accuracy grasps refused or failed": f"{len(acc) - len(ok)} of {len(acc)}",
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
