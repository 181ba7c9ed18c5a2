"""The least squares through its normal equations: ``estimate_com``'s fast closed form.

For k poses the regression of the observable unknowns is Yr (k n, p): for one pose
w = (m, m c_wx, m c_wy), the mass and the CoM's horizontal offset in the world (p = 3), for
several theta = (m, m c_ee) itself (p = 4). Its Gram matrix N = Yr^T Yr (p, p) gives all
the estimate needs:

- its eigenvalues are the squared singular values of Yr (observability, condition number);
- its inverse, with Yr^T b, gives the least-squares solution and the covariance
  (2 sigma^2 N^-1, or N_w^-1 with per-joint weights).

The normal equations lose digits as eps * cond^2: where Yr's condition number exceeds
MAX_CONDITION (or the observability threshold ``rcond`` is within a factor 2 of the
smallest singular value), ``estimate`` returns None and the caller takes the SVD path
(``np.linalg.lstsq``), which also decides rank-deficient pose sets. Below it, the results
equal the SVD path's to ~1e-13 relative (tests/test_closed_form.py).

This module is the general form (any k, per-joint weights) and the Gram reduction that
``observability.by_gram`` gives IPOPT. The common cases have leaner copies of the same
algebra: ``one_pose`` (one pose, one std for all joints, 3x3 in Python floats) and
``several_poses`` (several poses, one std); ``estimator.estimate_com`` picks the path.
Every step is one NumPy call on small arrays (0.3-0.7 us each).
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin

from comgrasp_pin.estimation import one_pose
from comgrasp_pin.estimation.estimate import ComEstimate, new_estimate, refuse_empty_gripper
from comgrasp_pin.estimation.regressor import G0
from comgrasp_pin.estimation.small_linalg import eigvalsh, inv
from comgrasp_pin.robot import RobotModel

MAX_CONDITION = 100.0
"""Largest condition number of Yr (weights included) solved through the normal equations:
their relative error eps * cond^2 stays below 1e-12. Good pose sets have 5 to 30."""
NOISE_FLOOR = 1e-6
"""No torque difference is taken as known better than this (N m): the noise estimated from
the residuals of noise-free data is floored here, so its weights stay finite."""

WEIGHT_ROWS = G0 * np.array(
    [[0, 0, 1, 0, 0, 0], [0, 0, 0, 0, -1, 0], [0, 0, 0, 1, 0, 0]], dtype=float
)
"""(3, 6) picks from a world-aligned ee Jacobian (rows linear xyz, angular xyz) the torques
per unit of (m, m c_wx, m c_wy): G0 (J_lin_z, -J_ang_y, J_ang_x). From the regressor
Y = G0 [J_lin_z, J_ang_x R[1] - J_ang_y R[0]] with R[0] . (m c_ee) = m c_wx (world x)."""
_WORLD_ALIGNED = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
_EYE4 = np.eye(4)
_KT_TEMPLATE = np.zeros((6, 5))
_KT_TEMPLATE[2, 0] = 1.0  # the mass: J_lin_z
_KT_TEMPLATE[5, 4] = 1.0  # b, carried in row 5
MIN_EIGEN_RATIO = 1.0 / MAX_CONDITION**2
"""Smallest ratio of the Gram matrix's extreme eigenvalues solved through it."""


def regression(robot: RobotModel, Q: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """([Yr^T; b^T] (p + 1, k n), T_world_ee (k, 4, 4)) at the k configurations ``Q``.

    One pose: Yr (n, 3) of w = (m, m c_wx, m c_wy) is ``WEIGHT_ROWS @ J``^T. Several: Yr
    (k n, 4) of theta, pose i's block the regressor G0 [J_lin_z, J_ang_x R[1] - J_ang_y R[0]].
    The torque differences ``b`` (k n,) ride along as the last row: one product then gives
    the Gram matrix, Yr^T b and b^T b.
    """
    k, n = Q.shape
    model, data, fid = robot.model, robot.data, robot.ee_frame_id
    if k == 1:
        Xb = np.empty((4, n))
        J = pin.computeFrameJacobian(model, data, Q[0], fid, _WORLD_ALIGNED)
        np.matmul(WEIGHT_ROWS, J, out=Xb[:3])
        Xb[3] = b
        return Xb, data.oMf[fid].homogeneous[None]
    jacobian, oMf = pin.computeFrameJacobian, data.oMf
    frames = [(jacobian(model, data, q, fid, _WORLD_ALIGNED), oMf[fid].homogeneous) for q in Q]
    J = np.array([f[0] for f in frames])  # (k, 6, n)
    T = np.array([f[1] for f in frames])
    J[:, 5] = b.reshape(k, n)  # the unused rows J_ang_z carry b
    # Kt_i^T (5, 6) maps J_i to [Yr_i^T / G0; b_i^T]: row 0 J_lin_z, row 1 + j (the CoM's
    # ee coordinate j) R1_j J_ang_x - R0_j J_ang_y; G0 is applied to the Gram matrix after
    Kt = np.empty((k, 6, 5))
    Kt[:] = _KT_TEMPLATE
    Kt[:, 3, 1:4] = T[:, 1, :3]
    np.negative(T[:, 0, :3], out=Kt[:, 4, 1:4])
    Xb = (Kt.transpose(0, 2, 1) @ J).transpose(1, 0, 2).reshape(5, k * n)
    Xb[:4] *= G0
    return Xb, T


def gram_solution(Xb: np.ndarray, sigma: float | np.ndarray | None, rcond: float) -> tuple | None:
    """Least squares of b on Yr through the normal equations, or None.

    Args:
        Xb: (p + 1, rows) [Yr^T; b^T], b the torque differences (N m), pose-major.
        sigma: std of each torque reading: a float, (n,) per joint, or None (the noise is
            then estimated from the residuals where rows > p).
        rcond: the observability threshold on the singular values of Yr.

    Returns:
        (w (p,), N_inv (p, p), var, residuals (rows,), their sum of squares, singular
        values (4,) descending, condition number, noise_std or None), or None where Yr is
        too ill-conditioned for the normal equations (the caller then solves by SVD). The
        covariance of w is var * N_inv (var None: unknown, no more readings than unknowns).
    """
    p1, rows = Xb.shape
    p = p1 - 1
    Xt, b = Xb[:p], Xb[p]
    P = Xb @ Xb.T
    N = P[:p, :p]
    lam = eigvalsh(N)  # ascending: squared singular values of Yr
    low, high = float(lam[0]), float(lam[-1])
    per_joint = sigma if isinstance(sigma, np.ndarray) else None
    floor = max(MIN_EIGEN_RATIO, 4.0 * rcond * rcond)
    if per_joint is not None:  # cond(W Yr) <= cond(Yr) * sigma_max / sigma_min
        spread = float(per_joint.max() / per_joint.min())
        floor = max(MIN_EIGEN_RATIO * spread * spread, 4.0 * rcond * rcond)
    if not low > floor * high:
        return None
    if per_joint is not None:
        row_var = 2.0 * per_joint * per_joint  # of a difference of two readings
        Xw = Xt / np.tile(row_var, rows // len(row_var))  # Yr^T W, W = 1 / var
        N_inv = inv(Xw @ Xt.T)  # the covariance itself
        w = N_inv @ (Xw @ b)
    else:
        N_inv = inv(N)
        w = N_inv @ P[:p, p]
    residuals = b - w @ Xt
    rss = float(residuals @ residuals)
    noise_std = None
    var: float | None
    if per_joint is not None:
        var = 1.0
    elif isinstance(sigma, float):
        var = 2.0 * sigma * sigma  # of a difference of two readings
    elif rows > p:
        noise_std = max(math.sqrt(rss) / math.sqrt(rows - p), NOISE_FLOOR)
        var = noise_std * noise_std
    else:
        var = None
    sv = np.zeros(4)  # padded with 0 for one pose: the direction along gravity
    np.sqrt(lam[::-1], out=sv[:p])
    return w, N_inv, var, residuals, rss, sv, math.sqrt(high / low), noise_std


def estimate(
    robot: RobotModel,
    Q: np.ndarray,
    dtau: np.ndarray,
    sigma: float | np.ndarray | None,
    rcond: float,
) -> ComEstimate | None:
    """``estimate_com(method="lstsq")`` for k poses by the normal equations, or None.

    None where the SVD path must decide (an ill-conditioned or rank-deficient regression).

    Args:
        robot: the arm.
        Q: (k, n) checked configurations.
        dtau: (k, n) torque differences (N m).
        sigma: std of each reading (float, (n,) or None), as ``validate_inputs`` gives it.
        rcond: the observability threshold.

    Raises:
        EmptyGripperError, UnobservableError, InvalidInputError as ``estimate_com``.
    """
    k, n = Q.shape
    if k == 1 and (sigma is None or type(sigma) is float):
        floor = max(MIN_EIGEN_RATIO, 4.0 * rcond * rcond)
        return one_pose.estimate(robot, Q[0], dtau[0], sigma, floor, NOISE_FLOOR)
    Xb, T = regression(robot, Q, dtau.ravel())
    solution = gram_solution(Xb, sigma, rcond)
    if solution is None:
        return None
    w, N_inv, var, residuals, rss, sv, cond, noise_std = solution
    mass = float(w[0])
    refuse_empty_gripper(mass, None if var is None else var * float(N_inv[0, 0]), cond)
    inv_mass = 1.0 / mass
    # the delta method: cov = D (var N_inv) D^T for D = d(m, c_ee)/dw, sqrt(var) folded in D
    r = 1.0 if var is None else math.sqrt(var)
    if k == 1:
        R_xy = T[0, :2, :3].T  # (3, 2): the world's x and y axes in the ee frame
        com = (R_xy @ w[1:]) * inv_mass
        u = T[0, 2, :3] * -1.0  # gravity in the ee frame
        D = np.zeros((4, 3))
        D[1:, 1:] = R_xy * (r * inv_mass)
    else:
        com = w[1:] * inv_mass
        u = None
        D = _EYE4 * (r * inv_mass)
    D[0, 0] = r
    cov = None
    if var is not None:
        D[1:, 0] = com * (-r * inv_mass)
        cov = D @ N_inv @ D.T
    return new_estimate(com, mass, cov, u, residuals.reshape(k, n), math.sqrt(rss / len(residuals)),
                        sv, cond, "lstsq", "closed_form", 0, T, noise_std)  # fmt: skip
