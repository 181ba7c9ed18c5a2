"""Timing of the CoM estimator on the UR5: lstsq against plain lstsq, IPOPT (l2, prior, Huber), a peer.

    python benchmarks/bench_estimator.py [--quick] [--out benchmarks/results/estimator.json]

A realistic noisy case: a 0.5 kg payload with its CoM at (0.01, 0, 0.08) m in the ee frame,
Gaussian noise of 0.01 N m on every torque reading (before and after), ``torque_std`` passed
unless a key says ``no_std``. Four poses are one configuration with the wrist joints changed
(as tests/test_estimator.py's ``wrist_poses``). Times are medians over blocks of calls and
include the kinematics (the estimator's own Jacobians) unless a key says ``solve`` or
``nlpsol_call``. IPOPT solvers are built before timing (warm cache); the build time of each
problem is reported apart. The peer is mujoco-sysid's joint-body regressor on the MuJoCo world
(the same URDF) solved by NumPy least squares; it is skipped with a message when mujoco-sysid
is not installed (``pip install mujoco-sysid``: a benchmark-only tool, not a dependency).
The plain reference is what a user would write by hand in the same run: Pinocchio's
Jacobian, the (n, 4) regression of eq. 5 and ``np.linalg.lstsq`` (no checks, no covariance,
no observability decision). Targets (issue 33): ``estimate_com`` (checks, observability,
covariance included) within 2x of that plain reference at one pose, and at least 2x faster
than the peer on the same four poses. The machine is shared: the JSON keeps the load
average, and each ratio is of two figures taken in the same run.
"""

from __future__ import annotations

import argparse
import importlib.metadata
import json
import math
import os
import platform
import statistics
import time
from functools import partial
from pathlib import Path

import casadi as ca
import mujoco
import numpy as np
import pinocchio as pin

import comgrasp_pin as cg
from comgrasp_pin.estimation import ipopt as _ipopt
from comgrasp_pin.estimation.regressor import stacked_regressor

MASS, COM_EE = 0.5, np.array([0.01, 0.0, 0.08])
INERTIA_EE = np.diag([2e-3, 3e-3, 4e-3])  # about the CoM (as tests/_payload.py)
TORQUE_STD = 0.01  # N m, each reading
PRIOR_STD = 0.005  # m
HUBER_DELTA = 3.0
SEED = 0
TARGETS = {  # key: (limit, "max" = at most / "min" = at least)
    "ours_over_plain_one_pose": (2.0, "max"),
    "peer_over_ours_four_poses": (2.0, "min"),
}


def payload_torques(robot: cg.RobotModel, Q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Clean (tau_before, tau_after) (k, n): RNEA at v = a = 0 with a payload at the ee."""
    loaded = pin.Model(robot.model)
    frame = loaded.frames[robot.ee_frame_id]
    loaded.appendBodyToJoint(
        frame.parentJoint, pin.Inertia(MASS, COM_EE, INERTIA_EE), frame.placement
    )
    d0, d1, z = robot.model.createData(), loaded.createData(), np.zeros(robot.nq)
    tau_before = np.array([pin.rnea(robot.model, d0, q, z, z) for q in Q])
    tau_after = np.array([pin.rnea(loaded, d1, q, z, z) for q in Q])
    return tau_before, tau_after


def noisy(tau: np.ndarray, rng) -> np.ndarray:
    return tau + rng.normal(scale=TORQUE_STD, size=tau.shape)


def wrist_poses(robot: cg.RobotModel, q: np.ndarray, k: int, rng) -> np.ndarray:
    """q and k - 1 copies with the wrist joints offset (as tests/test_estimator.py)."""
    offsets = np.zeros((k, robot.nq))
    offsets[1:, -3:] = rng.uniform(-0.8, 0.8, size=(k - 1, 3))
    return q + offsets


def plain_lstsq(robot: cg.RobotModel, q: np.ndarray, dtau: np.ndarray) -> np.ndarray:
    """theta = (m, m c_ee) by hand: Pinocchio's Jacobian, eq. 5's regression, np.linalg.lstsq."""
    J = pin.computeFrameJacobian(robot.model, robot.data, q, robot.ee_frame_id,
                                 pin.LOCAL_WORLD_ALIGNED)  # fmt: skip
    R = robot.data.oMf[robot.ee_frame_id].rotation
    g = robot.model.gravity.linear
    Y = np.column_stack((-(g @ J[:3]), J[3:].T @ (pin.skew(g) @ R)))
    return np.linalg.lstsq(Y, dtau, rcond=None)[0]


def median_time(fn, calls: int, blocks: int) -> float:
    """Median over ``blocks`` of the mean time of ``calls`` calls (s)."""
    fn()
    samples = []
    for _ in range(blocks):
        t0 = time.perf_counter()
        for _ in range(calls):
            fn()
        samples.append((time.perf_counter() - t0) / calls)
    return statistics.median(samples)


def errors(est, u_true: np.ndarray | None = None) -> dict:
    """Mass error (g) and CoM error (mm); one pose without a prior: across gravity only."""
    com_true = COM_EE if u_true is None else COM_EE - u_true * (u_true @ COM_EE)
    return {
        "mass_error_g": 1e3 * float(est.mass - MASS),
        "com_error_mm": 1e3 * float(np.linalg.norm(est.com_ee - com_true)),
    }


def cold_and_warm(fn, calls: int, blocks: int) -> tuple[float, float]:
    """(first call with an empty solver cache, warm median) in s; the difference is the build."""
    _ipopt.build.cache_clear()
    t0 = time.perf_counter()
    fn()
    cold = time.perf_counter() - t0
    return cold, median_time(fn, calls, blocks)


# ----------------------------------------------------------------------------------- the peer


def peer_available() -> bool:
    try:
        import mujoco_sysid.regressors  # noqa: F401
    except ImportError:
        return False
    return True


def bench_peer(robot: cg.RobotModel, Q: np.ndarray, rng, calls: int, blocks: int) -> dict:
    """mujoco-sysid on the MuJoCo world vs ours, the same torques, 4 poses, lstsq."""
    from mujoco_sysid.regressors import get_jacobian, joint_body_regressor

    from comgrasp_pin.simulation import build_model
    from comgrasp_pin.simulation.world import ARM_JOINTS

    def add_payload(spec: mujoco.MjSpec) -> None:
        body = spec.body("eelink").add_body(name="payload")  # frame = eelink = the ee frame
        body.explicitinertial = True
        body.mass = MASS
        body.ipos = COM_EE.tolist()
        body.inertia = np.diag(INERTIA_EE).tolist()

    m0, m1 = build_model(), build_model(extras=[add_payload])
    d0, d1 = mujoco.MjData(m0), mujoco.MjData(m1)
    qadr = [m1.joint(name).qposadr[0] for name in ARM_JOINTS]
    dofs = [m1.joint(name).dofadr[0] for name in ARM_JOINTS]
    payload = m1.body("payload").id

    # static torques from MuJoCo: qfrc_bias at zero velocity (gravity only)
    tb, ta = np.empty(Q.shape), np.empty(Q.shape)
    for i, q in enumerate(Q):
        for m, d, out in ((m0, d0, tb), (m1, d1, ta)):
            d.qpos[qadr] = q
            d.qvel[:] = 0.0
            mujoco.mj_forward(m, d)
            out[i] = d.qfrc_bias[dofs]
    tb, ta = noisy(tb, rng), noisy(ta, rng)
    dtau = (ta - tb).ravel()

    data = mujoco.MjData(m1)
    data.qvel[:] = 0.0

    def peer_regressor() -> np.ndarray:
        rows = []
        for q in Q:
            data.qpos[qadr] = q
            # what the regressor reads: poses, com-based frames, velocities, cacc (v = a = 0)
            mujoco.mj_kinematics(m1, data)
            mujoco.mj_comPos(m1, data)
            mujoco.mj_comVel(m1, data)
            data.qacc[:] = 0.0
            mujoco.mj_rnePostConstraint(m1, data)
            Yb = joint_body_regressor(m1, data, payload)  # (6, 10), body frame
            J = get_jacobian(m1, data, payload)  # (6, nv), body frame
            rows.append((J.T @ Yb)[dofs, :4])  # static rows of (m, m c) for the arm joints
        return np.vstack(rows)

    def peer() -> np.ndarray:
        return np.linalg.lstsq(peer_regressor(), dtau, rcond=None)[0]

    def ours(std):
        return lambda: cg.estimate_com(robot, Q, tb, ta, torque_std=std)

    theta = peer()
    peer_mass, peer_com = float(theta[0]), theta[1:] / theta[0]
    est = ours(TORQUE_STD)()
    Y_ours = stacked_regressor(robot, Q)[0]
    t_peer = median_time(peer, calls, blocks)
    t_peer_regressor = median_time(peer_regressor, calls, blocks)
    t_ours = median_time(ours(TORQUE_STD), calls, blocks)
    t_ours_no_std = median_time(ours(None), calls, blocks)
    return {
        "peer": f"mujoco-sysid {importlib.metadata.version('mujoco-sysid')}",
        "poses": len(Q),
        "mujoco_model_bodies": int(m1.nbody),
        "regressor_max_abs_difference": float(np.abs(peer_regressor() - Y_ours).max()),
        "peer_mass_error_g": 1e3 * (peer_mass - MASS),
        "peer_com_error_mm": 1e3 * float(np.linalg.norm(peer_com - COM_EE)),
        "ours_mass_error_g": 1e3 * (est.mass - MASS),
        "ours_com_error_mm": 1e3 * float(np.linalg.norm(est.com_ee - COM_EE)),
        "peer_minus_ours_mass_g": 1e3 * (peer_mass - est.mass),
        "peer_minus_ours_com_mm": 1e3 * float(np.linalg.norm(peer_com - est.com_ee)),
        "peer_four_poses_us": 1e6 * t_peer,
        "peer_regressor_only_four_poses_us": 1e6 * t_peer_regressor,
        "ours_lstsq_four_poses_us": 1e6 * t_ours,
        "ours_lstsq_four_poses_no_std_us": 1e6 * t_ours_no_std,
        "ratio_peer_over_ours": t_peer / t_ours,
        "ratio_peer_over_ours_no_std": t_peer / t_ours_no_std,
    }


# ------------------------------------------------------------------------------------- main


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="fewer repetitions (~5 s)")
    parser.add_argument("--out", default=str(Path(__file__).parent / "results/estimator.json"))
    args = parser.parse_args()
    # many short blocks: the median shrugs off bursts of load from other processes
    calls, blocks = (100, 9) if args.quick else (400, 41)
    ipopt_calls, ipopt_blocks = (20, 9) if args.quick else (100, 15)

    load_before = os.getloadavg()[0]  # other jobs on the 2 cores slow every figure
    robot = cg.RobotModel.ur5()
    rng = np.random.default_rng(SEED)
    q = robot.random_configuration(rng)
    Q4 = wrist_poses(robot, q, 4, rng)
    tb4, ta4 = payload_torques(robot, Q4)
    tb4, ta4 = noisy(tb4, rng), noisy(ta4, rng)
    tb1, ta1 = tb4[0], ta4[0]
    u1 = -robot.ee_pose(q)[:3, :3][2]  # gravity in the ee frame: unseen at one pose
    prior = cg.AxisPrior(COM_EE, [1.0, 0.0, 0.0], PRIOR_STD)
    cases = {"one_pose": (q, tb1, ta1), "four_poses": (Q4, tb4, ta4)}
    results: dict = {"robot": "ur5"}
    table: list[tuple[str, float, str]] = []

    def record(key: str, seconds: float, unit: str) -> float:
        value = seconds * {"us": 1e6, "ms": 1e3}[unit]
        results[f"{key}_{unit}"] = value
        table.append((key, value, unit))
        return seconds

    # 1. closed form, with and without torque_std
    accuracy: dict = {}
    lstsq: dict = {}
    for name, (Q, tb, ta) in cases.items():
        for std, suffix in ((None, "_no_std"), (TORQUE_STD, "")):
            fn = partial(cg.estimate_com, robot, Q, tb, ta, torque_std=std)
            lstsq[name + suffix] = record(
                f"lstsq_{name}{suffix}", median_time(fn, calls, blocks), "us"
            )
        accuracy[f"lstsq_{name}"] = errors(fn(), u1 if name == "one_pose" else None)
    jacobian = partial(
        pin.computeFrameJacobian,
        robot.model,
        robot.data,
        q,
        robot.ee_frame_id,
        pin.LOCAL_WORLD_ALIGNED,
    )
    record("kinematics_jacobian", median_time(jacobian, calls, blocks), "us")
    plain = partial(plain_lstsq, robot, q, ta1 - tb1)
    plain_s = record("plain_lstsq_one_pose", median_time(plain, calls, blocks), "us")
    ours_s = median_time(partial(cg.estimate_com, robot, q, tb1, ta1, torque_std=TORQUE_STD),
                         calls, blocks)  # fmt: skip
    results["ours_over_plain_one_pose"] = ours_s / plain_s
    theta = plain()
    ours = cg.estimate_com(robot, q, tb1, ta1, torque_std=TORQUE_STD)
    results["plain_vs_ours_one_pose_max_abs"] = {
        "mass_kg": abs(float(theta[0]) - ours.mass),
        "com_across_gravity_m": float(np.abs(theta[1:] / theta[0] - ours.com_ee).max()),
    }

    # 2.-4. IPOPT through estimate_com: l2, axis prior, Huber (warm cache; build apart)
    _ipopt.build(2, 2, "l2", False)  # load the IPOPT plugin once, outside any build time
    ipopt_cases = {
        "ipopt_l2_one_pose": ("one_pose", {}),
        "ipopt_l2_four_poses": ("four_poses", {}),
        "ipopt_prior_one_pose": ("one_pose", {"com_prior": prior}),
        "ipopt_prior_four_poses": ("four_poses", {"com_prior": prior}),
        "ipopt_huber_four_poses": ("four_poses", {"loss": "huber", "huber_delta": HUBER_DELTA}),
    }
    build_ms, ipopt_runs, ipopt_times = {}, {}, {}
    for key, (name, kwargs) in ipopt_cases.items():
        Q, tb, ta = cases[name]
        fn = partial(cg.estimate_com, robot, Q, tb, ta, "ipopt", TORQUE_STD, **kwargs)
        cold, warm = cold_and_warm(fn, ipopt_calls, ipopt_blocks)
        ipopt_times[key] = record(key, warm, "ms")
        build_ms[key] = 1e3 * (cold - warm)
        est = fn()
        ipopt_runs[key] = {"status": est.solver_status, "iterations": est.iterations}
        no_prior_one_pose = name == "one_pose" and "com_prior" not in kwargs
        accuracy[key] = errors(est, u1 if no_prior_one_pose else None)
    results["ipopt_build_ms"] = build_ms
    results["ipopt_runs"] = ipopt_runs

    # 5. the prior problem at one pose, solve only: arrays prepared as estimate_com does
    Y1 = stacked_regressor(robot, q[None])[0]
    b1 = ta1 - tb1
    w1 = np.full(robot.nq, 1.0 / (math.sqrt(2.0) * TORQUE_STD))
    closed = cg.estimate_com(robot, q, tb1, ta1, torque_std=TORQUE_STD)
    P = prior.across()
    Pu = P @ u1
    c0 = closed.com_ee - u1 * float(Pu @ (P @ (closed.com_ee - prior.point_ee))) / float(Pu @ Pu)
    x0 = np.r_[closed.mass, c0]  # the warm start of estimate_com: on the line nearest the axis
    solve = partial(_ipopt.solve, Y1, b1, w1, x0, "l2", HUBER_DELTA, prior)
    solver = _ipopt.build(robot.nq, 4, "l2", True).nlpsol
    params = _ipopt.parameters(Y1, b1, w1, "l2", HUBER_DELTA, prior)[0]  # as ipopt.solve
    call = partial(solver, x0=x0, p=params)
    solve_s = record(
        "ipopt_prior_one_pose_solve", median_time(solve, ipopt_calls, ipopt_blocks), "ms"
    )
    call_s = record(
        "ipopt_prior_one_pose_nlpsol_call", median_time(call, ipopt_calls, ipopt_blocks), "ms"
    )
    record("ipopt_prior_one_pose_around_nlpsol", ipopt_times["ipopt_prior_one_pose"] - call_s, "ms")
    res = solve()
    x_call = np.asarray(call()["x"]).ravel()
    via = cg.estimate_com(
        robot, q, tb1, ta1, method="ipopt", torque_std=TORQUE_STD, com_prior=prior
    )
    x_est = np.r_[via.mass, via.com_ee]
    results["ipopt_prior_one_pose_solve_detail"] = {
        "status": res.return_status,
        "iterations": res.iterations,
        "nlpsol_call_vs_solve_max_abs_x": float(np.abs(x_call - res.x).max()),
        "solve_vs_estimate_com_max_abs_x": float(np.abs(res.x - x_est).max()),
    }

    # 7. the peer
    if peer_available():
        peer = bench_peer(robot, Q4, rng, calls, blocks)
        table.append(("peer mujoco-sysid 4 poses", peer["peer_four_poses_us"], "us"))
    else:
        print("mujoco-sysid is not installed (pip install mujoco-sysid): peer comparison skipped")
        peer = None
    results["peer"] = peer

    results["accuracy"] = accuracy
    results["ratios"] = {
        "ipopt_l2_over_lstsq_one_pose": ipopt_times["ipopt_l2_one_pose"] / lstsq["one_pose"],
        "ipopt_l2_over_lstsq_four_poses": ipopt_times["ipopt_l2_four_poses"] / lstsq["four_poses"],
        "ipopt_prior_over_l2_one_pose": ipopt_times["ipopt_prior_one_pose"]
        / ipopt_times["ipopt_l2_one_pose"],
        "ipopt_huber_over_l2_four_poses": ipopt_times["ipopt_huber_four_poses"]
        / ipopt_times["ipopt_l2_four_poses"],
        "lstsq_with_std_over_no_std_one_pose": lstsq["one_pose"] / lstsq["one_pose_no_std"],
        "ours_over_plain_one_pose": results["ours_over_plain_one_pose"],
        "ipopt_prior_one_pose_estimate_over_solve": ipopt_times["ipopt_prior_one_pose"] / solve_s,
        "peer_over_ours_four_poses": None if peer is None else peer["ratio_peer_over_ours"],
    }
    results["peer_over_ours_four_poses"] = results["ratios"]["peer_over_ours_four_poses"]
    results["targets"] = {key: {kind: limit} for key, (limit, kind) in TARGETS.items()}
    results["meets_targets"] = {
        key: results[key] is not None
        and (results[key] <= limit if kind == "max" else results[key] >= limit)
        for key, (limit, kind) in TARGETS.items()
    }
    results["case"] = {
        "payload_mass_kg": MASS,
        "payload_com_ee_m": COM_EE.tolist(),
        "torque_noise_std_nm": TORQUE_STD,
        "prior": {"point_ee": COM_EE.tolist(), "direction_ee": [1.0, 0.0, 0.0], "std_m": PRIOR_STD},
        "huber_delta": HUBER_DELTA,
        "seed": SEED,
        "q": q.tolist(),
        "poses": Q4.tolist(),
    }
    results["ipopt_options"] = dict(_ipopt.IPOPT_OPTIONS)
    results["environment"] = {
        "python": platform.python_version(),
        "machine": platform.machine(),
        "cpus": os.cpu_count(),
        "numpy": np.__version__,
        "pinocchio": pin.__version__,
        "casadi": ca.__version__,
        "mujoco": mujoco.__version__,
        "mujoco_sysid": importlib.metadata.version("mujoco-sysid") if peer is not None else None,
        "quick": args.quick,
        "date": time.strftime("%Y-%m-%dT%H:%M:%S"),
        "load_avg_1min_before": load_before,
        "load_avg_1min_after": os.getloadavg()[0],
    }
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(results, indent=2) + "\n")

    print(f"{'case':40s} {'value':>12s} {'unit':6s}")
    for key, value, unit in table:
        print(f"{key:40s} {value:12.3f} {unit:6s}")
    for key, (limit, kind) in TARGETS.items():
        sign = "<=" if kind == "max" else ">="
        verdict = "met" if results["meets_targets"][key] else "MISSED"
        value = "n/a" if results[key] is None else f"{results[key]:.3f}"
        print(f"target {key:40s} {value:>12s} {sign} {limit:g}: {verdict}")
    print(
        "ipopt build (ms):",
        ", ".join(f"{k.removeprefix('ipopt_')} {v:.1f}" for k, v in build_ms.items()),
    )
    for key, acc in accuracy.items():
        mass_g, com_mm = acc["mass_error_g"], acc["com_error_mm"]
        print(f"  {key:28s} mass error {mass_g:+8.3f} g   CoM error {com_mm:7.3f} mm")
    if peer is not None:
        print(
            f"peer vs ours (4 poses, lstsq): mass {peer['peer_minus_ours_mass_g']:+.2e} g, "
            f"CoM {peer['peer_minus_ours_com_mm']:.2e} mm apart; "
            f"time peer/ours {peer['ratio_peer_over_ours']:.2f}"
        )
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
