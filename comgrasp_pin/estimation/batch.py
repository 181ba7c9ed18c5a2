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
from comgrasp_pin.estimation import closed_form, one_pose
from comgrasp_pin.estimation.estimate import (
    MASS_SIGMAS,
    MIN_MASS_KG,
    check_finite_result,
    singular_is_unobservable,
)
from comgrasp_pin.estimation.estimator import RCOND
from comgrasp_pin.estimation.inputs import check_rcond, validate_inputs
from comgrasp_pin.estimation.regressor import G0
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
        ComGraspError: its subclasses (a ValueError), naming the offending grasps.
    """
    rcond = check_rcond(rcond)
    if np.ndim(q) != 2:
        raise InvalidInputError(f"q must be (N, {robot.nq}) for a batch, got {np.shape(q)}")
    Q, dtau, sigma = validate_inputs(robot, q, tau_before, tau_after, torque_std)
    count, n = Q.shape
    model, data, fid = robot.model, robot.data, robot.ee_frame_id
    oMf, jacobian = data.oMf, pin.computeFrameJacobian
    # (``rotation`` would be a view into ``data``, overwritten by the next pose)
    frames = [(jacobian(model, data, q_i, fid, _WORLD_ALIGNED), oMf[fid].homogeneous) for q_i in Q]
    J = np.array([f[0] for f in frames])  # (N, 6, n) world-aligned ee Jacobians
    R = np.array([f[1] for f in frames])[:, :3, :3]  # (N, 3, 3) R_world_ee
    A = J[:, 2:5]  # rows J_lin_z, J_ang_x, J_ang_y: Y_r = G0 A^T
    Aw = A if sigma is None else A / (sigma * sigma)  # A W with W = diag(1 / sigma^2)
    N = Aw @ A.transpose(0, 2, 1)
    rhs = (Aw @ dtau[:, :, None])[:, :, 0]
    lam, N_inv = _eigenvalues_and_inverse(N)
    # ill-conditioned: the closed forms lose digits, and the observability decision is near
    # and (near) double eigenvalues: the trigonometric formula loses digits (one_pose)
    floor = max(closed_form.MIN_EIGEN_RATIO, 4 * rcond**2) * lam[:, 2]
    gap = np.minimum(lam[:, 2] - lam[:, 1], lam[:, 1] - lam[:, 0])
    hard = np.flatnonzero(~((lam[:, 0] > floor) & (gap >= one_pose.MIN_GAP * lam[:, 2])))
    if hard.size:
        lam[hard] = np.linalg.eigvalsh(N[hard])
    bad = np.flatnonzero(~(lam[:, 0] > rcond * rcond * lam[:, 2]))
    if bad.size:
        raise UnobservableError(
            f"grasps {bad[:10].tolist()} (of {bad.size}) leave the mass unobservable: their "
            f"regression is singular at rcond={rcond}"
        )
    if hard.size:
        N_inv[hard] = np.linalg.inv(N[hard])
    w = (N_inv @ rhs[:, :, None])[:, :, 0] / G0  # (m, m c_wy, -m c_wx)
    mass = w[:, 0]
    var_scale = 2.0 / G0**2  # cov(w) = 2 N^-1 / G0^2: each difference is of two readings
    if sigma is not None:
        threshold = MASS_SIGMAS * np.sqrt(var_scale * N_inv[:, 0, 0])
    else:
        threshold = np.full(count, MIN_MASS_KG)
    empty = np.flatnonzero(~(mass > threshold))
    if empty.size:
        raise EmptyGripperError(
            f"grasps {empty[:10].tolist()} (of {empty.size}) have a payload mass not "
            f"measurably above zero (e.g. {mass[empty[0]]:.3g} kg vs threshold "
            f"{threshold[empty[0]]:.3g} kg): empty gripper?"
        )
    inv_mass = (1.0 / mass)[:, None]
    # theta = B w with one_pose_basis B = [[1, 0, 0], [0, R[1], -R[0]]] (as columns)
    com_ee = (w[:, 1, None] * R[:, 1] - w[:, 2, None] * R[:, 0]) * inv_mass
    cov = None
    if sigma is not None:  # the delta method: D = d(m, c_ee)/dw, cov = D cov(w) D^T
        D = np.zeros((count, 4, 3))
        D[:, 0, 0] = 1.0
        D[:, 1:, 0] = -com_ee * inv_mass
        D[:, 1:, 1] = R[:, 1] * inv_mass
        D[:, 1:, 2] = -R[:, 0] * inv_mass
        cov = var_scale * (D @ N_inv @ D.transpose(0, 2, 1))
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


def _eigenvalues_and_inverse(N: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Ascending eigenvalues (count, 3) and inverses (count, 3, 3) of symmetric 3x3 matrices.

    In closed form (the trigonometric formula and the adjugate, as ``one_pose``) on whole
    arrays: a tenth of LAPACK's time on 10 000 small matrices, as accurate where the matrix
    is well conditioned; the caller redoes the others by LAPACK.
    """
    a, b, c = N[:, 0, 0], N[:, 0, 1], N[:, 0, 2]
    d, e, f = N[:, 1, 1], N[:, 1, 2], N[:, 2, 2]
    p1 = b * b + c * c + e * e
    q3 = (a + d + f) / 3.0
    p = np.sqrt(((a - q3) ** 2 + (d - q3) ** 2 + (f - q3) ** 2 + 2.0 * p1) / 6.0)
    lam = np.empty((len(N), 3))
    adj = np.empty_like(N)
    with np.errstate(divide="ignore", invalid="ignore"):  # singular or a multiple of I: redone
        x, y, z, bb, cc, ee = (a - q3) / p, (d - q3) / p, (f - q3) / p, b / p, c / p, e / p
        half_det = 0.5 * (x * (y * z - ee * ee) - bb * (bb * z - ee * cc) + cc * (bb * ee - y * cc))
        phi = np.arccos(np.clip(half_det, -1.0, 1.0)) / 3.0
        lam[:, 2] = q3 + 2.0 * p * np.cos(phi)
        lam[:, 0] = q3 + 2.0 * p * np.cos(phi + 2.0 * np.pi / 3.0)
        lam[:, 1] = 3.0 * q3 - lam[:, 0] - lam[:, 2]
        adj[:, 0, 0], adj[:, 1, 1], adj[:, 2, 2] = d * f - e * e, a * f - c * c, a * d - b * b
        adj[:, 0, 1] = adj[:, 1, 0] = c * e - b * f
        adj[:, 0, 2] = adj[:, 2, 0] = b * e - c * d
        adj[:, 1, 2] = adj[:, 2, 1] = b * c - a * e
        det = a * adj[:, 0, 0] + b * adj[:, 0, 1] + c * adj[:, 0, 2]
        return lam, adj / det[:, None, None]
