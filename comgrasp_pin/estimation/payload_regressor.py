"""The dynamic payload model: joint torques linear in the payload's ten inertial parameters.

A rigid payload fixed to the ee frame adds to the joint torques of a moving arm

    dtau = Y(q, qd, qdd) @ pi,   pi = (m, m c_x, m c_y, m c_z, Ixx, Ixy, Iyy, Ixz, Iyz, Izz)

with c the CoM and I the inertia about the ee frame's origin, both in ee-frame axes
(kg, kg m, kg m^2): Pinocchio's dynamic-parameter order (``pin.Inertia.toDynamicParameters``).
Per sample, Y = J_ee^T Phi(v_ee, a_ee - g_ee), where J_ee is the (6, n) ee Jacobian in the
ee frame (LOCAL), v_ee, a_ee the ee frame's spatial velocity and acceleration, g_ee the
model's gravity (``robot.model.gravity``) in the ee frame, and Phi Pinocchio's (6, 10) body
regressor (``pin.bodyRegressor``): the wrench the body needs, linear in pi.

With qd = qdd = 0 the first four columns are the static regressor of
``estimation.regressor`` (theta = (m, m c_ee)) and the inertia columns vanish.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from comgrasp_pin import validate
from comgrasp_pin.errors import InvalidInputError
from comgrasp_pin.robot import RobotModel

N_PARAMS = 10
PARAMETER_NAMES = ("m", "mcx", "mcy", "mcz", "Ixx", "Ixy", "Iyy", "Ixz", "Iyz", "Izz")
"""pi's order (Pinocchio's): mass, first moments (kg m), inertia at the ee origin (kg m^2)."""

_LOCAL = pin.ReferenceFrame.LOCAL


def payload_regressor(
    robot: RobotModel, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray
) -> np.ndarray:
    """Y with dtau = Y @ pi for a payload rigidly held in the ee frame.

    Args:
        robot: the arm; its model's gravity is used (``load_robot`` sets a mount's).
        q: joint positions (rad or m), (n,) for one sample or (k, n) for k samples.
        qd: joint velocities (rad/s or m/s), the shape of q.
        qdd: joint accelerations (rad/s^2 or m/s^2), the shape of q.

    Returns:
        (n, 10) for one sample, (k, n, 10) for k samples (sample-major; ``reshape(-1, 10)``
        stacks them). Columns in ``PARAMETER_NAMES`` order: N m/kg for m, N/kg for m c,
        1/s^2 for the inertia (revolute joints; a prismatic joint's row is in N per unit).

    Raises:
        InvalidInputError: shapes that differ or do not end in n, NaN or inf.
    """
    arrays = [validate.real_array(x, name) for x, name in ((q, "q"), (qd, "qd"), (qdd, "qdd"))]
    shape = arrays[0].shape
    for x, name in zip(arrays, ("q", "qd", "qdd"), strict=True):
        if x.shape != shape or x.ndim not in (1, 2) or x.shape[-1] != robot.nq:
            raise InvalidInputError(
                f"q, qd and qdd must have the same shape (n,) or (k, n) with n = {robot.nq}; "
                f"{name} has shape {x.shape}"
            )
        if not np.all(np.isfinite(x)):
            raise InvalidInputError(f"{name} contains NaN or inf")
    Q, QD, QDD = (x.reshape(-1, robot.nq) for x in arrays)
    Y = regressor_rows(robot, Q, QD, QDD)
    return Y[0] if len(shape) == 1 else Y


def regressor_rows(robot: RobotModel, Q: np.ndarray, QD: np.ndarray, QDD: np.ndarray) -> np.ndarray:
    """(k, n, 10) payload regressor of k samples (k, n), unchecked: for inner loops."""
    model, data, fid = robot.model, robot.data, robot.ee_frame_id
    Y = np.empty((len(Q), robot.nq, N_PARAMS))
    for i, (q, qd, qdd) in enumerate(zip(Q, QD, QDD)):
        pin.forwardKinematics(model, data, q, qd, qdd)
        pin.computeJointJacobians(model, data, q)
        M_world_ee = pin.updateFramePlacement(model, data, fid)
        J_ee = pin.getFrameJacobian(model, data, fid, _LOCAL)
        v_ee = pin.getFrameVelocity(model, data, fid, _LOCAL)
        a_ee = pin.getFrameAcceleration(model, data, fid, _LOCAL)
        g_ee = M_world_ee.actInv(model.gravity)
        Y[i] = J_ee.T @ pin.bodyRegressor(v_ee, a_ee - g_ee)
    return Y


def parameter_scale(typical_length_m: float = 0.1, typical_mass_kg: float = 1.0) -> np.ndarray:
    """(10,) typical magnitudes of pi: (m, m L (x3), m L^2 (x6)).

    For a payload of mass ``typical_mass_kg`` whose CoM and radius of gyration are
    ``typical_length_m`` from the ee origin; columns of Y times these give each parameter's
    typical torque contribution.
    """
    if not (typical_length_m > 0 and typical_mass_kg > 0):
        raise InvalidInputError(
            f"typical length and mass must be > 0, got {typical_length_m}, {typical_mass_kg}"
        )
    L, m = float(typical_length_m), float(typical_mass_kg)
    return np.array([m, *(3 * [m * L]), *(6 * [m * L * L])])


def condition_number(Y: np.ndarray, scale: np.ndarray | None = None) -> float:
    """sigma_max / sigma_min of a stacked regressor (inf if rank deficient).

    ``Y`` is (k, n, 10) or (k*n, 10); its columns are multiplied by ``scale`` (10,)
    (``parameter_scale``), or left in SI units if None.
    """
    A = np.asarray(Y, float).reshape(-1, N_PARAMS)
    if scale is not None:
        A = A * scale
    s = np.linalg.svd(A, compute_uv=False)
    return float(s[0] / s[-1]) if s[-1] > 0 else float("inf")
