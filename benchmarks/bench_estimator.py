"""Timing of the CoM estimator: lstsq vs IPOPT, one pose and four, and batch throughput.

    python benchmarks/bench_estimator.py [--quick] [--out benchmarks/results/estimator.json]

Times are medians over blocks of calls (UR5, clean RNEA torques with a 0.7 kg payload). The
IPOPT solvers are built before timing (build time reported apart); every IPOPT solve starts
from zero. Targets (issue 3): lstsq <= 15 us per one-pose estimate including kinematics,
IPOPT <= 1.5 ms, batch >= 100 000 estimates/s for 10 000 grasps.
"""

from __future__ import annotations

import argparse
import json
import platform
import statistics
import time
from pathlib import Path

import casadi as ca
import numpy as np
import pinocchio as pin

import comgrasp_pin as cg
from comgrasp_pin.estimation import ipopt as _lsq_ipopt
from comgrasp_pin.estimation.regressor import stacked_regressor

MASS, COM_EE = 0.7, np.array([0.04, -0.03, 0.15])


def payload_torques(robot: cg.RobotModel, Q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(tau_before, tau_after) (k, n) from RNEA at v = a = 0 with a payload at the ee."""
    loaded = pin.Model(robot.model)
    frame = loaded.frames[robot.ee_frame_id]
    loaded.appendBodyToJoint(
        frame.parentJoint, pin.Inertia(MASS, COM_EE, np.eye(3) * 1e-3), frame.placement
    )
    d0, d1, z = robot.model.createData(), loaded.createData(), np.zeros(robot.nq)
    tau_before = np.array([pin.rnea(robot.model, d0, q, z, z) for q in Q])
    tau_after = np.array([pin.rnea(loaded, d1, q, z, z) for q in Q])
    return tau_before, tau_after


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


def ipopt_default_options_ms(Y: np.ndarray, b: np.ndarray, calls: int, blocks: int) -> float:
    """The same problem with IPOPT's default options (only quiet): what tuning bought."""
    rows, p = Y.shape
    Ys, bs, w = ca.SX.sym("Y", rows, p), ca.SX.sym("b", rows), ca.SX.sym("w", p)
    nlp = {"x": w, "p": ca.vertcat(ca.vec(Ys), bs), "f": 0.5 * ca.sumsqr(Ys @ w - bs)}
    opts = {"print_time": False, "ipopt.print_level": 0, "ipopt.sb": "yes"}
    solver = ca.nlpsol("default", "ipopt", nlp, opts)
    params = np.concatenate([Y.ravel(order="F"), b])
    return 1e3 * median_time(lambda: solver(x0=np.zeros(p), p=params), calls, blocks)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="fewer repetitions")
    parser.add_argument("--out", default=str(Path(__file__).parent / "results/estimator.json"))
    args = parser.parse_args()
    # many short blocks: the median shrugs off bursts of load from other processes
    calls, blocks = (200, 5) if args.quick else (400, 61)
    ipopt_calls, ipopt_blocks = (20, 5) if args.quick else (200, 11)
    n_batch = 10_000

    robot = cg.RobotModel.ur5()
    rng = np.random.default_rng(0)
    q = robot.random_configuration(rng)
    Q4 = cg.plan_wrist_poses(robot, q, 4)
    tb4, ta4 = payload_torques(robot, Q4)
    tb1, ta1 = tb4[0], ta4[0]

    def estimate(Q, tb, ta, method):
        return lambda: cg.estimate_com(robot, Q, tb, ta, method=method)

    lstsq_1 = median_time(estimate(q, tb1, ta1, "lstsq"), calls, blocks)
    lstsq_1_best = median_time(estimate(q, tb1, ta1, "lstsq"), calls, 1)
    for _ in range(blocks - 1):
        lstsq_1_best = min(lstsq_1_best, median_time(estimate(q, tb1, ta1, "lstsq"), calls, 1))
    lstsq_1_cov = median_time(
        lambda: cg.estimate_com(robot, q, tb1, ta1, torque_std=0.05), calls, blocks
    )
    lstsq_4 = median_time(estimate(Q4, tb4, ta4, "lstsq"), calls // 4, blocks)
    t_build = time.perf_counter()
    _lsq_ipopt.lsq_solver.cache_clear()
    cg.estimate_com(robot, q, tb1, ta1, method="ipopt")
    cg.estimate_com(robot, Q4, tb4, ta4, method="ipopt")
    build_ms = 1e3 * (time.perf_counter() - t_build) / 2

    kinematics = median_time(
        lambda: pin.computeFrameJacobian(
            robot.model, robot.data, q, robot.ee_frame_id, pin.LOCAL_WORLD_ALIGNED
        ),
        calls,
        blocks,
    )
    ipopt_1 = median_time(estimate(q, tb1, ta1, "ipopt"), ipopt_calls, ipopt_blocks)
    ipopt_4 = median_time(estimate(Q4, tb4, ta4, "ipopt"), ipopt_calls, ipopt_blocks)
    est_ipopt_1 = cg.estimate_com(robot, q, tb1, ta1, method="ipopt")
    est_ipopt_4 = cg.estimate_com(robot, Q4, tb4, ta4, method="ipopt")
    Y4 = stacked_regressor(robot, Q4)[0]
    b4 = (ta4 - tb4).ravel()
    ipopt_default_4 = ipopt_default_options_ms(Y4, b4, ipopt_calls, ipopt_blocks)
    ipopt_tuned_4 = 1e3 * median_time(
        lambda: _lsq_ipopt.solve_lsq(Y4, b4), ipopt_calls, ipopt_blocks
    )

    Qb = np.array([robot.random_configuration(rng) for _ in range(n_batch)])
    tbb, tab = payload_torques(robot, Qb)
    batch_s = median_time(lambda: cg.estimate_com_batch(robot, Qb, tbb, tab), 1, 3)
    batch_est = cg.estimate_com_batch(robot, Qb, tbb, tab)
    loop_s = median_time(
        lambda: [cg.estimate_com(robot, Qb[i], tbb[i], tab[i]) for i in range(2000)], 1, 3
    )

    results = {
        "robot": "ur5",
        "lstsq_one_pose_us": 1e6 * lstsq_1,
        "lstsq_one_pose_best_block_us": 1e6 * lstsq_1_best,
        "lstsq_one_pose_with_cov_us": 1e6 * lstsq_1_cov,
        "lstsq_four_poses_us": 1e6 * lstsq_4,
        "kinematics_jacobian_us": 1e6 * kinematics,
        "ipopt_one_pose_ms": 1e3 * ipopt_1,
        "ipopt_four_poses_ms": 1e3 * ipopt_4,
        "ipopt_four_poses_solver_only_tuned_ms": ipopt_tuned_4,
        "ipopt_four_poses_solver_only_default_options_ms": ipopt_default_4,
        "ipopt_build_ms": build_ms,
        "ipopt_iterations_one_pose": est_ipopt_1.iterations,
        "ipopt_iterations_four_poses": est_ipopt_4.iterations,
        "ipopt_status": est_ipopt_4.solver_status,
        "ipopt_options": {k: v for k, v in _lsq_ipopt.IPOPT_OPTIONS.items()},
        "ratio_ipopt_over_lstsq_one_pose": ipopt_1 / lstsq_1,
        "ratio_ipopt_over_lstsq_four_poses": ipopt_4 / lstsq_4,
        "batch_grasps": n_batch,
        "batch_estimates_per_s": n_batch / batch_s,
        "batch_max_mass_error_kg": float(np.abs(batch_est.mass - MASS).max()),
        "single_call_loop_estimates_per_s": 2000 / loop_s,
        "targets": {"lstsq_one_pose_us": 15.0, "ipopt_ms": 1.5, "batch_estimates_per_s": 1e5},
        "environment": {
            "python": platform.python_version(),
            "machine": platform.machine(),
            "numpy": np.__version__,
            "pinocchio": pin.__version__,
            "casadi": ca.__version__,
            "quick": args.quick,
            "date": time.strftime("%Y-%m-%dT%H:%M:%S"),
        },
    }
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(results, indent=2) + "\n")
    for key, value in results.items():
        if isinstance(value, float):
            print(f"{key:40s} {value:12.3f}")
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
