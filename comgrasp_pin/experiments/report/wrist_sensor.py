"""The accuracy experiment with the wrist force/torque sensor instead of the joint torques.

Every trial grasp reads the joint torques and the wrist sensor over the same windows, and
locates the CoM three ways from the same poses and side views (``accuracy.csv``): from the
joint torques (``accuracy``, what the robot used), from the wrench (``accuracy_wrench``) and
from both stacked (``accuracy_both``). This section sets them side by side per object below
30° of tilt, grasp by grasp, with the wrench's own calibration (its ``pos_std_wrench_m``).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from comgrasp_pin.experiments.report.common import (
    NOT_RECORDED,
    TIE_POINTS,
    abs_tilts,
    column_values,
    object_groups,
    recorded,
    rows_of,
    without_errors,
)
from comgrasp_pin.experiments.report.sensors import UP_TO_DEG
from comgrasp_pin.experiments.stats import calibration, mean_ci, paired_difference, z_scores


def _mean(values: np.ndarray) -> str:
    ci = mean_ci(100 * values)
    return f"{ci.mean:.1f}" if ci.n else "–"


def _row(name: str, rows: Sequence[dict]) -> tuple[str, str]:
    """A table row of ``rows`` (one object, or the group) below 30°, and its verdict."""
    low = abs_tilts(rows) < UP_TO_DEG
    joints, wrench = (
        column_values(rows, "accuracy")[low],
        column_values(rows, "accuracy_wrench")[low],
    )
    both = column_values(rows, "accuracy_both")[low]
    z = z_scores(*(column_values(rows, c)[low] for c in ("pos_esti_wrench_m", "pos_real_m",
                                                     "pos_std_wrench_m")))  # fmt: skip
    cal = calibration(z)
    share = column_values(rows, "wrench_share_com")[low]
    share = share[np.isfinite(share)]
    pd = paired_difference(100 * wrench, 100 * joints, tie=TIE_POINTS)
    d = pd.diff
    ci = f" ({d.lo:+.2f} to {d.hi:+.2f})" if np.isfinite(d.lo) else ""
    bound = d.hi if np.isfinite(d.hi) else d.mean  # one grasp: its own difference
    verdict = "as accurate or more" if bound >= -TIE_POINTS else "less"
    if not np.isfinite(d.mean):
        verdict = "–"
    cov = f"{100 * cal.inside95 / cal.n:.0f} ({cal.inside95}/{cal.n})" if cal.n else "–"
    cells = [
        name, str(d.n), _mean(joints), _mean(wrench), _mean(both),
        f"{d.mean:+.2f}{ci}" if np.isfinite(d.mean) else "–", cov,
        f"{cal.rms:.2f}" if cal.n else "–",
        f"{100 * np.mean(share):.0f}" if len(share) else "–", verdict,
    ]  # fmt: skip
    return "| " + " | ".join(cells) + " |", verdict


def wrist_sensor_table(rows: Sequence[dict], objects: Sequence[str] | None = None) -> str:
    """Markdown: per object below 30°, the accuracy from the joint torques, the wrench and
    both on the same grasps; the wrench minus the joint torques (paired, 95 % t interval);
    the wrench's interval's coverage and rms z; the wrench's share of the information on the
    CoM along the rod with both; and whether the wrench is at least as accurate."""
    ok = without_errors(rows)
    if not recorded(ok, "accuracy_wrench"):
        return f"The wrist sensor's estimate (`accuracy_wrench`): {NOT_RECORDED}."
    groups = [objects] if objects is not None else [g for g in object_groups(ok) if g]
    lines = [
        f"Grasps below {UP_TO_DEG:g}° of tilt. Accuracy (%) from the joint torques (what the "
        "robot used), from the wrist sensor's wrench and from both, on the same grasps; "
        "wrench − joints: the paired difference in accuracy points with its 95 % t interval "
        f"(a tie within {TIE_POINTS:g} points); coverage and rms z of the wrench's own 95 % "
        "interval; the wrench's share (%) of the information on the CoM along the rod when "
        "both are used.",
        "",
        "| object | grasps | joint torques | wrench | both | wrench − joints (points, 95 % "
        "CI) | wrench covers (%) | rms z | wrench share (%) | wrench vs joints |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    verdicts = []
    for group in groups:
        for obj in group:
            line, verdict = _row(obj, rows_of(ok, [obj]))
            lines.append(line)
            verdicts.append((obj, verdict))
        lines.append(_row(f"all of {', '.join(group)}", rows_of(ok, group))[0])
    judged = [(obj, v) for obj, v in verdicts if v != "–"]
    worse = [obj for obj, v in judged if v == "less"]
    lines += [
        "",
        f"The wrench is at least as accurate as the joint torques below {UP_TO_DEG:g}° "
        f"(the 95 % interval of the difference reaching −{TIE_POINTS:g} points or above; "
        "with one grasp, its difference) for "
        f"{len(judged) - len(worse)} of {len(judged)} objects with grasps there"
        + (f"; less accurate for {', '.join(worse)}." if worse else "."),
    ]
    return "\n".join(lines)
