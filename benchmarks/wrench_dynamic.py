"""The payload from a motion: joint torques, the wrist sensor's wrench, and both, on the same runs.

On the project's UR5 one planned excitation motion (``plan_excitation``, 20 s) is played in
MuJoCo per seed: once with the empty arm and once per payload (0.6-2 kg), each run logging the
joint torques (``sensor_preset("realistic").torque``: link side, offsets, drift, noise) and the
wrist sensor at ``ft_sensor`` (``wrench_preset``: "ft300s", the realistic preset's, and
"ur_eseries", the coarse built-in class). Per run three estimates, each with the empty run of
the same seed:

- joint torques: ``estimate_payload_dynamic(robot, joint_log, empty_joint_log)``;
- wrench: ``estimate_wrench_dynamic(robot, wrench_log, empty_log=empty_wrench_log,
  combine_joint_torques=False)`` (the tool's parameters fitted from the empty run);
- combined: the same with the joint torques (the empty run's efforts for the arm).

Written: the errors of the mass, the CoM and the principal moments (about the CoM, along the
true principal axes; relative for moments of at least ``DOMINANT_KGM2``, absolute for all)
against the simulator's truth, and the share of runs whose 95 % interval holds the truth
(mass, CoM coordinates, moments) with the rms z-scores, one table per wrench class.

    python benchmarks/wrench_dynamic.py [--seeds 8] [--wrench ft300s,ur_eseries]
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

from comgrasp_pin.config import sensor_preset, wrench_preset
from comgrasp_pin.planning.excitation import ExcitationSettings, plan_excitation
from comgrasp_pin.robot_io.from_motion.dynamic import estimate_payload_dynamic
from comgrasp_pin.robot_io.from_motion.wrench_dynamic import estimate_wrench_dynamic
from comgrasp_pin.simulation.arm_worlds import arm_robot
from comgrasp_pin.simulation.payload_motion import simulate_motion
from comgrasp_pin.simulation.payloads import Payload, Solid, box, off_axis_weight, rod

SETTINGS = ExcitationSettings(periods=4, velocity_scale=0.8, acceleration_limit=12.0)
"""inertia_from_motion.py's UR5 motion."""
METHODS = ("joint torques", "wrench", "combined")
DOMINANT_KGM2 = 1e-3
"""Principal moments at least this large are compared relatively (inertia_from_motion.py's
rule: a rod's moment about its own axis, 2e-5 kg m^2, is not); all are compared absolutely."""


def payloads() -> tuple[Payload, ...]:
    """0.6-2 kg: the motion tests' three and a 2 kg box hanging 7 cm below the jaws."""
    heavy = Payload.from_parts(
        "box_2kg", (Solid("box", (0.12, 0.10, 0.16), 2.0, (0.02, -0.01, 0.07)),)
    )
    return rod(), off_axis_weight(), box(), heavy


def errors(est, p: Payload) -> dict:
    """Errors and z-scores of the mass, the CoM and the moments along the true axes."""
    true, axes = np.linalg.eigh(p.I_com_ee)
    inertia, inertia_cov = est.inertia.inertia_com_ee, est.inertia.inertia_cov
    moments = np.array([u @ inertia @ u for u in axes.T])
    m_std = np.array([np.sqrt(np.kron(u, u) @ inertia_cov @ np.kron(u, u)) for u in axes.T])
    std = np.sqrt(np.diag(est.cov))
    return {
        "mass_err_rel": float(est.mass / p.mass - 1),
        "com_err_m": float(np.linalg.norm(est.com_ee - p.p_com_ee)),
        "moment_err_rel": (moments / true - 1)[true >= DOMINANT_KGM2].tolist(),
        "moment_err_kgm2": (moments - true).tolist(),
        "z_mass": float((est.mass - p.mass) / std[0]),
        "z_com": ((est.com_ee - p.p_com_ee) / std[1:]).tolist(),
        "z_moments": ((moments - true) / m_std).tolist(),
        "q_mass": float(est.t95[0]),
        "q_com": est.t95[1:].tolist(),
        "q_moments": [est.inertia.t95] * 3,
        "verdict": est.verdict,
    }


def run_seed(robot, motion, seed: int, wrench_name: str) -> list[dict]:
    torque = sensor_preset("realistic").torque
    wrench = wrench_preset(wrench_name)
    args = (motion.t, motion.q, motion.qd, motion.qdd)
    empty_j, empty_w = simulate_motion("ur5", None, *args, sensor=torque, seed=1000 + seed,
                                       offsets_seed=seed, wrench=wrench)  # fmt: skip
    rows = []
    for p in payloads():
        log_j, log_w = simulate_motion("ur5", p, *args, sensor=torque, seed=seed,
                                       offsets_seed=seed, wrench=wrench)  # fmt: skip
        fits = {}
        t0 = time.perf_counter()
        fits["joint torques"] = estimate_payload_dynamic(robot, log_j, empty_j)
        t1 = time.perf_counter()
        fits["wrench"] = estimate_wrench_dynamic(robot, log_w, empty_log=empty_w,
                                                 combine_joint_torques=False)  # fmt: skip
        t2 = time.perf_counter()
        fits["combined"] = estimate_wrench_dynamic(robot, log_w, empty_log=empty_w)
        t3 = time.perf_counter()
        row = {"payload": p.name, "seed": seed, "fit_s": [t1 - t0, t2 - t1, t3 - t2]}
        row.update({m: errors(fits[m], p) for m in METHODS})
        row["combined_shares_mass"] = fits["combined"].sources["wrench"]["mass_kg"]
        row["combined_agreement_chi2"] = fits["combined"].wrench.agreement["chi2"]
        row["combined_joint_source"] = fits["combined"].joint_torques.arm_model
        rows.append(row)
        print(p.name, seed, {m: (round(row[m]["mass_err_rel"] * 1e3, 2),
                                 round(row[m]["com_err_m"] * 1e3, 2)) for m in METHODS},
              flush=True)  # fmt: skip
    return rows


def summary(rows: list[dict]) -> dict:
    """Per payload and over all, per method: rms errors and the 95 % coverage."""
    out = {}
    for name in [*sorted({r["payload"] for r in rows}), "all"]:
        sel = [r for r in rows if name in ("all", r["payload"])]
        out[name] = {}
        for m in METHODS:
            e = [r[m] for r in sel]
            z_com = np.array([x["z_com"] for x in e])
            z_mom = np.array([x["z_moments"] for x in e])
            mom = np.concatenate([x["moment_err_rel"] for x in e])
            mom_abs = np.array([x["moment_err_kgm2"] for x in e])
            out[name][m] = {
                "runs": len(e),
                "mass_err_rel_rms": float(np.sqrt(np.mean([x["mass_err_rel"] ** 2 for x in e]))),
                "com_err_mm_rms": float(1e3 * np.sqrt(np.mean([x["com_err_m"] ** 2 for x in e]))),
                "moment_err_rel_rms": float(np.sqrt(np.mean(mom**2))) if mom.size else None,
                "moment_err_kgm2_rms": float(np.sqrt(np.mean(mom_abs**2))),
                "coverage95_mass": float(np.mean([abs(x["z_mass"]) < x["q_mass"] for x in e])),
                "coverage95_com": float(np.mean(np.abs(z_com) < [x["q_com"] for x in e])),
                "coverage95_moments": float(np.mean(np.abs(z_mom) < [x["q_moments"] for x in e])),
                "rms_z_mass": float(np.sqrt(np.mean([x["z_mass"] ** 2 for x in e]))),
                "rms_z_com": float(np.sqrt(np.mean(z_com**2))),
                "identified": float(np.mean([x["verdict"] == "identified" for x in e])),
            }
    return out


def _percent(x: float | None) -> str:
    return "-" if x is None else f"{100 * x:.1f}"


def table(result: dict) -> str:
    lines = []
    for wrench_name, block in result["wrench_classes"].items():
        lines += [
            f"\nwrench class {wrench_name} (torque sensor: realistic), {result['seeds']} seeds",
            "| payload | method | mass err rms % | CoM err rms mm | moments err rms % | "
            "moments err rms 1e-6 kg m^2 | cov95 mass | cov95 CoM | cov95 moments | rms z mass "
            "| rms z CoM | identified |",
            "|---|---|---|---|---|---|---|---|---|---|---|---|",
        ]
        for name, per in block["summary"].items():
            for m, s in per.items():
                lines.append(
                    f"| {name} | {m} | {100 * s['mass_err_rel_rms']:.3f} | "
                    f"{s['com_err_mm_rms']:.2f} | {_percent(s['moment_err_rel_rms'])} | "
                    f"{1e6 * s['moment_err_kgm2_rms']:.1f} | {100 * s['coverage95_mass']:.0f} | "
                    f"{100 * s['coverage95_com']:.0f} | {100 * s['coverage95_moments']:.0f} | "
                    f"{s['rms_z_mass']:.2f} | {s['rms_z_com']:.2f} | "
                    f"{100 * s['identified']:.0f} |"
                )
    return "\n".join(lines)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=8)
    ap.add_argument("--wrench", default="ft300s,ur_eseries")
    ap.add_argument("--out", default="benchmarks/results/wrench_dynamic.json")
    ap.add_argument("--table", action="store_true", help="only summarise --out's runs again")
    args = ap.parse_args()
    if args.table:
        result = json.loads(Path(args.out).read_text())
        for block in result["wrench_classes"].values():
            block["summary"] = summary(block["runs"])
        Path(args.out).write_text(json.dumps(result, indent=1) + "\n")
        print(table(result))
        return
    robot = arm_robot("ur5")
    t0 = time.perf_counter()
    motion = plan_excitation(robot, 20.0, settings=SETTINGS, seed=0)
    result = {"arm": "ur5", "seeds": args.seeds, "plan_s": time.perf_counter() - t0,
              "motion_condition_number": motion.condition_number,
              "payloads": {p.name: {"mass_kg": p.mass, "com_ee_m": p.p_com_ee.tolist()}
                           for p in payloads()},
              "wrench_classes": {}}  # fmt: skip
    for wrench_name in args.wrench.split(","):
        rows = [r for seed in range(args.seeds) for r in run_seed(robot, motion, seed, wrench_name)]
        result["wrench_classes"][wrench_name] = {"summary": summary(rows), "runs": rows}
        Path(args.out).parent.mkdir(parents=True, exist_ok=True)
        Path(args.out).write_text(json.dumps(result, indent=1) + "\n")
    print(table(result))
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
