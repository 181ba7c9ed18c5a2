"""The static payload model, linear in theta = (m, m*c_ee) (paper eq. 5, docs/design.md section 3).

A payload of mass m (kg) with its CoM at c_ee (m, ee frame) held still at q changes the joint
torques by

    dtau = tau_after - tau_before = Y(q) @ theta,     theta = (m, m*c_ee)  (kg, kg m)

with, for the (6, n) world-aligned ee Jacobian J = (J_lin; J_ang) and g = (0, 0, -G0):

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

G0 = 9.81
"""Magnitude of gravity (m/s^2); gravity in the world frame is (0, 0, -G0)."""
GRAVITY_WORLD = np.array([0.0, 0.0, -G0])
DOWN_WORLD = np.array([0.0, 0.0, -1.0])

_WORLD_ALIGNED = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED


def regressor_from_jacobian(J_world: np.ndarray, R_world_ee: np.ndarray) -> np.ndarray:
    """(n, 4) regression matrix Y for theta = (m, m*c_ee).

    Args:
        J_world: (6, n) ee Jacobian, rows (linear, angular), world-aligned at the ee origin.
        R_world_ee: (3, 3) orientation of the ee frame in the world.

    Returns:
        Y with dtau = Y @ theta; column 0 in N m/kg, columns 1..3 in N/kg.
    """
    # -J_lin^T g = G0 J_lin_z;  J_ang^T [g]x R = G0 (J_ang_x R[1] - J_ang_y R[0])
    Y = np.empty((J_world.shape[1], 4))
    Y[:, 0] = G0 * J_world[2]
    Y[:, 1:] = G0 * (J_world[3, :, None] * R_world_ee[1] - J_world[4, :, None] * R_world_ee[0])
    return Y


def pose_regressor(robot: RobotModel, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Y(q) (n, 4) and T_world_ee (4, 4) at one configuration ``q`` (n,)."""
    J = pin.computeFrameJacobian(robot.model, robot.data, q, robot.ee_frame_id, _WORLD_ALIGNED)
    T_world_ee = robot.data.oMf[robot.ee_frame_id].homogeneous
    return regressor_from_jacobian(J, T_world_ee[:3, :3]), T_world_ee


def stacked_regressor(robot: RobotModel, Q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Regression over k poses: Y (k*n, 4), pose-major rows, and T_world_ee (k, 4, 4).

    ``Q`` is (k, n); the unknowns are shared because theta is written in the ee frame.
    """
    k, n = Q.shape
    J = np.empty((k, 6, n))
    T = np.empty((k, 4, 4))
    for i in range(k):
        J[i] = pin.computeFrameJacobian(
            robot.model, robot.data, Q[i], robot.ee_frame_id, _WORLD_ALIGNED
        )
        T[i] = robot.data.oMf[robot.ee_frame_id].homogeneous
    Y = np.empty((k, n, 4))
    Y[:, :, 0] = G0 * J[:, 2]
    Y[:, :, 1:] = G0 * (J[:, 3, :, None] * T[:, None, 1, :3] - J[:, 4, :, None] * T[:, None, 0, :3])
    return Y.reshape(k * n, 4), T


def gravity_in_ee(R_world_ee: np.ndarray) -> np.ndarray:
    """(3,) unit gravity direction (down) in the ee frame: R_world_ee^T (0, 0, -1)."""
    return -R_world_ee[2].copy()


def one_pose_basis(R_world_ee: np.ndarray) -> np.ndarray:
    """(4, 3) B with theta = B w for one pose, for w = (m, m c_wy, -m c_wx).

    w is the mass and the CoM's horizontal offset in the world (the part one pose observes);
    B writes it in the ee frame through the rows of ``R_world_ee`` (3, 3).
    """
    B = np.zeros((4, 3))
    B[0, 0] = 1.0
    B[1:, 1] = R_world_ee[1]
    B[1:, 2] = -R_world_ee[0]
    return B


def perpendicular_basis(u: np.ndarray) -> np.ndarray:
    """(3, 2) orthonormal basis of the plane perpendicular to the unit vector ``u`` (3,)."""
    helper = np.eye(3)[int(np.argmin(np.abs(u)))]
    e1 = np.cross(u, helper)
    e1 /= np.linalg.norm(e1)
    return np.stack([e1, np.cross(u, e1)], axis=1)
