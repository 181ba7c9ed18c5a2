"""The least squares through its normal equations: ``estimate_com``'s fast closed form.

For k poses the regression of the observable unknowns is Yr (k n, p): for one pose
w = (m, m c_wy, -m c_wx) (p = 3, ``regressor.one_pose_basis``), for several theta itself
(p = 4). Its Gram matrix N = Yr^T Yr (p, p) gives everything the estimate needs:

- its eigenvalues are the squared singular values of Yr (observability, condition number);
- its inverse, with Yr^T b, gives the least-squares solution and the covariance
  (2 sigma^2 N^-1, or N_w^-1 with per-joint weights).

The normal equations lose digits as eps * cond^2: where Yr's condition number exceeds
MAX_CONDITION (or where the observability threshold ``rcond`` is within a factor 2 of
the smallest singular value), ``gram_solution`` returns None and the caller takes the SVD
path (``np.linalg.lstsq``), which also decides rank-deficient pose sets. Below it, the
results equal the SVD path's to ~1e-13 relative (tests/test_closed_form.py).
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin

from comgrasp_pin.estimation.estimate import ComEstimate, new_estimate, refuse_empty_gripper
from comgrasp_pin.estimation.regressor import G0, stacked_regressor
from comgrasp_pin.robot import RobotModel

try:  # the gufuncs behind np.linalg.eigvalsh / inv, without its 3 us of argument checks
    from numpy.linalg import _umath_linalg

    _eigvalsh = _umath_linalg.eigvalsh_lo
    _inv = _umath_linalg.inv
except (ImportError, AttributeError):  # pragma: no cover - another NumPy layout
    _eigvalsh, _inv = np.linalg.eigvalsh, np.linalg.inv

MAX_CONDITION = 100.0
"""Largest condition number of Yr (weights included) solved through the normal equations:
their relative error eps * cond^2 stays below 1e-12. Good pose sets have 5 to 30."""
NOISE_FLOOR = 1e-6
"""No torque difference is taken as known better than this (N m): the noise estimated from
the residuals of noise-free data is floored here, so its weights stay finite."""

_WORLD_ALIGNED = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED


def one_pose_regression(robot: RobotModel, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(Yr^T (3, n), T_world_ee (1, 4, 4)) for w = (m, m c_wy, -m c_wx) at ``q`` (n,).

    Yr = Y B with ``one_pose_basis``: the columns are G0 times the Jacobian's rows
    (linear z, angular x, angular y), world-aligned at the ee.
    """
    fid = robot.ee_frame_id
    J = pin.computeFrameJacobian(robot.model, robot.data, q, fid, _WORLD_ALIGNED)
    return G0 * J[2:5], robot.data.oMf[fid].homogeneous[None]


def gram_solution(
    Xt: np.ndarray, b: np.ndarray, sigma: float | np.ndarray | None, rcond: float
) -> tuple | None:
    """Least squares of b (rows,) on Yr = Xt^T through the normal equations, or None.

    Args:
        Xt: (p, rows) the regression, transposed.
        b: (rows,) torque differences (N m), pose-major.
        sigma: std of each torque reading: a float, (n,) per joint, or None (the noise is
            then estimated from the residuals where rows > p).
        rcond: the observability threshold on the singular values of Yr.

    Returns:
        (w (p,), cov_w (p, p) or None, residuals (rows,), singular values (4,) descending,
        condition number, noise_std or None), or None where Yr is too ill-conditioned for
        the normal equations (the caller then solves by SVD).
    """
    p, rows = Xt.shape
    N = Xt @ Xt.T
    lam = _eigvalsh(N)  # ascending: squared singular values of Yr
    low, high = float(lam[0]), float(lam[-1])
    weighted = sigma is not None and not isinstance(sigma, float)
    # per joint weights: cond(Yr_w) <= cond(Yr) * sigma_max / sigma_min
    spread = float(sigma.max() / sigma.min()) if weighted else 1.0
    if not low > max(spread * spread / MAX_CONDITION**2, 4.0 * rcond * rcond) * high:
        return None
    if weighted:
        Xw = Xt * np.tile(0.5 / (sigma * sigma), rows // len(sigma))  # Yr^T W, W = 1/var
        cov_w = _inv(Xw @ Xt.T)
        w = cov_w @ (Xw @ b)
    else:
        N_inv = _inv(N)
        w = N_inv @ (Xt @ b)
    residuals = b - w @ Xt
    noise_std = None
    if sigma is None:
        dof = rows - p
        cov_w = None
        if dof > 0:
            rss = float(residuals @ residuals)
            noise_std = max(math.sqrt(rss) / math.sqrt(dof), NOISE_FLOOR)
            cov_w = (noise_std * noise_std) * N_inv
    elif not weighted:
        cov_w = (2.0 * sigma * sigma) * N_inv
    sv = np.zeros(4)  # padded with 0 for one pose: the direction along gravity
    sv[:p] = np.sqrt(lam[::-1])
    return w, cov_w, residuals, sv, math.sqrt(high / low), noise_std


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
    if k == 1:
        Xt, T = one_pose_regression(robot, Q[0])
    else:
        Y, T = stacked_regressor(robot, Q)
        Xt = Y.T
    solution = gram_solution(Xt, dtau.ravel(), sigma, rcond)
    if solution is None:
        return None
    w, cov_w, residuals, sv, cond, noise_std = solution
    mass = float(w[0])
    refuse_empty_gripper(mass, None if cov_w is None else float(cov_w[0, 0]), cond)
    # theta = B w and the delta method's D = d(m, c)/dw = G B, G = d(m, c)/dtheta
    D = np.zeros((4, len(w)))
    D[0, 0] = 1.0
    if k == 1:
        R = T[0, :3, :3]
        B_com = np.empty((3, 2))  # the CoM rows of one_pose_basis
        B_com[:, 0] = R[1]
        B_com[:, 1] = -R[0]
        com = (B_com @ w[1:]) / mass
        D[1:, 1:] = B_com / mass
        u = -R[2]  # gravity in the ee frame
    else:
        com = w[1:] / mass
        D[1:, 1:] = np.eye(3) / mass
        u = None
    cov = None
    if cov_w is not None:
        D[1:, 0] = com / -mass
        cov = D @ cov_w @ D.T
    return new_estimate(com, mass, cov, u, residuals.reshape(k, n), sv, cond, "lstsq",
                        "closed_form", 0, T, noise_std)  # fmt: skip
