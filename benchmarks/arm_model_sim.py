"""A payload from an identified arm model, against the simulator's truth and the empty-run path.

For each arm (the project's UR5, example-robot-data's Panda): two planned excitation motions,
A and B (``plan_excitation`` seeds 0 and 1). The estimator is given a WRONG URDF model of
the arm: two mid links 20 % lighter than the simulated ones (UR5: links 2 and 3, upper arm
and forearm, as ``tests/test_arm_model.py`` does; Panda: links 3 and 4), the situation of a
real arm whose vendor inertials are off. Per Monte Carlo run, played in MuJoCo by the
computed-torque servo with the realistic link-side torque sensor (its own offsets, drift and
noise per log):

- an empty run of A, on which the arm is identified (``identify_arm`` with the wrong model);
- per reference payload (rod, box, off-axis weight) a loaded run of B, estimated with the
  arm model (``estimate_payload_dynamic(wrong, loaded_B, arm_model=arm)``);
- an empty run of B, estimated with the arm model: does the mass's 95 % interval hold 0,
  which verdict;
- the comparison on the same data: the empty-run path with the right model
  (``estimate_payload_dynamic(right, loaded_B, empty_B)``).

Written per arm and payload, for both paths: the errors of mass, CoM and principal moments
(about the CoM, along the true principal axes; the dominant ones, >= ``DOMINANT_KGM2``, as
relative errors; the off-axis weight has none), the share of runs whose 95 % interval holds
the truth and the rms z of mass, CoM (three components pooled) and moments (all three
pooled), their mean z (a bias the runs share), the verdicts, the median time per estimate and
the identified delay.

Measured (20 runs): the arm-model path's mass and CoM intervals hold (coverage 0.92-1.00),
its moments' do not on the UR5 (coverage 0.57-0.75, rms z 1.7-2.0, mean z 1.5-1.9: a bias
shared by the runs). The bias is mostly MuJoCo's 1 ms step: the logged torques' departure
from the continuous-time dynamics depends on the motion, so an empty run of the same motion
cancels it and an arm model from another motion cannot; at ``--sim-dt 2.5e-4`` the moments'
coverage is 0.88-0.95 (rms z 0.95-1.27) and the delay found halves (-0.56 -> -0.24 ms).

    python benchmarks/arm_model_sim.py [--runs 20] [--arms ur5,panda]
        [--out benchmarks/results/arm_model_sim.json] [--sim-dt 0.001]
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import os
import re
import time
from collections import Counter
from pathlib import Path

# one BLAS thread: on a 2-core machine shared with other jobs, OpenBLAS's two threads made
# each estimate 2.5 s instead of 0.07 s (the pinv's SVDs of the tall weighted system)
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np
import pinocchio as pin

from comgrasp_pin.errors import ComGraspError
from comgrasp_pin.planning.excitation import ExcitationSettings, plan_excitation
from comgrasp_pin.robot_io.from_motion.arm_model import identify_arm
from comgrasp_pin.robot_io.from_motion.dynamic import estimate_payload_dynamic
from comgrasp_pin.simulation import arm_worlds
from comgrasp_pin.simulation.arm_worlds import arm_robot
from comgrasp_pin.simulation.payload_motion import simulate_motion
from comgrasp_pin.simulation.payloads import reference_payloads

DOMINANT_KGM2 = 1e-3
"""Principal moments at least this large are reported as relative errors (as
``inertia_from_motion.py``: a 1 kg payload's m r^2 at r = 3 cm)."""
Z95 = 1.96
WRONG_LINKS = {"ur5": (2, 3), "panda": (3, 4)}
"""The joints whose links the estimator's URDF model makes lighter (Pinocchio's indices)."""
WRONG_SCALE = 0.8
FAST = {"n_random": 200, "n_starts": 1}
SETTINGS = {
    # the Panda's smallest joint acceleration limit is 7.5 rad/s^2 (joint 2, Franka's data
    # sheet); a UR5's wrists are allowed far more than 12 rad/s^2
    "ur5": ExcitationSettings(acceleration_limit=12.0, **FAST),
    "panda": ExcitationSettings(acceleration_limit=7.5, **FAST),
}
PATHS = ("arm_model", "empty_run")


def wrong_robot(arm: str):
    """``arm_robot(arm)`` with the links of ``WRONG_LINKS[arm]`` 20 % lighter (mass and inertia)."""
    robot = arm_robot(arm)
    for j in WRONG_LINKS[arm]:
        I = robot.model.inertias[j]
        robot.model.inertias[j] = pin.Inertia(
            WRONG_SCALE * I.mass, I.lever, WRONG_SCALE * I.inertia
        )
    robot.data = robot.model.createData()
    return robot


def principal(est, payload):
    """Estimated moments along the true principal axes, their std, the true moments."""
    true, axes = np.linalg.eigh(payload.I_com_ee)
    inertia, inertia_cov = est.inertia.inertia_com_ee, est.inertia.inertia_cov
    est_m = np.array([u @ inertia @ u for u in axes.T])
    std = np.array([np.sqrt(np.kron(u, u) @ inertia_cov @ np.kron(u, u)) for u in axes.T])
    return est_m, std, true


def payload_row(est, payload, fit_s: float) -> dict:
    """One estimate against the payload's truth."""
    m_std = np.sqrt(np.diag(est.cov))
    moments, moment_std, true = principal(est, payload)
    return {
        "mass_err_rel": est.mass / payload.mass - 1,
        "com_err_m": float(np.linalg.norm(est.com_ee - payload.p_com_ee)),
        "moment_err_rel": (moments / true - 1).tolist(),
        "moment_err_kgm2": (moments - true).tolist(),
        "z_mass": (est.mass - payload.mass) / m_std[0],
        "z_com": ((est.com_ee - payload.p_com_ee) / m_std[1:]).tolist(),
        "z_moments": ((moments - true) / moment_std).tolist(),
        "verdict": est.verdict,
        "delay_s": est.joint_torques.delay_s,
        "std_arm_model_kg": est.std_parts.get("arm model", 0.0),
        "fit_s": fit_s,
    }


def timed(f, *args, **kw):
    t0 = time.perf_counter()
    out = f(*args, **kw)
    return out, time.perf_counter() - t0


def run_arm(arm: str, runs: int, settings: ExcitationSettings) -> dict:
    right, wrong = arm_robot(arm), wrong_robot(arm)
    (A, B), plan_s = timed(lambda: [plan_excitation(right, 20.0, settings=settings, seed=s)
                                    for s in (0, 1)])  # fmt: skip
    a, b = (A.t, A.q, A.qd, A.qdd), (B.t, B.q, B.qd, B.qdd)
    payloads = reference_payloads()
    rows = {p.name: {path: [] for path in PATHS} for p in payloads}
    empty_rows, identify, failures = [], [], []
    for run in range(runs):
        seed = 100 * (run + 1)  # every log its own noise and its own sensor offsets
        empty_A = simulate_motion(arm, None, *a, seed=seed, offsets_seed=seed)
        empty_B = simulate_motion(arm, None, *b, seed=seed + 1, offsets_seed=seed + 1)
        model, identify_s = timed(identify_arm, wrong, empty_A)
        identify.append({"identify_s": identify_s,
                         "explained": model.validation.get("explained_total")})  # fmt: skip
        est, fit_s = timed(estimate_payload_dynamic, wrong, empty_B, arm_model=model)
        m_std = np.sqrt(est.cov[0, 0])
        empty_rows.append({
            "mass_kg": est.mass, "mass_std_kg": m_std, "z": est.mass / m_std,
            "holds_zero": bool(abs(est.mass) <= Z95 * m_std), "verdict": est.verdict,
            "reasons": [_reason(r) for r in est.reasons],
            "delay_s": est.joint_torques.delay_s, "fit_s": fit_s,
        })  # fmt: skip
        for i, p in enumerate(payloads):
            loaded_B = simulate_motion(arm, p, *b, seed=seed + 2 + i, offsets_seed=seed + 2 + i)
            calls = {
                "arm_model": lambda: estimate_payload_dynamic(wrong, loaded_B, arm_model=model),
                "empty_run": lambda: estimate_payload_dynamic(right, loaded_B, empty_B),
            }
            for path, call in calls.items():
                try:
                    est, fit_s = timed(call)
                except ComGraspError as e:  # counted, not fatal: a Monte Carlo's outcome
                    failures.append({"run": run, "payload": p.name, "path": path,
                                     "error": f"{type(e).__name__}: {e}"})  # fmt: skip
                    continue
                rows[p.name][path].append(payload_row(est, p, fit_s))
        print(f"  {arm} run {run + 1}/{runs}", flush=True)
    return {
        "plan_s": plan_s,
        "condition_number": {"A": A.condition_number, "B": B.condition_number},
        "wrong_links": list(WRONG_LINKS[arm]),
        "identify_s_median": float(np.median([r["identify_s"] for r in identify])),
        "identify_explained_median": float(np.median([r["explained"] for r in identify])),
        "payloads": {
            name: {path: _summary(name, r) for path, r in by_path.items()}
            for name, by_path in rows.items()
        },  # fmt: skip
        "empty_B_with_arm_model": _empty_summary(empty_rows),
        "failures": failures,
    }


def _reason(text: str) -> str:
    """A verdict's reason without its numbers, to be counted."""
    return re.sub(r"-?\d+(\.\d+)?", "#", text.split(":")[0].split(" (")[0])


def _rms(x) -> float:
    return float(np.sqrt(np.mean(np.square(x))))


def _summary(name: str, runs: list[dict]) -> dict:
    if not runs:
        return {"runs": 0}
    true = np.linalg.eigvalsh(next(p for p in reference_payloads() if p.name == name).I_com_ee)
    dominant = true >= DOMINANT_KGM2
    mass = np.array([r["mass_err_rel"] for r in runs])
    com = np.array([r["com_err_m"] for r in runs])
    mom = np.array([r["moment_err_rel"] for r in runs])[:, dominant]
    mom_abs = np.array([r["moment_err_kgm2"] for r in runs])
    z_mom = np.array([r["z_moments"] for r in runs])
    z = {
        "mass": np.array([r["z_mass"] for r in runs]),
        "com": np.array([r["z_com"] for r in runs]).ravel(),
        "moments": z_mom.ravel(),  # all three
    }
    delays = [r["delay_s"] for r in runs if r["delay_s"] is not None]
    return {
        "runs": len(runs),
        "true_moments_kgm2": true.tolist(),
        "dominant": dominant.tolist(),
        "mass_err_rel_rms": _rms(mass),
        "mass_err_rel_max": float(np.max(np.abs(mass))),
        "com_err_mm_rms": 1e3 * _rms(com),
        "com_err_mm_max": 1e3 * float(np.max(com)),
        "dominant_moment_err_rel_rms": _rms(mom) if mom.size else None,
        "dominant_moment_err_rel_max": float(np.max(np.abs(mom))) if mom.size else None,
        "moment_err_kgm2_rms": np.sqrt(np.mean(mom_abs**2, axis=0)).tolist(),
        "coverage95": {k: float(np.mean(np.abs(v) < Z95)) for k, v in z.items()},
        "rms_z": {k: _rms(v) for k, v in z.items()},
        "mean_z": {k: float(np.mean(v)) for k, v in z.items()},  # a bias shared by the runs
        "mass_err_rel_mean": float(np.mean(mass)),
        "coverage95_per_moment": np.mean(np.abs(z_mom) < Z95, axis=0).tolist(),
        "rms_z_per_moment": np.sqrt(np.mean(z_mom**2, axis=0)).tolist(),
        "mean_z_per_moment": np.mean(z_mom, axis=0).tolist(),
        "verdicts": dict(Counter(r["verdict"] for r in runs)),
        "std_arm_model_kg_median": float(np.median([r["std_arm_model_kg"] for r in runs])),
        "fit_s_median": float(np.median([r["fit_s"] for r in runs])),
        "delay_ms_median": 1e3 * float(np.median(delays)) if delays else None,
    }


def _empty_summary(runs: list[dict]) -> dict:
    return {
        "runs": len(runs),
        "holds_zero": float(np.mean([r["holds_zero"] for r in runs])),
        "rms_z": _rms([r["z"] for r in runs]),
        "mass_g_rms": 1e3 * _rms([r["mass_kg"] for r in runs]),
        "mass_g_max_abs": 1e3 * float(np.max(np.abs([r["mass_kg"] for r in runs]))),
        "mass_std_g_median": 1e3 * float(np.median([r["mass_std_kg"] for r in runs])),
        "verdicts": dict(Counter(r["verdict"] for r in runs)),
        "reasons": dict(Counter(x for r in runs for x in r["reasons"])),
        "delay_ms_median": 1e3 * float(np.median([r["delay_s"] for r in runs])),
        "fit_s_median": float(np.median([r["fit_s"] for r in runs])),
    }


def _pc(x) -> str:
    return "-" if x is None else f"{100 * x:.1f}"


def print_table(result: dict) -> None:
    head = (f"{'arm':6}{'payload':16}{'path':10}{'mass%rms':>9}{'max':>7}{'CoMmm':>7}{'max':>6}"
            f"{'mom%rms':>8}{'max':>6}  cov95 m/c/I     rms z m/c/I     {'ident':>5}"
            f"{'ms':>6}{'delay':>6}")  # fmt: skip
    print(head)
    for arm, res in result["arms"].items():
        for name, by_path in res["payloads"].items():
            for path, s in by_path.items():
                if not s["runs"]:
                    print(f"{arm:6}{name:16}{path:10} (every run failed)")
                    continue
                c, z = s["coverage95"], s["rms_z"]
                delay = s["delay_ms_median"]
                print(f"{arm:6}{name:16}{path:10}{100 * s['mass_err_rel_rms']:9.2f}"
                      f"{100 * s['mass_err_rel_max']:7.2f}{s['com_err_mm_rms']:7.2f}"
                      f"{s['com_err_mm_max']:6.1f}{_pc(s['dominant_moment_err_rel_rms']):>8}"
                      f"{_pc(s['dominant_moment_err_rel_max']):>6}"
                      f"  {c['mass']:.2f}/{c['com']:.2f}/{c['moments']:.2f}"
                      f"  {z['mass']:4.2f}/{z['com']:4.2f}/{z['moments']:4.2f}"
                      f"{s['verdicts'].get('identified', 0):>6}/{s['runs']}"
                      f"{1e3 * s['fit_s_median']:5.0f}"
                      f"{'' if delay is None else f'{delay:6.2f}'}")  # fmt: skip
        e = res["empty_B_with_arm_model"]
        print(f"{arm:6}empty B + arm model: holds 0 in {100 * e['holds_zero']:.0f} % "
              f"(rms z {e['rms_z']:.2f}, mass rms {e['mass_g_rms']:.1f} g, max "
              f"{e['mass_g_max_abs']:.1f} g, std {e['mass_std_g_median']:.1f} g), verdicts "
              f"{e['verdicts']}, reasons {e['reasons']}, delay {e['delay_ms_median']:.2f} ms")  # fmt: skip
        if res["failures"]:
            print(f"{arm:6}failures: {res['failures']}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=20)
    ap.add_argument("--arms", default="ur5,panda")
    ap.add_argument("--out", default="benchmarks/results/arm_model_sim.json")
    ap.add_argument("--sim-dt", type=float, default=None,
                    help="MuJoCo's time step (s), a diagnostic: default the simulator's own "
                         "(arm_worlds.SIM_DT); a finer step makes the logged torques closer "
                         "to the continuous-time dynamics")  # fmt: skip
    args = ap.parse_args()
    if args.sim_dt is not None:
        arm_worlds.SIM_DT = args.sim_dt  # read when each arm's world is compiled
    t0 = time.perf_counter()
    result = {"runs": args.runs, "sensor": "realistic preset (link-side)",
              "wrong_scale": WRONG_SCALE, "dominant_kgm2": DOMINANT_KGM2,
              "openblas_threads": os.environ["OPENBLAS_NUM_THREADS"],
              "sim_dt_s": arm_worlds.SIM_DT, "arms": {}}  # fmt: skip
    for arm in args.arms.split(","):
        result["arms"][arm] = run_arm(arm, args.runs, SETTINGS[arm])
        result["arms"][arm]["settings"] = dataclasses.asdict(SETTINGS[arm])
    result["wall_s"] = time.perf_counter() - t0
    print_table(result)
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    Path(args.out).write_text(json.dumps(result, indent=1) + "\n")
    print(f"wrote {args.out} ({result['wall_s']:.0f} s)")


if __name__ == "__main__":
    main()
