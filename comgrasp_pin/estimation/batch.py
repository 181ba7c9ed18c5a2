"""Many independent one-pose estimates at once: ``estimate_com``'s least squares, vectorised.

Each grasp i has its own configuration q_i and torque readings; the estimate is the one-pose
``estimate_com(..., method="lstsq")`` for every i (CoM across gravity, mass), computed with
batched NumPy instead of a Python call per grasp: the same unknowns (``one_pose_basis``), the
same input checks (``validate_inputs``) and the same empty-gripper test, solved through the
3x3 normal equations instead of an SVD. Only the kinematics loop is per grasp.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from comgrasp_pin.errors import EmptyGripperError, InvalidInputError, UnobservableError
from comgrasp_pin.estimation.estimate import (
    MASS_SIGMAS,
    MIN_MASS_KG,
    check_finite_result,
    singular_is_unobservable,
)
from comgrasp_pin.estimation.estimator import RCOND
from comgrasp_pin.estimation.inputs import check_rcond, validate_inputs
from comgrasp_pin.estimation.regressor import G0, one_pose_basis
from comgrasp_pin.robot import RobotModel

_WORLD_ALIGNED = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED


@dataclass(frozen=True)
class ComEstimateBatch:
    """One-pose estimates for N grasps; field meanings as in ``ComEstimate``.

    Attributes:
        com_ee: (N, 3) CoM in the ee frame (m), no component along ``unobservable_ee``.
        mass: (N,) kg.
        weight: (N,) N.
        unobservable_ee: (N, 3) unit gravity direction in the ee frame.
        cov: (N, 4, 4) covariance of (mass, com_ee), or None without torque_std.
        residual_rms: (N,) N m.
        condition_number: (N,).
    """

    com_ee: np.ndarray
    mass: np.ndarray
    weight: np.ndarray
    unobservable_ee: np.ndarray
    cov: np.ndarray | None
    residual_rms: np.ndarray
    condition_number: np.ndarray

    def __len__(self) -> int:
        return len(self.mass)


@singular_is_unobservable()
def estimate_com_batch(
    robot: RobotModel,
    q: np.ndarray,
    tau_before: np.ndarray,
    tau_after: np.ndarray,
    torque_std: float | np.ndarray | None = None,
    rcond: float = RCOND,
) -> ComEstimateBatch:
    """One-pose closed-form estimates for N grasps.

    Args:
        robot: the arm.
        q: (N, n) configurations (rad / m), one row per grasp.
        tau_before: (N, n) joint torques without the object (N m).
        tau_after: (N, n) joint torques holding the object (N m).
        torque_std: scalar or (n,) torque std (N m): weighted LS and ``cov``.
        rcond: relative singular-value threshold deciding observability (as in
            ``estimate_com``).

    Raises:
        ComGraspError subclasses (ValueError) naming the offending grasps.
    """
    rcond = check_rcond(rcond)
    if np.ndim(q) != 2:
        raise InvalidInputError(f"q must be (N, {robot.nq}) for a batch, got {np.shape(q)}")
    Q, dtau, sigma = validate_inputs(robot, q, tau_before, tau_after, torque_std)
    count, n = Q.shape
    A = np.empty((count, 3, n))  # rows J_lin_z, J_ang_x, J_ang_y: Y_r = G0 A^T
    R = np.empty((count, 3, 3))
    model, data, fid = robot.model, robot.data, robot.ee_frame_id
    for i in range(count):
        J = pin.computeFrameJacobian(model, data, Q[i], fid, _WORLD_ALIGNED)
        A[i] = J[2:5]
        R[i] = data.oMf[fid].rotation
    Aw = A if sigma is None else A / (sigma * sigma)  # A W with W = diag(1 / sigma^2)
    N = Aw @ A.transpose(0, 2, 1)
    rhs = np.einsum("kin,kn->ki", Aw, dtau)
    lam = np.linalg.eigvalsh(N)
    bad = np.flatnonzero(~(lam[:, 0] > rcond * rcond * lam[:, 2]))
    if bad.size:
        raise UnobservableError(
            f"grasps {bad[:10].tolist()} (of {bad.size}) leave the mass unobservable: their "
            f"regression is singular at rcond={rcond}"
        )
    N_inv = np.linalg.inv(N)
    w = np.einsum("kij,kj->ki", N_inv, rhs) / G0  # (m, m c_wy, -m c_wx)
    mass = w[:, 0]
    B = np.stack([one_pose_basis(r) for r in R])
    cov = None
    if sigma is not None:
        cov_theta = (2.0 / G0**2) * (B @ N_inv @ B.transpose(0, 2, 1))
        threshold = MASS_SIGMAS * np.sqrt(cov_theta[:, 0, 0])
    else:
        threshold = np.full(count, MIN_MASS_KG)
    empty = np.flatnonzero(~(mass > threshold))
    if empty.size:
        raise EmptyGripperError(
            f"grasps {empty[:10].tolist()} (of {empty.size}) have a payload mass not "
            f"measurably above zero (e.g. {mass[empty[0]]:.3g} kg vs threshold "
            f"{threshold[empty[0]]:.3g} kg): empty gripper?"
        )
    theta = np.einsum("kij,kj->ki", B, w)
    com_ee = theta[:, 1:] / mass[:, None]
    if sigma is not None:
        G = np.zeros((count, 4, 4))
        G[:, 0, 0] = 1.0
        G[:, 1:, 0] = -com_ee / mass[:, None]
        G[:, 1:, 1:] = np.eye(3) / mass[:, None, None]
        cov = G @ cov_theta @ G.transpose(0, 2, 1)
    residuals = dtau - G0 * np.einsum("ki,kin->kn", w, A)
    rms = np.sqrt(np.mean(residuals**2, axis=1))
    check_finite_result(mass=mass, com_ee=com_ee, cov=cov, residual_rms=rms)
    return ComEstimateBatch(
        com_ee=com_ee,
        mass=mass,
        weight=mass * G0,
        unobservable_ee=-R[:, 2],
        cov=cov,
        residual_rms=rms,
        condition_number=np.sqrt(lam[:, 2] / lam[:, 0]),
    )
