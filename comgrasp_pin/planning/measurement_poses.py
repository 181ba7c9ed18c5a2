"""Measurement poses for a real arm: within the limits, free of self-collision, D-optimal.

Candidates are drawn at random within the joint limits (kept ``margin`` from them), or, with
a start configuration, within ``max_offset`` of it on every joint (near the workspace the
arm already uses). Those that collide with the arm itself (``collision.SelfCollision``) or
put the ee or a wrist joint below ``min_height`` above the base are dropped. Then the poses
are chosen by greedy D-optimal design plus a Fedorov exchange on the stacked regressor of
``estimation.regressor`` (``planning.wrist_poses``), the start first if given. The
prediction is the Cramer-Rao bound for a payload of a given mass at the ee origin.
"""

from __future__ import annotations

import numpy as np

from comgrasp_pin import validate
from comgrasp_pin.errors import CollisionError, InvalidInputError
from comgrasp_pin.estimation import wrench
from comgrasp_pin.estimation.wrench_com import T_sensor_ee
from comgrasp_pin.planning.collision import SelfCollision
from comgrasp_pin.planning.wrist_poses import (
    PosePlan,
    check_prediction,
    exchange_d_optimal,
    greedy_d_optimal,
    information,
    predicted_std,
)
from comgrasp_pin.robot import RobotModel

UR_JOINTS = 6


def candidate_poses(
    robot: RobotModel,
    n: int,
    rng: np.random.Generator,
    start: np.ndarray | None = None,
    max_offset: float = 1.2,
    margin: float = 0.05,
) -> np.ndarray:
    """(n, nq) configurations within the limits (``margin`` inside), near ``start`` if given."""
    lo = np.maximum(robot.q_lower + margin, -np.pi)
    hi = np.minimum(robot.q_upper - margin, np.pi)
    if start is not None:
        lo = np.maximum(lo, start - max_offset)
        hi = np.minimum(hi, start + max_offset)
    return rng.uniform(lo, hi, size=(n, robot.nq))


def floor_heights(robot: RobotModel, q: np.ndarray) -> np.ndarray:
    """(4,) heights (m, world z) of the last three joint origins and the ee origin at ``q``.

    These are the points kept above the floor plane.
    """
    return np.r_[robot.joint_origins(q)[-3:, 2], robot.ee_pose(q)[2, 3]]


def feasible(robot: RobotModel, checker: SelfCollision, q: np.ndarray, min_height: float) -> bool:
    """Within the limits, no self-collision, ee and wrist origins above ``min_height`` (m)."""
    if np.any(q < robot.q_lower) or np.any(q > robot.q_upper):
        return False
    heights = floor_heights(robot, q)
    return bool(np.all(heights >= min_height)) and not checker.in_collision(q)


def plan_measurement_poses(
    robot: RobotModel,
    k: int,
    start: np.ndarray | None = None,
    torque_std: float = 0.005,
    mass: float = 1.0,
    srdf: str | None = None,
    n_candidates: int = 3000,
    seed: int = 0,
    min_height: float = 0.05,
    sensor_frame: str | None = None,
    wrench_std: tuple[float, float] = (0.01, 0.0005),
    max_offset: float = 1.2,
    margin: float = 0.05,
) -> PosePlan:
    """``k`` static poses that best determine the mass and the full 3-D CoM.

    The arguments and the result are those of ``estimation.plan_wrist_poses``, which turns
    only the wrist of one pose; here the poses range over the workspace.

    Args:
        robot: the arm (any serial arm with a collision model in its URDF).
        k: number of poses (>= 2 for a full 3-D CoM).
        start: (n,) first pose (rad), kept as pose 0, or None.
        torque_std: std of one averaged torque reading for the prediction (N m).
        mass: payload mass for the prediction (kg).
        srdf: SRDF whose disabled pairs are not checked (see ``collision``).
        n_candidates: random candidates drawn.
        seed: random seed.
        min_height: lowest height (m, world z) of the ee and the wrist joints.
        sensor_frame: plan for a wrist force/torque sensor at this frame instead of the
            joint torques: D-optimal for its ten unknowns (mass, CoM, the six offsets,
            ``estimation.wrench``); ``k`` >= 3 then.
        wrench_std: (force N, torque N m) std of one averaged wrench reading the wrench's
            prediction assumes.
        max_offset: with ``start``, candidates lie within this of it on every joint (rad).
        margin: candidates keep this from the joint limits (rad).

    Raises:
        InvalidInputError: bad k, start, torque_std or mass; CollisionError: the start
            collides or too few candidates are free.
    """
    k = validate.integer(k, "k", low=1)
    check_prediction(torque_std, mass)
    checker = SelfCollision(robot, srdf)
    if start is not None:
        start = robot.check_q(start)
        if not feasible(robot, checker, start, min_height):
            raise CollisionError(
                f"the start configuration is outside the joint limits, collides ("
                f"{checker.colliding_pairs(start)}) or is below {min_height} m"
            )
    rng = np.random.default_rng(seed)
    cand = candidate_poses(robot, n_candidates, rng, start, max_offset, margin)
    cand = np.array([q for q in cand if feasible(robot, checker, q, min_height)])
    need = k - (start is not None)
    if len(cand) < max(need, 1):
        raise CollisionError(
            f"only {len(cand)} of {n_candidates} candidate poses are free of self-collision and "
            f"above {min_height} m; increase --candidates or move the start pose"
        )
    fixed = [] if start is None else [start]
    pool = np.vstack([*fixed, cand]) if fixed else cand
    infos = (
        information(robot, pool)
        if sensor_frame is None
        else _wrench_infos(robot, pool, sensor_frame, wrench_std)
    )
    base = infos[0] if fixed else np.zeros(infos.shape[1:])
    chosen = [0] * len(fixed) + [
        len(fixed) + i for i in greedy_d_optimal(base, infos[len(fixed) :], need)
    ]
    chosen = exchange_d_optimal(infos, chosen, fixed=len(fixed))
    Q = pool[chosen]
    std = _predicted_std(robot, Q, infos[chosen].sum(axis=0), torque_std, mass, sensor_frame)
    wstd = None if sensor_frame is None else wrench_std
    return PosePlan(Q, tuple(robot.joint_names), robot.ee_frame, std, torque_std, mass,
                    len(cand), sensor_frame, wstd)  # fmt: skip


def _predicted_std(robot, Q, info, torque_std, mass, sensor_frame) -> np.ndarray:
    """(4,) std of (mass, com_ee) the poses promise for a payload at the ee origin.

    The joint torques' (``predicted_std``), or the wrist sensor's from its ``info`` (10, 10).
    """
    if sensor_frame is None:
        return predicted_std(robot, Q, torque_std, mass)
    T_se = T_sensor_ee(robot, sensor_frame)
    G = np.eye(4)
    G[1:, 1:] = T_se[:3, :3].T  # sensor axes to ee axes
    cov = wrench.predicted_cov(info, mass, T_se[:3, 3])
    return np.sqrt(np.diag(G @ cov @ G.T)) if np.all(np.isfinite(cov)) else np.full(4, np.inf)


def _wrench_infos(robot: RobotModel, Q: np.ndarray, sensor_frame: str, wrench_std) -> np.ndarray:
    """(c, 10, 10) each pose's information on the wrist sensor's ten unknowns."""
    g = robot.model.gravity.linear
    g_sensor = np.array([robot.frame_pose(q, sensor_frame)[:3, :3].T @ g for q in Q])
    return wrench.information(g_sensor, wrench_std)


def plan_dict(plan: PosePlan) -> dict:
    """The poses JSON: joints, configurations (rad) and the predicted std."""
    return {
        "joint_names": list(plan.joint_names),
        "ee_frame": plan.ee_frame,
        "q_rad": plan.q.tolist(),
        "predicted_std": {
            "mass_kg": float(plan.predicted_std[0]),
            "com_m": plan.predicted_std[1:].tolist(),
        },  # fmt: skip
        "assumed": {
            "torque_std_Nm": plan.torque_std,
            "mass_kg": plan.mass,
            "com_m": [0.0, 0.0, 0.0],
            "torque_std_means": "std of one averaged reading",
        },  # fmt: skip
        "n_candidates": plan.n_candidates,
        "sensor_frame": plan.sensor_frame,
        "wrench_std": None if plan.wrench_std is None else list(plan.wrench_std),
        "planned_for": "joint torques" if plan.sensor_frame is None else "a wrist sensor",
    }


def urscript_program(plan: PosePlan, hold_s: float = 3.0, a: float = 0.5, v: float = 0.3) -> str:
    """A URScript program: ``movej`` to each pose, hold ``hold_s`` seconds (measure there)."""
    if plan.q.shape[1] != UR_JOINTS:
        raise InvalidInputError(
            f"a URScript movej program needs a {UR_JOINTS}-joint UR arm; this one has "
            f"{plan.q.shape[1]} joints"
        )
    lines = [
        "# measurement poses planned by comgrasp_pin (comgrasp plan-poses): run once empty and",
        "# once holding the payload; record /joint_states and use the hold windows",
        "def comgrasp_measurement_poses():",
    ]
    for i, q in enumerate(plan.q):
        joints = ", ".join(f"{x:.6f}" for x in q)
        lines += [f"  # pose {i}", f"  movej([{joints}], a={a:g}, v={v:g})", f"  sleep({hold_s:g})"]
    lines += ["end", "comgrasp_measurement_poses()", ""]
    return "\n".join(lines)
