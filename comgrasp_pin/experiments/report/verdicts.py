"""The report's verdicts and summaries: against the paper and the project's aims."""

from __future__ import annotations

from collections import Counter
from collections.abc import Sequence

import numpy as np

from comgrasp_pin.experiments import paper
from comgrasp_pin.experiments.report.accuracy_tables import method_comparison
from comgrasp_pin.experiments.report.calibration import calibration_table
from comgrasp_pin.experiments.report.common import (
    NOT_RECORDED,
    PAPER_RANGE_DEG,
    abs_tilts,
    as_float,
    column_values,
    describe,
    internal_error_note,
    natural_key,
    object_groups,
    objects_in,
    outcomes,
    rows_of,
    without_errors,
)
from comgrasp_pin.experiments.report.regrasp import (
    TARGET_BELOW_10,
    TARGET_UP_TO_30,
    extra_pose_summary,
    success_rates,
)
from comgrasp_pin.experiments.stats import (
    binned_mean,
)

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
    objects = objects_in(rows, objects)
    rows = rows_of(rows, objects)
    ok = without_errors(rows)
    lines = [
        "| object | grasps (failed) | mean, tilt < 10° | mean, 10–30° | worst bin vs paper obj1 "
        "(≤ 30°) | above paper in every bin |",
        "|---|---|---|---|---|---|",
    ]
    for obj in objects:
        sel = [r for r in ok if r["object"] == obj]
        failed = sum(1 for r in rows if r["object"] == obj and r.get("error"))
        if not sel and not failed:
            continue
        theta = abs_tilts(sel) if sel else np.zeros(0)
        acc = 100 * column_values(sel, "accuracy") if sel else np.zeros(0)
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
    objects = objects_in(rows, objects)
    rows = rows_of(rows, objects)
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
        failed = r.get("error") or not int(as_float(r.get("success")) == 1)
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
    method, the objects in each group, the run seeds and the failures; the trials that
    ended in an internal error are named and counted in none of these."""
    note = internal_error_note([*acc, *reg])
    acc, reg = outcomes(acc), outcomes(reg)
    rows = list(acc) + list(reg)
    seeds = sorted(
        {int(as_float(r["seed"])) // 100_000 for r in rows if np.isfinite(as_float(r.get("seed")))}
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
        + (f" {note}" if note else "")
    )


def extra_objects_section(acc: Sequence[dict], reg: Sequence[dict]) -> str:
    """Markdown for the extra objects (not in the paper), each object on its own and never
    pooled with the paper's six nor with each other: ours against the paper's method in our
    world, calibration, pick and place, the extra pose. Their accuracy and success rates are
    in the experiments' tables, apart from the paper's six."""
    extra = sorted(
        set(object_groups(list(acc))[1]) | set(object_groups(list(reg))[1]), key=natural_key
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
