"""Inverse kinematics for top-down grasps, on Pinocchio only (no MuJoCo).

A top-down grasp of a lying rod: ee-z points down (world -z), ee-x runs along the rod, so
ee-y (the jaw axis) is horizontal across it. A rod with yaw psi can be grasped with ee-x at
psi or psi + pi; ``grasp_frame`` picks one (side-camera boom, along ee -y, away from the
robot base when possible), ``solve_ik`` finds joints close to a seed (damped least squares
on the SE(3) log error, joint limits enforced, wrist_3 moved by multiples of 2 pi towards
the seed), ``solve_top_down`` tries both and keeps the best.
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin

from comgrasp_pin.errors import IKError
from comgrasp_pin.geometry import GraspPose
from comgrasp_pin.robot import RobotModel
from comgrasp_pin.workcell import GRIPPER, Q_HOME, TABLE_Z

FINGERTIP_CLEARANCE = 0.002  # fingertips kept this far above the table (m)
_LOCAL = pin.ReferenceFrame.LOCAL


def top_down_frame(x: float, y: float, z: float, yaw: float) -> np.ndarray:
    """(4, 4) T_world_ee with ee-z down, ee-x = (cos yaw, sin yaw, 0), origin (x, y, z) (m)."""
    c, s = np.cos(yaw), np.sin(yaw)
    T = np.eye(4)
    T[:3, :3] = np.array([[c, s, 0.0], [s, -c, 0.0], [0.0, 0.0, -1.0]])
    T[:3, 3] = [x, y, z]
    return T


def grasp_height(z_axis: float, table_z: float = TABLE_Z) -> float:
    """Eelink height (m) for a rod whose axis is at ``z_axis``: on the axis, but with the
    fingertips at least 2 mm above the table."""
    return max(z_axis, table_z + GRIPPER.fingertip_below_ee + FINGERTIP_CLEARANCE)


def grasp_frame(grasp: GraspPose, dz: float = 0.0, boom_away: bool = True) -> np.ndarray:
    """(4, 4) T_world_ee of ``grasp`` raised by ``dz`` (m), eelink at ``grasp_height``.

    With ``boom_away`` the yaw among (yaw, yaw + pi) that points the side-camera boom (ee -y)
    away from the robot base (world origin) is chosen.
    """
    yaw = grasp.yaw
    if boom_away:
        minus_y = np.array([-np.sin(yaw), np.cos(yaw)])
        if minus_y @ np.array([grasp.x, grasp.y]) < 0.0:
            yaw += np.pi
    return top_down_frame(grasp.x, grasp.y, grasp_height(grasp.z) + dz, yaw)


def solve_ik(
    robot: RobotModel,
    T_world_goal: np.ndarray,
    q_seed: np.ndarray,
    tol: float = 1e-8,
    max_iter: int = 200,
    damping: float = 1e-3,
) -> np.ndarray:
    """(n,) joints reaching ``T_world_goal`` (4, 4), starting from ``q_seed`` (rad).

    Damped least squares in the ee frame, steps clipped to 0.5 rad, joints clipped to their
    limits. Raises IKError when the pose error norm stays above ``tol``.
    """
    q = robot.check_q(q_seed).copy()
    goal = pin.SE3(np.asarray(T_world_goal, dtype=float))
    lo, hi = robot.q_lower, robot.q_upper
    model, data, fid = robot.model, robot.data, robot.ee_frame_id
    damping_eye = damping**2 * np.eye(6)
    err = np.full(6, np.inf)
    for _ in range(max_iter):
        pin.forwardKinematics(model, data, q)
        T_ee_goal = pin.updateFramePlacement(model, data, fid).actInv(goal)
        err = pin.log6(T_ee_goal).vector
        if math.sqrt(err @ err) < tol:  # np.linalg.norm's value, without its checks
            break
        J = pin.Jlog6(T_ee_goal) @ pin.computeFrameJacobian(model, data, q, fid, _LOCAL)
        dq = J.T @ np.linalg.solve(J @ J.T + damping_eye, err)
        step = np.abs(dq).max()
        if step > 0.5:
            dq *= 0.5 / step
        q = np.minimum(np.maximum(q + dq, lo), hi)  # np.clip's values
    else:
        raise IKError(
            f"IK did not converge: pose error {np.linalg.norm(err):.2e} > {tol:.0e} "
            f"for target position {goal.translation} from seed {q_seed}"
        )
    return _wrap_towards(q, q_seed, lo, hi)


def _wrap_towards(q: np.ndarray, q_seed: np.ndarray, lo: np.ndarray, hi: np.ndarray):
    """Move each joint by multiples of 2 pi towards the seed, staying within limits."""
    q = q.copy()
    for i in range(len(q)):
        k = np.round((q_seed[i] - q[i]) / (2 * np.pi))
        cand = q[i] + 2 * np.pi * k
        if lo[i] <= cand <= hi[i]:
            q[i] = cand
    return q


def solve_top_down(
    robot: RobotModel,
    grasp: GraspPose,
    q_seed: np.ndarray | None = None,
    dz: float = 0.0,
    boom_away: bool = True,
) -> tuple[np.ndarray, np.ndarray]:
    """Joints for the top-down ``grasp`` raised by ``dz`` (m): (q (n,), T_world_ee (4, 4)).

    Both yaws (psi, psi + pi) are solved from ``q_seed`` (default ``Q_HOME``); the one with the
    boom away from the base is preferred if ``boom_away``, otherwise (or if it fails) the
    one closest to the seed.
    """
    seed = Q_HOME if q_seed is None else robot.check_q(q_seed)
    preferred = grasp_frame(grasp, dz, boom_away=True)
    other = preferred.copy()
    other[:3, :2] *= -1.0  # yaw + pi: x and y flip, z stays down
    results = []
    for T in (preferred, other):
        try:
            q = solve_ik(robot, T, seed)
        except IKError:
            continue
        results.append((q, T))
    if not results:
        raise IKError(f"no IK solution for grasp {grasp} (dz = {dz} m)")
    if boom_away:
        return results[0]
    return min(results, key=lambda r: float(np.linalg.norm(r[0] - seed)))
