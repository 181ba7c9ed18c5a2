"""The static payload model, linear in theta = (m, m*c_ee) (paper eq. 5, docs/design.md section 3).

A payload of mass m (kg) with its CoM at c_ee (m, ee frame) held still at q changes the joint
torques by

    dtau = tau_after - tau_before = Y(q) @ theta,     theta = (m, m*c_ee)  (kg, kg m)

with, for the (6, n) world-aligned ee Jacobian J = (J_lin; J_ang) and the robot model's
gravity g (world frame, ``robot.model.gravity``: any direction and magnitude):

    Y(q) = [ -J_lin^T g ,  J_ang^T [g]x R_world_ee ]                       (n, 4)

This is -J_c^T (m g) for the linear Jacobian J_c = J_lin - [R c_ee]x J_ang of the CoM point,
i.e. the torque that holds the payload's weight. For a revolute joint (J_lin column a x r,
J_ang column a) row i reads -a_i . ((r_i + R c_ee) x m g): eq. 5. For a prismatic joint it is
-a_i . m g. The columns are the first four of Pinocchio's ten inertial parameters of a body
at the ee frame (``frameBodyRegressor``); tests check both paths agree.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from comgrasp_pin.robot import RobotModel

RANK_TOL = 1e-9
"""Singular values of a (whitened) regressor below this fraction of the largest are directions
the poses leave open."""

_WORLD_ALIGNED = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED


def stacked_regressor(
    robot: RobotModel, Q: np.ndarray, gravity: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """Regression over k poses: Y (k*n, 4), pose-major rows, and T_world_ee (k, 4, 4).

    ``Q`` is (k, n); the unknowns are shared because theta is written in the ee frame.
    ``gravity``: (3,) the model's gravity (world, m/s^2), read from ``robot.model`` if None.
    Per pose Y = J^T M with M (6, 4) = [[-g, 0], [0, [g]x R]].
    """
    k, n = Q.shape
    model, data, fid = robot.model, robot.data, robot.ee_frame_id
    g = model.gravity.linear if gravity is None else gravity
    J = np.empty((k, 6, n))
    T = np.empty((k, 4, 4))
    for i in range(k):
        J[i] = pin.computeFrameJacobian(model, data, Q[i], fid, _WORLD_ALIGNED).reshape(6, n)
        T[i] = data.oMf[fid].homogeneous
    M = np.zeros((k, 6, 4))
    M[:, :3, 0] = -g
    M[:, 3:, 1:] = pin.skew(g) @ T[:, :3, :3]
    return (J.transpose(0, 2, 1) @ M).reshape(k * n, 4), T


def pose_regressor(robot: RobotModel, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Y(q) (n, 4) and T_world_ee (4, 4) at one configuration ``q`` (n,)."""
    Y, T = stacked_regressor(robot, np.asarray(q, dtype=float)[None])
    return Y, T[0]
