"""The static wrench path on the simulated UR5: mass, CoM and the 95 % intervals over many draws.

Per draw: a random box of 0.5-2 kg held by the jaws (its CoM a few cm off the ee axis and
below the jaws), four poses from ``plan_measurement_poses(robot, k=4, seed=draw)`` (what
``comgrasp plan-poses`` runs), a trajectory visiting them (``motion.trajectory.Quintic`` at
the config's holding limits, ``HOLD_S`` still at each) played in MuJoCo twice, as a user
would run it: once with nothing held (the tool's calibration) and once holding the box. Each
session has its own noise and its own wrist-sensor offset and drift (a sensor re-zeroed or
drifted between sessions: independent seeds). Estimates, as ``comgrasp estimate --wrench``
makes them (still windows found in the log):

- ``calibrated_tool``: the empty session with ``subtract_tool=False`` (``--keep-tool``), its
  ``theta_sensor`` and covariance given as ``tool=`` to the loaded session (``--tool``); both
  with the sensor's data-sheet drift (``drift_std``, ``drift_rate_std`` of the preset's
  ``WrenchSensorConfig``) in the windows' covariance;
- ``calibrated_tool_no_drift``: the same without the drift (each window's own spread, the
  residuals' excess scaling the covariance): the static path as the CLI runs it;
- ``urdf_tool``: the loaded session with the URDF's tool subtracted (the default), drift given;
- ``joint_torques``: the joint-torque static path on the same sessions
  (``estimate_from_log``, the empty windows as before and the loaded ones as after, the two
  logs joined end to end, the torque sensor's data-sheet drift given).

Presets: ``realistic`` (``sensor_preset("realistic")``: the FT 300-S class wrist sensor with
its per-episode offset, random-walk and rate drift; link-side torques with offsets and
drift; the gripper 3 % heavier than its URDF with its CoM 2 mm off) and ``ideal``. The bare
arm world (``arm_worlds``) does not apply ``SensorConfig.gripper_mass_error``: here the
gripper's excess is a small body welded to the gripper in both sessions, exact for a static
wrench (its first moment is the misstated gripper's minus the URDF's).

Truth: the simulator's payload definition (``Payload``). Written: per preset and handling,
the mass error (% of the truth), the CoM error (mm, norm and per ee axis), the share of
draws whose 95 % interval (1.96 std) holds the truth, the rms z-scores, the verdicts.

The wrench path refuses poses that turn the sensor too little (``check_orientations``): such
a draw is recorded as ``refused``. ``--plan-survey N`` counts them over N plans without
simulating (``plan_survey`` in the JSON).

    python benchmarks/wrench_static.py [--draws 100] [--first 0] [--quick]
    python benchmarks/wrench_static.py --plan-survey 500
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import time
import xml.etree.ElementTree as ET
from dataclasses import asdict
from pathlib import Path

import numpy as np

from comgrasp_pin.config import MotionConfig, sensor_preset
from comgrasp_pin.errors import UnobservableError
from comgrasp_pin.estimation.wrench import check_orientations
from comgrasp_pin.estimation.wrench_com import T_sensor_ee, tool_beyond
from comgrasp_pin.motion.trajectory import Quintic, min_duration
from comgrasp_pin.planning.measurement_poses import plan_measurement_poses
from comgrasp_pin.robot_io.at_rest.joint_torques import estimate_from_log
from comgrasp_pin.robot_io.at_rest.windows import MAX_SPEED, MIN_STATIC_S, find_static_windows
from comgrasp_pin.robot_io.at_rest.wrench_static import estimate_wrench_static
from comgrasp_pin.robot_io.log_files.log_types import JointLog
from comgrasp_pin.simulation.arm_worlds import SENSOR_FRAME, arm_robot, arm_urdf
from comgrasp_pin.simulation.payload_motion import MotionSimConfig, simulate_motion
from comgrasp_pin.simulation.payloads import Payload, Solid

HOLD_S = 2.5
"""Seconds still at each pose (the first and last are ``MotionSimConfig.rest_s``)."""
TRAJ_DT = 0.01
"""Sampling of the desired trajectory (s); the servo interpolates it (cubic Hermite)."""
PRESETS = ("realistic", "ideal")
HANDLINGS = ("calibrated_tool", "calibrated_tool_no_drift", "urdf_tool", "joint_torques")
TARGETS = {"mass_err_pct_max": 1.0, "com_err_mm_max": 2.0, "coverage95": (0.90, 0.97)}
GRIPPER_LINK = "gripper_base"


def random_payload(rng: np.random.Generator) -> Payload:
    """A box of 0.5-2 kg, sides 5-15 cm, its centre 0-3 cm off the ee axis (x, y) and 2-8 cm
    beyond the jaws' centre (ee z): an object the jaws hold near its top."""
    mass = rng.uniform(0.5, 2.0)
    size = tuple(rng.uniform(0.05, 0.15, 3))
    centre = (*rng.uniform(-0.03, 0.03, 2), rng.uniform(0.02, 0.08))
    return Payload.from_parts("box", (Solid("box", size, mass, centre),))


def gripper_excess(robot, mass_error: float, com_error: float) -> Solid | None:
    """The misstated gripper of ``simulation.scene.misstate_gripper`` as a small ball welded
    in the ee frame: the gripper link's mass times (1 + mass_error) with its CoM moved
    ``com_error`` along (1, 1, 1)/sqrt 3, minus the URDF's (same first moment at rest)."""
    if not (mass_error or com_error):
        return None
    link = next(x for x in ET.parse(arm_urdf("ur5")).getroot().iter("link")
                if x.get("name") == GRIPPER_LINK)  # fmt: skip
    inertial = link.find("inertial")
    m = float(inertial.find("mass").get("value"))
    c = np.array([float(v) for v in inertial.find("origin").get("xyz").split()])
    moment = (1 + mass_error) * m * (c + com_error * np.ones(3) / np.sqrt(3)) - m * c
    excess = mass_error * m
    T_se = T_sensor_ee(robot, GRIPPER_LINK)  # the gripper link's frame to the ee's
    p_ee = np.linalg.solve(T_se, np.r_[moment / excess, 1.0])[:3]
    return Solid("sphere", (0.01,), excess, tuple(p_ee))


def session_trajectory(Q: np.ndarray, limits: MotionConfig):
    """(t, q, qd, qdd) from pose 0 to the last, a quintic between poses, ``HOLD_S`` still at
    each pose in between (the first and last rests are the simulation's)."""
    t_parts, q_parts = [np.zeros(1)], [Q[:1]]
    qd_parts, qdd_parts = [np.zeros((1, Q.shape[1]))], [np.zeros((1, Q.shape[1]))]
    t_end = 0.0
    for i, (a, b) in enumerate(zip(Q[:-1], Q[1:])):
        move = Quintic(a, b, min_duration(a, b, limits.v_max_holding, limits.a_max_holding))
        tt = move.times(TRAJ_DT)[1:]
        q, qd, qdd = move.sample(tt)
        hold = np.arange(1, round(HOLD_S / TRAJ_DT) + 1) * TRAJ_DT if i < len(Q) - 2 else []
        t_parts += [t_end + tt, t_end + move.duration + np.asarray(hold)]
        q_parts += [q, np.repeat(b[None], len(hold), axis=0)]
        qd_parts += [qd, np.zeros((len(hold), len(b)))]
        qdd_parts += [qdd, np.zeros((len(hold), len(b)))]
        t_end += move.duration + (HOLD_S if len(hold) else 0.0)
    return tuple(np.concatenate(p) for p in (t_parts, q_parts, qd_parts, qdd_parts))


def simulate(body: Payload | None, traj, sensors, seed: int, offsets_seed: int):
    """(JointLog, WrenchLog) of one session on the UR5 holding ``body`` (None: nothing)."""
    return simulate_motion("ur5", body, *traj, sensor=sensors.torque, seed=seed,
                           offsets_seed=offsets_seed, wrench=sensors.wrench,
                           config=MotionSimConfig(rest_s=HOLD_S))  # fmt: skip


def held_body(payload: Payload | None, excess: Solid | None) -> Payload | None:
    """What the jaws carry beyond the URDF: the payload and the gripper's excess."""
    parts = (*(payload.parts if payload is not None else ()), *((excess,) if excess else ()))
    return Payload.from_parts("held", parts) if parts else None


def join_logs(empty: JointLog, loaded: JointLog) -> tuple[JointLog, float]:
    """One JointLog: the empty session, then the loaded one; and the loaded one's shift (s)."""
    shift = float(empty.time[-1] + (empty.time[1] - empty.time[0]))
    cat = np.concatenate
    log = JointLog(cat([empty.time, loaded.time + shift]), empty.joint_names,
                   cat([empty.position, loaded.position]), cat([empty.effort, loaded.effort]),
                   "mujoco:empty+loaded", cat([empty.velocity, loaded.velocity]))  # fmt: skip
    return log, shift


def scored(mass, com_ee, cov, payload: Payload, verdict: str, extra: dict) -> dict:
    """Errors and z-scores of (mass, com_ee) against the payload's truth."""
    err = np.r_[mass - payload.mass, np.asarray(com_ee) - payload.p_com_ee]
    std = np.sqrt(np.diag(cov))
    return {"mass_err_rel": float(err[0] / payload.mass), "com_err_m": err[1:].tolist(),
            "std": std.tolist(), "z": (err / std).tolist(), "verdict": verdict,
            **extra}  # fmt: skip


PLAN_FOR = {"wrench": SENSOR_FRAME["ur5"], "joints": None}
"""``--plan-for``: the poses planned for the wrist sensor (`comgrasp plan-poses
--sensor-frame ft_sensor`) or for the joint torques (`comgrasp plan-poses`)."""


def run_draw(robot, draw: int, preset: str, limits: MotionConfig, plan_for="wrench") -> dict:
    """One draw: plan, simulate both sessions, estimate every way, score against the truth."""
    sensors = sensor_preset(preset)
    payload = random_payload(np.random.default_rng((draw, 1)))
    excess = gripper_excess(robot, sensors.gripper_mass_error, sensors.gripper_com_error)
    plan = plan_measurement_poses(robot, k=4, seed=draw, sensor_frame=PLAN_FOR[plan_for])
    traj = session_trajectory(plan.q, limits)
    empty_j, empty_w = simulate(held_body(None, excess), traj, sensors, 2 * draw + 1, draw)
    load_j, load_w = simulate(held_body(payload, excess), traj, sensors, 2 * draw + 2, draw)
    row = {"draw": draw, "preset": preset, "mass": payload.mass,
           "com_ee": payload.p_com_ee.tolist(), "q": plan.q.tolist(),
           "session_s": float(load_w.time[-1])}  # fmt: skip
    try:
        row.update(wrench_handlings(robot, empty_w, load_w, payload, excess, sensors))
    except UnobservableError as exc:  # the planned poses do not turn the sensor enough
        row["refused"] = str(exc)
    joined, shift = join_logs(empty_j, load_j)
    before = [tuple(w) for w in find_static_windows(empty_j, MAX_SPEED, MIN_STATIC_S)]
    after = [(a + shift, b + shift) for a, b in before]
    jt = estimate_from_log(robot, joined, before, after,
                           drift_std=sensors.torque.drift_std)  # fmt: skip
    row["joint_torques"] = scored(jt.mass, jt.com_ee, jt.cov, payload, "", {})
    return row


def wrench_handlings(robot, empty_w, load_w, payload, excess, sensors) -> dict:
    """The wrench path's estimates of one draw: calibrated tool (with and without the
    data sheet's drift) and the URDF's tool, scored; the tool calibrations' own errors."""
    out = {}
    data_sheet = {"drift_std": sensors.wrench.drift_std,
                  "drift_rate_std": sensors.wrench.drift_rate_std}  # fmt: skip
    truth = tool_theta(robot, excess)
    for name, noise in (("calibrated_tool", data_sheet), ("calibrated_tool_no_drift", {})):
        tool = estimate_wrench_static(robot, empty_w, subtract_tool=False, **noise)
        fit = tool.wrench.fit
        z = (fit.theta[:4] - truth) / np.sqrt(np.diag(fit.theta_cov)[:4])
        out[f"tool_{name}"] = {"mass": tool.mass, "mass_err": float(tool.mass - truth[0]),
                               "mass_std": float(np.sqrt(tool.cov[0, 0])),
                               "verdict": tool.verdict, "chi2_dof": fit.chi2_dof,
                               "scale": fit.scale, "z_theta": z.tolist(),
                               "z_theta_unscaled": (z * np.sqrt(fit.scale)).tolist()}  # fmt: skip
        calibrated = (fit.theta[:4], fit.theta_cov[:4, :4])
        out[name] = wrench_scored(robot, load_w, payload, tool=calibrated, **noise)
    out["urdf_tool"] = wrench_scored(robot, load_w, payload, **data_sheet)
    return out


def tool_theta(robot, excess: Solid | None) -> np.ndarray:
    """(4,) the simulated tool's m, m c in the sensor frame (kg, kg m): the URDF's links
    beyond the sensor and the gripper's excess."""
    tool = tool_beyond(robot, SENSOR_FRAME["ur5"])
    theta = np.r_[tool.mass, tool.mass * tool.lever]
    if excess is not None:
        T_se = T_sensor_ee(robot, SENSOR_FRAME["ur5"])
        theta += excess.mass * np.r_[1.0, (T_se @ np.r_[excess.p_centre_ee, 1.0])[:3]]
    return theta


def wrench_scored(robot, log, payload: Payload, **kw) -> dict:
    """``estimate_wrench_static(robot, log, **kw)`` scored against the payload."""
    est = estimate_wrench_static(robot, log, **kw)
    fit = est.wrench.fit
    extra = {"chi2_dof": fit.chi2_dof, "windows": est.at_rest.n_poses,
             "spread_deg": fit.spread_deg.tolist()}  # fmt: skip
    return scored(est.mass, est.com_ee, est.cov, payload, est.verdict, extra)


def plan_survey(robot, n: int, plan_for: str = "wrench") -> dict:
    """Of ``n`` plans (seeds 0..n-1) of ``plan_measurement_poses(robot, k=4)``, those whose
    gravity directions in the sensor frame the wrench path refuses (``check_orientations``),
    and the spread of the others (deg, the smaller of the two principal directions)."""
    g_world = robot.model.gravity.linear
    refused, spread = [], []
    for seed in range(n):
        Q = plan_measurement_poses(robot, k=4, seed=seed, sensor_frame=PLAN_FOR[plan_for]).q
        g = np.array([robot.frame_pose(q, SENSOR_FRAME["ur5"])[:3, :3].T @ g_world for q in Q])
        try:
            spread.append(float(check_orientations(g)[1]))
        except UnobservableError:
            refused.append(seed)
    return {"plans": n, "planned_for": plan_for, "refused": len(refused), "refused_seeds": refused,
            "spread_deg_min": min(spread), "spread_deg_median": float(np.median(spread)),
            "below_15_deg": int(np.sum(np.array(spread) < 15))}  # fmt: skip


def _stats(x: np.ndarray) -> dict:
    """max, 95th percentile and mean of |x|."""
    a = np.abs(np.asarray(x, dtype=float))
    return {"max": float(a.max()), "p95": float(np.percentile(a, 95)), "mean": float(a.mean())}


def summary(rows: list[dict], handling: str) -> dict:
    """Errors, coverage and z-scores of one preset's rows for one handling (the draws it
    has: the wrench path refuses poses that do not turn the sensor enough)."""
    e = [r[handling] for r in rows if handling in r]
    com = 1e3 * np.array([x["com_err_m"] for x in e])
    z = np.array([x["z"] for x in e])
    out = {
        "draws": len(e),
        "refused": len(rows) - len(e),
        "mass_err_pct": _stats(100 * np.array([x["mass_err_rel"] for x in e])),
        "com_err_mm_norm": _stats(np.linalg.norm(com, axis=1)),
        "com_err_mm_axis": {ax: _stats(com[:, i]) for i, ax in enumerate("xyz")},
        "coverage95": {k: float(np.mean(np.abs(z[:, i]) < 1.96))
                       for i, k in enumerate(("mass", "com_x", "com_y", "com_z"))},
        "coverage95_com_all": float(np.mean(np.abs(z[:, 1:]) < 1.96)),
        "rms_z": {k: float(np.sqrt(np.mean(z[:, i] ** 2)))
                  for i, k in enumerate(("mass", "com_x", "com_y", "com_z"))},
        "mean_z": {k: float(np.mean(z[:, i]))
                   for i, k in enumerate(("mass", "com_x", "com_y", "com_z"))},
        "verdicts": {v: sum(x["verdict"] == v for x in e) for v in sorted({x["verdict"] for x in e})},
    }  # fmt: skip
    tool = [r[f"tool_{handling}"] for r in rows if f"tool_{handling}" in r]
    if tool and "z_theta" in tool[0]:
        for key in ("z_theta", "z_theta_unscaled"):
            zt = np.array([t[key] for t in tool])
            out[f"tool_rms_{key}"] = np.sqrt(np.mean(zt**2, axis=0)).tolist()
            out[f"tool_coverage95_{key}"] = np.mean(np.abs(zt) < 1.96, axis=0).tolist()
        out["tool_scale_mean"] = float(np.mean([t["scale"] for t in tool]))
    if "chi2_dof" in e[0]:
        out["chi2_dof_median"] = float(np.median([x["chi2_dof"] for x in e]))
        out["spread_deg_min"] = float(np.min([x["spread_deg"][1] for x in e]))
    cov = out["coverage95"]
    lo, hi = TARGETS["coverage95"]
    out["meets"] = {
        "mass_within_1pct": out["mass_err_pct"]["max"] <= TARGETS["mass_err_pct_max"],
        "com_within_2mm": out["com_err_mm_norm"]["max"] <= TARGETS["com_err_mm_max"],
        "coverage_90_97": all(lo <= c <= hi for c in cov.values()),
    }
    return out


def table(result: dict) -> str:
    lines = ["| preset | handling | mass err % max/p95/mean | CoM err mm max/p95/mean | "
             "cov95 m, cx, cy, cz | rms z m, cx, cy, cz | verdicts |", "|---" * 7 + "|"]  # fmt: skip
    for preset, block in result["presets"].items():
        for h, s in block["summary"].items():
            m, c = s["mass_err_pct"], s["com_err_mm_norm"]
            cov = ", ".join(f"{100 * v:.0f}" for v in s["coverage95"].values())
            rz = ", ".join(f"{v:.2f}" for v in s["rms_z"].values())
            lines.append(f"| {preset} | {h} | {m['max']:.2f}/{m['p95']:.2f}/{m['mean']:.2f} | "
                         f"{c['max']:.2f}/{c['p95']:.2f}/{c['mean']:.2f} | {cov} | {rz} | "
                         f"{s['verdicts']}, refused {s['refused']} |")  # fmt: skip
    return "\n".join(lines)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--draws", type=int, default=100)
    ap.add_argument("--quick", action="store_true", help="10 draws per preset")
    ap.add_argument("--first", type=int, default=0, help="the first draw's number (seed)")
    ap.add_argument("--presets", default=",".join(PRESETS))
    ap.add_argument("--out", default="benchmarks/results/wrench_static.json")
    ap.add_argument("--plan-for", default="wrench", choices=tuple(PLAN_FOR),
                    help="plan the poses for the wrist sensor (plan-poses --sensor-frame) or "
                    "for the joint torques")  # fmt: skip
    ap.add_argument(
        "--plan-survey",
        type=int,
        default=0,
        metavar="N",
        help="only survey N plans' spread of gravity (no simulation), into --out",
    )
    args = ap.parse_args()
    if args.plan_survey:
        out = Path(args.out)
        result = json.loads(out.read_text()) if out.exists() else {}
        key = "plan_survey" if args.plan_for == "wrench" else "plan_survey_joints"
        result[key] = plan_survey(arm_robot("ur5"), args.plan_survey, args.plan_for)
        out.write_text(json.dumps(result, indent=1) + "\n")
        print(result[key])
        return
    draws = 10 if args.quick else args.draws
    robot, limits = arm_robot("ur5"), MotionConfig()
    result = {"arm": "ur5", "draws": draws, "first_draw": args.first,
              "planned_for": args.plan_for, "hold_s": HOLD_S, "targets": TARGETS,
              "limits": {"v_max": limits.v_max_holding, "a_max": limits.a_max_holding},
              "environment": {"python": platform.python_version(), "cpus": os.cpu_count(),
                              "quick": args.quick, "date": time.strftime("%Y-%m-%d %H:%M")},
              "presets": {}}  # fmt: skip
    for preset in args.presets.split(","):
        t0 = time.perf_counter()
        rows = []
        for draw in range(args.first, args.first + draws):
            rows.append(run_draw(robot, draw, preset, limits, args.plan_for))
            r = rows[-1]
            print(preset, draw, r.get("refused", ""),
                  {h: (round(100 * r[h]["mass_err_rel"], 3),
                       round(1e3 * float(np.linalg.norm(r[h]["com_err_m"])), 2))
                   for h in HANDLINGS if h in r}, flush=True)  # fmt: skip
        sensors = sensor_preset(preset)
        result["presets"][preset] = {
            "wall_s": time.perf_counter() - t0,
            "wrench_sensor": asdict(sensors.wrench),
            "torque_sensor": asdict(sensors.torque),
            "gripper_mass_error": sensors.gripper_mass_error,
            "gripper_com_error_m": sensors.gripper_com_error,
            "summary": {h: summary(rows, h) for h in HANDLINGS},
            "rows": rows,
        }
        Path(args.out).parent.mkdir(parents=True, exist_ok=True)
        Path(args.out).write_text(json.dumps(result, indent=1) + "\n")
    print(table(result))
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
