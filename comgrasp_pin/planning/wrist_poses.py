"""Extra static poses that make the full 3-D CoM observable: turn only the wrist.

With one pose the CoM along gravity is lost. Further poses that change the wrist's
orientation relative to gravity (not merely about the vertical) add the missing direction.
The poses are chosen for D-optimality: maximise log det(Y^T Y) of the stacked regression
(``regressor``) for theta = (m, m c_ee). The criterion is independent of the payload and of
the units of theta, and maximising it minimises the volume of the confidence ellipsoid of
(m, c_ee) as well, since that covariance is G cov_theta G^T with a fixed Jacobian G.

``plan_wrist_poses`` and ``robot_io.plan_measurement_poses`` (any pose, free of
self-collision) take the same arguments in the same order (robot, k, start, torque_std,
mass) and return the same ``PosePlan``.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np

from comgrasp_pin import validate
from comgrasp_pin.errors import InvalidInputError
from comgrasp_pin.estimation.regressor import pose_regressor
from comgrasp_pin.robot import RobotModel

N_WRIST = 3
"""The wrist joints are the last N_WRIST joints of the arm."""
MAX_GRID = 21
"""Largest ``n_grid``: the candidates are n_grid ** 3 wrist poses (9261 at most)."""


@dataclass(frozen=True)
class PosePlan:
    """Planned static poses.

    Attributes:
        q: (k, n) configurations (rad / m), joint order ``joint_names``.
        joint_names: the arm's joints.
        ee_frame: the frame the CoM will be estimated in.
        predicted_std: (4,) predicted std of (mass, com_ee) (kg, m): the Cramer-Rao bound
            for a payload of ``mass`` at the ee origin, infinite where a direction is lost.
        torque_std: std of one averaged reading the prediction assumes (N m).
        mass: payload mass the prediction assumes (kg).
        n_candidates: candidate poses searched (within the limits; collision-free where
            the planner checks collisions).
        sensor_frame: the wrist sensor's frame the poses were planned for, or None (the
            joint torques); wrench_std: the (force N, torque N m) std its prediction
            assumes, or None.
    """

    q: np.ndarray
    joint_names: tuple[str, ...]
    ee_frame: str
    predicted_std: np.ndarray
    torque_std: float
    mass: float
    n_candidates: int
    sensor_frame: str | None = None
    wrench_std: tuple[float, float] | None = None


def check_prediction(torque_std: float, mass: float) -> None:
    """InvalidInputError unless ``torque_std`` (N m) and ``mass`` (kg) are finite and > 0."""
    validate.number(torque_std, "torque_std (N m)", low=0.0, low_open=True)
    validate.number(mass, "mass (kg)", low=0.0, low_open=True)


def plan_wrist_poses(
    robot: RobotModel,
    k: int,
    start: np.ndarray,
    torque_std: float = 0.005,
    mass: float = 1.0,
    max_offset: float = 0.6,
    n_grid: int = 5,
    margin: float = 0.05,
) -> PosePlan:
    """Plan ``k`` static configurations for estimation: ``start`` and k - 1 wrist variations.

    Greedy D-optimal design over a grid of wrist offsets: each step adds the candidate that
    most increases log det(sum_i Y_i^T Y_i). No collision check (the wrist turns in place;
    ``robot_io.plan_measurement_poses`` checks self-collision over the whole workspace).

    Args:
        robot: the arm (n >= 3 joints).
        k: number of poses wanted (an integer >= 1).
        start: (n,) measurement configuration (rad / m), returned as pose 0.
        torque_std: std of one averaged reading for the prediction (N m).
        mass: payload mass for the prediction (kg).
        max_offset: largest change of a wrist joint from ``start`` (rad, > 0, at most 2 pi).
        n_grid: grid points per wrist joint in [-max_offset, max_offset] (2 ... MAX_GRID).
        margin: distance kept from the joint limits (rad, >= 0, at most 2 pi).

    Returns:
        The plan; only the last three joints of its poses differ from ``start``.

    Raises:
        InvalidInputError: an argument of the wrong type, shape or range, or too few
            distinct wrist poses within the limits.
    """
    if not isinstance(robot, RobotModel):
        raise InvalidInputError(f"robot must be a RobotModel, got {type(robot).__name__}")
    k = validate.integer(k, "k", low=1)
    q = robot.check_q(start)
    check_prediction(torque_std, mass)
    if robot.nq < N_WRIST:
        raise InvalidInputError(f"the robot has {robot.nq} joints; a wrist needs {N_WRIST}")
    # a turn at most: a larger offset is the same poses, and a huge one overflows the grid
    max_offset = validate.number(max_offset, "max_offset (rad)", low=0.0, high=2 * np.pi,
                                 low_open=True)  # fmt: skip
    n_grid = validate.integer(n_grid, "n_grid", low=2, high=MAX_GRID)
    margin = validate.number(margin, "margin (rad)", low=0.0, high=2 * np.pi)
    candidates = _wrist_candidates(robot, q, max_offset, n_grid, margin)
    if len(candidates) < k - 1:
        raise InvalidInputError(
            f"only {len(candidates)} distinct wrist poses fit within the joint limits near the "
            f"start; {k - 1} are needed (increase max_offset or n_grid)"
        )
    Q = q[None].copy()
    if k > 1:
        Y0 = pose_regressor(robot, q)[0]
        chosen = greedy_d_optimal(Y0.T @ Y0, information(robot, candidates), k - 1)
        Q = np.vstack([q, candidates[chosen]])
    std = predicted_std(robot, Q, torque_std, mass)
    names = tuple(robot.joint_names)
    return PosePlan(Q, names, robot.ee_frame, std, float(torque_std), float(mass), len(candidates))


def information(robot: RobotModel, Q: np.ndarray) -> np.ndarray:
    """(c, 4, 4) information Y^T Y of theta = (m, m c_ee) per configuration of Q (c, n).

    For unit noise on each torque difference.
    """
    return np.array([Y.T @ Y for Y in (pose_regressor(robot, q)[0] for q in Q)]).reshape(-1, 4, 4)


def greedy_d_optimal(info: np.ndarray, infos: np.ndarray, m: int) -> list[int]:
    """Indices of ``m`` candidates of ``infos`` (c, 4, 4) added one by one to ``info`` (4, 4).

    Each maximises log det of the sum; before full rank, the trace.
    """
    chosen: list[int] = []
    available = np.ones(len(infos), dtype=bool)
    for _ in range(m):
        sign, logdet = np.linalg.slogdet(info + infos)
        score = np.where((sign > 0) & available, logdet, -np.inf)
        # before full rank every det is 0: fall back to the trace (total information)
        if not np.isfinite(score).any():
            score = np.where(available, np.trace(infos, axis1=1, axis2=2), -np.inf)
        best = int(np.argmax(score))
        chosen.append(best)
        available[best] = False
        info = info + infos[best]
    return chosen


def exchange_d_optimal(infos: np.ndarray, chosen: list[int], fixed: int = 0) -> list[int]:
    """Fedorov exchange: swap chosen candidates for others while log det grows.

    The first ``fixed`` entries of ``chosen`` stay. Returns the improved index list.
    """
    chosen = list(chosen)
    for _ in range(10):
        improved = False
        for slot in range(fixed, len(chosen)):
            rest = sum(infos[c] for j, c in enumerate(chosen) if j != slot)
            sign, logdet = np.linalg.slogdet(rest + infos)
            score = np.where(sign > 0, logdet, -np.inf)
            score[[c for j, c in enumerate(chosen) if j != slot]] = -np.inf
            best = int(np.argmax(score))
            if score[best] > score[chosen[slot]] + 1e-9:
                chosen[slot], improved = best, True
        if not improved:
            break
    return chosen


def predicted_std(
    robot: RobotModel,
    Q: np.ndarray,
    torque_std: float,
    mass: float,
    com_ee: np.ndarray | None = None,
) -> np.ndarray:
    """(4,) std of (mass, com_ee) (kg, m) that k poses Q (k, n) promise.

    For a payload of ``mass`` (kg) at ``com_ee`` (m, default the ee origin) and white noise
    of std ``torque_std`` (N m) on each averaged reading (a difference has 2 torque_std^2):
    the Cramer-Rao bound 2 torque_std^2 (Y^T Y)^-1 for theta, by the delta method for
    (m, c). Infinite where the poses leave a direction unobserved.
    """
    from comgrasp_pin.estimation.estimate import delta_method

    info = information(robot, np.atleast_2d(Q)).sum(axis=0)
    c = np.zeros(3) if com_ee is None else np.asarray(com_ee, float)
    s = np.linalg.svd(info, compute_uv=False)
    if not s[-1] > 1e-12 * s[0]:
        return np.full(4, np.inf)
    cov = delta_method(np.r_[mass, mass * c], 2 * torque_std**2 * np.linalg.inv(info))
    return np.sqrt(np.diag(cov))


def best_next_pose(robot: RobotModel, existing_q: np.ndarray, candidates: np.ndarray) -> int:
    """The D-optimal next pose: index of the row of ``candidates`` (c, n).

    The one that most increases log det of the information of the poses ``existing_q``
    (k, n) for theta = (m, m c_ee).
    """
    existing_q = np.atleast_2d(validate.real_array(existing_q, "existing_q"))
    candidates = np.atleast_2d(validate.real_array(candidates, "candidates"))
    if len(candidates) == 0:
        raise InvalidInputError("best_next_pose needs at least one candidate configuration")
    info = sum(Y.T @ Y for Y in (pose_regressor(robot, q)[0] for q in existing_q))
    scores = []
    for c in candidates:
        Y = pose_regressor(robot, c)[0]
        sign, logdet = np.linalg.slogdet(info + Y.T @ Y)
        scores.append(logdet if sign > 0 else -np.inf)
    return int(np.argmax(scores))


def _wrist_candidates(
    robot: RobotModel, q: np.ndarray, max_offset: float, n_grid: int, margin: float
) -> np.ndarray:
    """(C, n) distinct configurations with the wrist offset on a grid, within the limits."""
    steps = np.linspace(-max_offset, max_offset, n_grid)
    wrist = slice(robot.nq - N_WRIST, robot.nq)
    lo = robot.q_lower[wrist] + margin
    hi = robot.q_upper[wrist] - margin
    out, seen = [], {tuple(np.round(q[wrist], 9))}
    for offset in itertools.product(steps, repeat=N_WRIST):
        c = q.copy()
        c[wrist] = np.clip(q[wrist] + np.array(offset), lo, np.maximum(lo, hi))
        key = tuple(np.round(c[wrist], 9))
        if key not in seen:  # clipping may map several offsets to one pose
            seen.add(key)
            out.append(c)
    return np.array(out).reshape(-1, robot.nq)
