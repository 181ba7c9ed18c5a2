"""Do the payload's 95 % intervals hold in every regime? Coverage and rms z, row by row.

Each row draws a regime's logs ``--draws`` times with fresh noise and runs the estimate the
user would run; against the truth it records, for the mass, the CoM and (from a motion) the
principal moments about the CoM along the true axes:

- coverage: the share of draws whose stated 95 % interval (``PayloadEstimate``'s, with its
  degrees of freedom) holds the truth, with its binomial 95 % interval (Wilson);
- rms z: the root mean square of (estimate - truth) / stated std;
- bias: the mean of z with its 95 % interval: what the pipeline (filter, differentiation,
  grid) or a model error adds the same in every draw, in units of the stated std;
- rms score: the same with each z taken through its Student t (nu degrees of freedom) to the
  normal's quantile: 1 for a calibrated interval whatever nu (a t variable's rms z is
  sqrt(nu / (nu - 2)), 1.29 at nu = 5).

Rows (``--rows``, comma-separated names; default all the synthetic ones):

- ``white_0.005``, ``white_0.05``, ``white_0.5``: efforts from Pinocchio's RNEA of the UR5 with
  the payload appended, viscous and Coulomb friction of the model's own shape (the exact
  model), white noise of that std (N m), an empty run;
- ``correlated_0.2s``: noise of 0.05 N m low-passed with a 0.2 s time constant, empty run;
- ``gains_common``, ``gains_per_joint``: motor currents whose drive gains err by 10 % (one
  error shared by all joints; independent per joint), drawn anew each draw and stated as
  ``gain_cov`` with correlation 1 or 0;
- ``urdf_model``: no empty run, the URDF's model with friction fitted;
- ``urdf_wrong_2_links``: the same, the arm's true links 2 and 3 20 % heavier than its URDF;
- ``arm_model``: the arm's own model identified from an empty run of another motion;
- ``arm_model_friction_shape``, ``urdf_model_friction_shape``: the same two with a Coulomb
  friction sharper than the model's (tanh(qd / 0.01) against tanh(qd / 0.02)): a model
  error, the same in every draw;
- ``static_joint_torques``: three poses that turn the wrist, the UR5's gravity torques
  (Pinocchio) with the payload and without, 200 samples of 0.05 N m white noise per window,
  before/after at the same poses (``estimate_from_log``): no inertia;
- ``static_wrench``: a wrist sensor (tool0) at four planned poses, the payload's and the
  URDF tool's gravity wrench, a bias, 200 samples per window of 0.1 N and 0.005 N m white
  noise, the tool known (``estimate_wrench_static``): no inertia;
- ``mujoco_ur5``, ``mujoco_panda``: the three reference payloads in turn, played in MuJoCo
  (1 ms step) with the realistic torque sensor, and an empty run; ``mujoco_ur5_0.25ms``,
  ``mujoco_panda_0.25ms``: the same at a 0.25 ms step;
- ``mujoco_ur5_wrench``, ``mujoco_ur5_both``: the same on the UR5 with the realistic wrist
  sensor (FT 300-S class): the wrench alone (the tool from the empty run), and the wrench
  stacked with the joint torques.

    python benchmarks/interval_regimes.py [--draws 40] [--rows white_0.05,urdf_model]
        [--out benchmarks/results/interval_regimes.json]
"""

from __future__ import annotations

import argparse
import json
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
import pinocchio as pin
from scipy.signal import lfilter
from scipy.stats import norm
from scipy.stats import t as student_t

from comgrasp_pin.robot import RobotModel
from comgrasp_pin.robot_io import JointLog, estimate_payload_dynamic, identify_arm
from comgrasp_pin.robot_io.from_motion.motion_system import COULOMB_SPEED

PAYLOAD = pin.Inertia(0.8, np.array([0.02, -0.01, 0.08]), np.diag([4e-3, 5e-3, 3e-3]))
RATE_HZ = 250.0
DURATION_S = 16.0
SYNTHETIC = ("white_0.005", "white_0.05", "white_0.5", "correlated_0.2s", "gains_common",
             "gains_per_joint", "urdf_model", "urdf_wrong_2_links", "arm_model",
             "urdf_model_friction_shape", "arm_model_friction_shape", "static_joint_torques",
             "static_wrench")  # fmt: skip
MUJOCO = ("mujoco_ur5", "mujoco_panda", "mujoco_ur5_0.25ms", "mujoco_panda_0.25ms",
          "mujoco_ur5_wrench", "mujoco_ur5_both")  # fmt: skip
GAIN_STD = 0.1
NOMINAL_GAINS = np.array([10.0, 10.7, 8.5, 9.0, 9.5, 10.1])  # N m / A, a UR10e's order


def fourier_motion(robot: RobotModel, seed: int, duration: float = DURATION_S):
    """A smooth motion at rest at both ends: each joint four windowed harmonics."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, duration, 1 / RATE_HZ)
    w = 2 * np.pi / (duration / 2)
    q = np.tile([0.0, -1.6, 1.6, -1.57, -1.57, 0.0], (len(t), 1))
    window = np.sin(np.pi * t / duration) ** 2
    for j in range(robot.nq):
        for h in range(1, 5):
            a, b = rng.normal(0, 0.25 / h, 2)
            q[:, j] += window * (a * np.sin(h * w * t) + b * (np.cos(h * w * t) - 1))
    qd = np.gradient(q, t, axis=0)
    return t, q, qd, np.gradient(qd, t, axis=0)


def true_model(robot: RobotModel, inertia, heavier_links=()):
    """The arm as it is: the URDF's model, links scaled, the payload appended at the ee."""
    model = pin.Model(robot.model)
    for j in heavier_links:
        Y = model.inertias[j]
        model.inertias[j] = pin.Inertia(1.2 * Y.mass, Y.lever, 1.2 * Y.inertia)
    if inertia is not None:
        frame = model.frames[robot.ee_frame_id]
        model.appendBodyToJoint(frame.parentJoint, inertia, frame.placement)
    return model


def efforts(robot, inertia, motion, rng, noise, offset, heavier_links=(), tau_c=0.0,
            coulomb_speed=COULOMB_SPEED):  # fmt: skip
    """Efforts along ``motion`` (RNEA of the true arm), friction, offsets and noise."""
    t, q, qd, qdd = motion
    model = true_model(robot, inertia, heavier_links)
    data = model.createData()
    tau = np.array([pin.rnea(model, data, a, b, c) for a, b, c in zip(q, qd, qdd)])
    tau += 0.3 * np.tanh(qd / coulomb_speed) + 0.5 * qd + offset
    e = rng.standard_normal(tau.shape)
    if tau_c > 0:  # first-order low-pass, rescaled to the same std
        a = np.exp(-1 / (RATE_HZ * tau_c))
        e = lfilter([np.sqrt(1 - a**2)], [1, -a], e, axis=0)
    return tau + noise * e


def joint_log(robot, t, q, tau, rng, gains=None) -> JointLog:
    q_read = q + 1e-5 * rng.standard_normal(q.shape)
    log = JointLog(t, tuple(robot.joint_names), q_read, tau, "synthetic")
    if gains is None:
        return log
    return replace(log, current_gains=gains)


def synthetic_draw(robot, row: str, motion, draw: int, arm_motion):
    """One draw of a synthetic row: the estimate and the true payload."""
    rng = np.random.default_rng(10_000 + draw)
    noise = float(row.split("_")[1]) if row.startswith("white") else 0.05
    tau_c = 0.2 if row == "correlated_0.2s" else 0.0
    heavier = (2, 3) if row == "urdf_wrong_2_links" else ()
    speed = 0.01 if row.endswith("friction_shape") else COULOMB_SPEED
    t, q = motion[0], motion[1]
    tau = efforts(robot, PAYLOAD, motion, rng, noise, 0.2, heavier, tau_c, speed)
    empty_run = not row.startswith(("urdf", "arm"))
    tau_e = (efforts(robot, None, motion, rng, noise, 0.25, heavier, tau_c, speed)
             if empty_run else None)  # fmt: skip
    kwargs = {}
    if row.startswith("gains"):  # the efforts are K_true I; the log converts with K_nominal
        delta = (np.full(6, rng.normal(0, GAIN_STD)) if row == "gains_common"
                 else rng.normal(0, GAIN_STD, 6))  # fmt: skip
        scale = 1.0 / (1.0 + delta)  # logged effort = K_nom I = tau / (1 + delta)
        tau, tau_e = tau * scale, tau_e * scale
        corr = 1.0 if row == "gains_common" else 0.0
        s = GAIN_STD * NOMINAL_GAINS
        kwargs["gain_cov"] = np.outer(s, s) * (corr + (1 - corr) * np.eye(6))
    gains = NOMINAL_GAINS if row.startswith("gains") else None
    log = joint_log(robot, t, q, tau, rng, gains)
    empty = None if tau_e is None else joint_log(robot, t, q, tau_e, rng, gains)
    if row.startswith("arm_model"):
        ta, qa = arm_motion[0], arm_motion[1]
        tau_a = efforts(robot, None, arm_motion, rng, 0.05, 0.25, coulomb_speed=speed)
        empty_other = joint_log(robot, ta, qa, tau_a, rng)
        kwargs["arm_model"] = identify_arm(robot, empty_other)
    return estimate_payload_dynamic(robot, log, empty, **kwargs), PAYLOAD


def static_draw(robot, row: str, draw: int):
    """One draw of a static row: still windows at planned poses, white noise."""
    from comgrasp_pin.estimation.wrench_com import tool_beyond
    from comgrasp_pin.planning.measurement_poses import plan_measurement_poses
    from comgrasp_pin.robot_io import WrenchLog, estimate_from_log, estimate_wrench_static

    rng = np.random.default_rng(20_000 + draw)
    hold = 200
    g = np.array([0.0, 0.0, -9.81])
    if row == "static_wrench":
        plan = plan_measurement_poses(robot, k=4)
        tool = tool_beyond(robot, "tool0")
        T_ee_s = np.linalg.solve(robot.frame_pose(plan.q[0], robot.ee_frame),
                                 robot.frame_pose(plan.q[0], "tool0"))  # fmt: skip
        c_s = (np.linalg.inv(T_ee_s) @ np.r_[PAYLOAD.lever, 1])[:3]
        bias, std = rng.normal(size=6), np.r_[[0.1] * 3, [0.005] * 3]
        rows, qs = [], []
        for q in plan.q:
            g_s = robot.frame_pose(q, "tool0")[:3, :3].T @ g
            w = sum(np.r_[m * g_s, np.cross(c, m * g_s)]
                    for m, c in ((PAYLOAD.mass, c_s), (tool.mass, tool.lever)))  # fmt: skip
            rows += list(w + bias + rng.normal(size=(hold, 6)) * std)
            qs += [q] * hold
        t = 0.01 * np.arange(len(qs))
        log = WrenchLog(t, tuple(robot.joint_names), np.array(qs), np.array(rows), "tool0", "b")
        known = (np.r_[tool.mass, tool.mass * np.asarray(tool.lever)], np.zeros((4, 4)))
        return estimate_wrench_static(robot, log, tool=known)
    q = np.array([[0.0, -1.6, 1.6, -1.57, -1.57, 0.0], [0.4, -1.4, 1.2, -0.6, -0.9, 1.0],
                  [-0.4, -1.8, 1.9, -2.4, -2.2, -1.2]])  # fmt: skip
    loaded = true_model(robot, PAYLOAD)
    tau = [[pin.computeGeneralizedGravity(m, m.createData(), qi) for qi in q]
           for m in (robot.model, loaded)]  # fmt: skip
    samples = [t + 0.05 * rng.standard_normal((hold, 6)) for t in tau[0] + tau[1]]
    t = np.arange(6 * hold) / 200.0
    log = JointLog(t, tuple(robot.joint_names), np.repeat(np.vstack([q, q]), hold, axis=0),
                   np.concatenate(samples), "synthetic")  # fmt: skip
    before = [(i + 0.05, i + 0.95) for i in range(3)]
    return estimate_from_log(robot, log, before=before, after=[(a + 3, b + 3) for a, b in before])


def mujoco_draw(row: str, motion, draw: int):
    """One draw of a MuJoCo row: the arm plays the motion empty and holding a rod."""
    from comgrasp_pin.config import wrench_preset
    from comgrasp_pin.robot_io import estimate_wrench_dynamic
    from comgrasp_pin.simulation.arm_worlds import arm_robot
    from comgrasp_pin.simulation.payload_motion import MotionSimConfig, simulate_motion
    from comgrasp_pin.simulation.payloads import reference_payloads

    arm = row.split("_")[1]
    config = MotionSimConfig(timestep_s=2.5e-4 if row.endswith("0.25ms") else 1e-3)
    payload = reference_payloads()[draw % 3]
    robot = arm_robot(arm)
    args = (motion.t, motion.q, motion.qd, motion.qdd)
    truth = pin.Inertia(payload.mass, np.asarray(payload.p_com_ee), payload.I_com_ee)
    if row.endswith(("wrench", "both")):
        ft = wrench_preset("ft300s")
        _, empty = simulate_motion(arm, None, *args, seed=1000 + draw, offsets_seed=draw,
                                   wrench=ft)  # fmt: skip
        _, log = simulate_motion(arm, payload, *args, seed=draw, offsets_seed=draw, wrench=ft)
        both = row.endswith("both")
        return estimate_wrench_dynamic(robot, log, empty_log=empty,
                                       combine_joint_torques=both), truth  # fmt: skip
    empty = simulate_motion(arm, None, *args, seed=1000 + draw, offsets_seed=draw, config=config)
    log = simulate_motion(arm, payload, *args, seed=draw, offsets_seed=draw, config=config)
    return estimate_payload_dynamic(robot, log, empty), truth


def scores(est, truth) -> dict:
    """z and inside-the-interval of the mass, the CoM and the principal moments."""
    std = est.std
    err = np.r_[est.mass - truth.mass, est.com_ee - truth.lever]
    half = est.interval95_halfwidth
    if est.inertia is None:  # at rest: no inertia
        m_err, m_std, m_half, m_dof = np.full(3, np.nan), np.ones(3), np.ones(3), np.inf
    else:
        true_m, axes = np.linalg.eigh(truth.inertia)
        I, C = est.inertia.inertia_com_ee, est.inertia.inertia_cov
        m_err = np.array([u @ I @ u for u in axes.T]) - true_m
        m_std = np.array([np.sqrt(np.kron(u, u) @ C @ np.kron(u, u)) for u in axes.T])
        m_half, m_dof = est.inertia.t95 * m_std, est.inertia.dof
    z = np.r_[err / std, m_err / m_std]
    dof = np.r_[est.dof, np.full(3, m_dof)]
    score = norm.ppf(np.clip(student_t.cdf(z, np.where(np.isfinite(dof), dof, 1e9)), 1e-12,
                             1 - 1e-12))  # fmt: skip
    return {
        "z": z.tolist(),
        "score": score.tolist(),
        "dof": dof.tolist(),
        "inside": np.r_[np.abs(err) <= half, np.abs(m_err) <= m_half].tolist(),
        "verdict": est.verdict,
        "inertia_verdict": None if est.inertia is None else est.inertia.verdict,
    }


def wilson(k: int, n: int) -> list[float]:
    """The binomial 95 % interval of a coverage of k in n (Wilson)."""
    z = 1.959964
    p = k / n
    centre = (p + z**2 / (2 * n)) / (1 + z**2 / n)
    half = z * np.sqrt(p * (1 - p) / n + z**2 / (4 * n**2)) / (1 + z**2 / n)
    return [float(centre - half), float(centre + half)]


def summarise(draws: list[dict]) -> dict:
    z = np.array([d["z"] for d in draws])
    score = np.array([d["score"] for d in draws])
    dof = np.array([d["dof"] for d in draws])
    inside = np.array([d["inside"] for d in draws])
    n = len(draws)
    groups = {"mass": [0], "com": [1, 2, 3], "moments": [4, 5, 6]}
    determined = np.array([d["inertia_verdict"] == "identified" for d in draws])
    out = {"draws": n, "verdicts": {v: sum(d["verdict"] == v for d in draws)
                                    for v in {d["verdict"] for d in draws}}}  # fmt: skip
    out["inertia_identified"] = int(determined.sum())
    for name, cols in groups.items():
        if np.all(np.isnan(z[:, cols])):
            continue  # no inertia at rest
        if name == "moments" and determined.any():  # where the inertia was determined
            sel = z[determined][:, cols]
            out["moments_where_identified"] = {
                "draws": int(determined.sum()),
                "coverage": float(inside[determined][:, cols].mean()),
                "rms_score": float(np.sqrt(np.mean(score[determined][:, cols] ** 2))),
                "rms_z": float(np.sqrt(np.mean(sel**2)))}  # fmt: skip
        k = int(inside[:, cols].sum())
        total = inside[:, cols].size
        out[name] = {"coverage": k / total, "coverage_ci95": wilson(k, total),
                     "rms_z": float(np.sqrt(np.mean(z[:, cols] ** 2))),
                     "rms_score": float(np.sqrt(np.mean(score[:, cols] ** 2))),
                     "bias_z": float(np.mean(z[:, cols])),
                     "bias_z_ci95": 1.96 * float(np.std(z[:, cols]) / np.sqrt(z[:, cols].size)),
                     "median_dof": float(np.median(dof[:, cols]))}  # fmt: skip
    return out


def markdown(results: dict) -> str:
    """The table of docs/uncertainty.md: one row per regime."""
    lines = ["| regime | verdicts | mass: coverage [binomial 95 %], rms z, rms score, mean z, ν "
             "| CoM: the same | moments: the same |", "|---|---|---|---|---|"]  # fmt: skip
    for row, r in results.items():
        cells = []
        for g in ("mass", "com", "moments"):
            if g not in r:
                cells.append("—")
                continue
            c = r[g]
            lo, hi = c["coverage_ci95"]
            nu = c["median_dof"]
            nu_text = "∞" if nu == np.inf else f"{nu:.0f}" if nu < 1000 else "> 1000"
            cells.append(f"{100 * c['coverage']:.0f} % [{100 * lo:.0f}–{100 * hi:.0f}], "
                         f"{c['rms_z']:.2f}, {c['rms_score']:.2f}, {c['bias_z']:+.2f}, "
                         f"{nu_text}")  # fmt: skip
        verdicts = ", ".join(f"{n} {v}" for v, n in sorted(r["verdicts"].items()))
        if "moments" in r:
            verdicts += f"; inertia identified {r['inertia_identified']}"
            w = r.get("moments_where_identified")
            if w:
                cells_w = (
                    f" (inertia identified: {100 * w['coverage']:.0f} %, {w['rms_score']:.2f})"
                )
            else:
                cells_w = ""
        else:
            cells_w = ""
        lines.append(f"| `{row}` | {verdicts} | " + " | ".join(cells) + cells_w + " |")
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--draws", type=int, default=40)
    parser.add_argument("--rows", default=",".join(SYNTHETIC))
    parser.add_argument("--out", default="benchmarks/results/interval_regimes.json")
    a = parser.parse_args()
    robot = RobotModel.ur5()
    motion = fourier_motion(robot, seed=0)
    arm_motion = fourier_motion(robot, seed=1, duration=24.0)
    results = {}
    for row in a.rows.split(","):
        t0 = time.perf_counter()
        draws = []
        mujoco_motion = None
        if row.startswith("mujoco"):
            from comgrasp_pin.planning.excitation import ExcitationSettings, plan_excitation
            from comgrasp_pin.simulation.arm_worlds import arm_robot

            settings = ExcitationSettings(n_random=200, n_starts=1)
            mujoco_motion = plan_excitation(arm_robot(row.split("_")[1]), 20.0,
                                            settings=settings, seed=0)  # fmt: skip
        for d in range(a.draws):
            if mujoco_motion is not None:
                est, truth = mujoco_draw(row, mujoco_motion, d)
            elif row.startswith("static"):
                est, truth = static_draw(robot, row, d), PAYLOAD
            else:
                est, truth = synthetic_draw(robot, row, motion, d, arm_motion)
            draws.append(scores(est, truth))
        results[row] = summarise(draws) | {"seconds": time.perf_counter() - t0}
        r = results[row]
        cells = " | ".join(f"{g} {r[g]['coverage']:.2f} z {r[g]['rms_z']:.2f} s "
                           f"{r[g]['rms_score']:.2f} b {r[g]['bias_z']:+.2f} nu "
                           f"{r[g]['median_dof']:.0f}"
                           for g in ("mass", "com", "moments") if g in r)  # fmt: skip
        print(f"{row:26s} {cells} | {r['verdicts']}", flush=True)
    Path(a.out).parent.mkdir(parents=True, exist_ok=True)
    Path(a.out).write_text(json.dumps({"draws": a.draws, "rows": results}, indent=1))
    print(markdown(results))


if __name__ == "__main__":
    main()
