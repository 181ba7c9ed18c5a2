"""Payload mass and CoM from joint torques before/after grasping, at one or several poses.

The model (see ``regressor``) is linear in theta = (m, m*c_ee): dtau = Y(q) theta. Writing
the unknowns in the ee frame lets k static poses stack into one (k*n, 4) problem.

Observability (threshold ``rcond``, relative to the largest singular value of Y):
- one pose: the CoM component along gravity never changes the torques; the estimate is the
  solution whose CoM has no component along gravity (in the ee frame), and
  ``unobservable_ee`` is the gravity direction in the ee frame;
- several poses: if the smallest singular value of Y exceeds ``rcond`` times the largest,
  the full 3-D CoM is estimated (``unobservable_ee`` None); if exactly one direction is
  lost and it is a pure CoM direction (the wrist orientation never changed relative to
  gravity), it is treated as for one pose; anything else leaves the mass unobservable and
  raises ``UnobservableError``.

Uncertainty: with iid Gaussian noise of std sigma on each torque reading, each difference
has variance 2 sigma^2, the least-squares theta is unbiased with covariance
2 sigma^2 (Y^T Y)^-1, which is the inverse Fisher information: for a linear-Gaussian model
least squares is the ML estimator, the BLUE, and attains the Cramer-Rao bound. (m, c_ee) is
a smooth function of theta (c = (m c)/m): its covariance ``cov`` is propagated by the delta
method, G cov_theta G^T with G = d(m, c)/d(theta); this equals the CRB of (m, c_ee) (ML is
invariant under reparametrisation) and is exact to first order in the noise.
"""

from __future__ import annotations

import math

import numpy as np

from comgrasp_pin.errors import InvalidInputError, UnobservableError
from comgrasp_pin.estimation.estimate import ComEstimate, assemble_estimate
from comgrasp_pin.estimation.ipopt import solve_lsq
from comgrasp_pin.estimation.regressor import (
    gravity_in_ee,
    one_pose_basis,
    perpendicular_basis,
    stacked_regressor,
)
from comgrasp_pin.robot import RobotModel

METHODS = ("lstsq", "ipopt")
RCOND = 1e-6
"""Singular values of Y below RCOND * (largest) count as unobservable directions."""
MASS_NULL_TOL = 1e-3
"""A lost direction whose mass component exceeds this (unit null vector) makes m unobservable."""


def estimate_com(
    robot: RobotModel,
    q: np.ndarray,
    tau_before: np.ndarray,
    tau_after: np.ndarray,
    method: str = "lstsq",
    torque_std: float | np.ndarray | None = None,
    rcond: float = RCOND,
) -> ComEstimate:
    """Estimate the held payload's mass and CoM (ee frame) from static joint torques.

    An estimated mass at or below 3 standard deviations (with torque_std; MIN_MASS_KG = 1 g
    without) is refused as an empty gripper rather than returned.

    Args:
        robot: the arm.
        q: (n,) one static configuration (rad / m) or (k, n) for k poses.
        tau_before: same shape as q, joint torques without the object (N m).
        tau_after: same shape as q, joint torques holding the object (N m).
        method: "lstsq" (closed form) or "ipopt" (CasADi + IPOPT, solver built once).
        torque_std: std of each torque reading (N m), scalar or (n,) per joint; enables
            ``cov`` and (per-joint) weighted least squares.
        rcond: relative singular-value threshold deciding observability.

    Raises:
        InvalidInputError, UnobservableError, EmptyGripperError, SolverError (all ValueError).
    """
    if method not in METHODS:
        raise InvalidInputError(f"unknown method {method!r}; valid methods are {METHODS}")
    if not 0.0 < rcond < 1.0:
        raise InvalidInputError(f"rcond must be in (0, 1), got {rcond}")
    Q, dtau, sigma = validate_inputs(robot, q, tau_before, tau_after, torque_std)
    return _general(robot, Q, dtau, sigma, method, rcond)


def _general(
    robot: RobotModel,
    Q: np.ndarray,
    dtau: np.ndarray,
    sigma: np.ndarray | None,
    method: str,
    rcond: float,
) -> ComEstimate:
    k, n = Q.shape
    Y, T = stacked_regressor(robot, Q)
    if k == 1:
        u, B = gravity_in_ee(T[0, :3, :3]), one_pose_basis(T[0, :3, :3])
    else:
        U_full, s_full, Vt = np.linalg.svd(Y, full_matrices=False)
        rank = int(np.sum(s_full > rcond * s_full[0])) if s_full[0] > 0 else 0
        if rank == 4:
            u, B = None, np.eye(4)  # Y @ B is Y: its SVD is reused below
        elif rank == 3 and abs(Vt[3, 0]) <= MASS_NULL_TOL:
            u = Vt[3, 1:] / np.linalg.norm(Vt[3, 1:])
            u = u if u @ gravity_in_ee(T[0, :3, :3]) >= 0 else -u
            B = np.zeros((4, 3))
            B[0, 0] = 1.0
            B[1:, 1:] = perpendicular_basis(u)
        else:
            raise UnobservableError(
                f"the {k} poses leave the mass unobservable: singular values of the "
                f"regression {np.array2string(s_full, precision=3)} (rank {rank} of 4 at "
                f"rcond={rcond}); use poses where the joints bear the payload's weight"
            )
    Yr = Y @ B
    if k > 1 and rank == 4:
        U, S, Vt_r = U_full, s_full, Vt
    else:
        U, S, Vt_r = np.linalg.svd(Yr, full_matrices=False)
    if not S[-1] > rcond * S[0]:
        raise UnobservableError(
            "the pose set leaves the mass unobservable: singular values of the regression "
            f"for (mass, CoM across gravity) are {np.array2string(S, precision=3)}, below "
            f"rcond={rcond}; no joint torque separates mass from CoM offset at this q"
        )
    sv = np.append(S, 0.0) if k == 1 else s_full
    b = dtau.ravel()
    rows_w = None if sigma is None else np.tile(1.0 / (math.sqrt(2.0) * sigma), k)
    if rows_w is not None and np.ptp(rows_w) > 0:  # per-joint sigma: weighted least squares
        U, S_w, Vt_r = np.linalg.svd(Yr * rows_w[:, None], full_matrices=False)
        Ysolve, bsolve = Yr * rows_w[:, None], b * rows_w
        cov_w = (Vt_r.T / S_w**2) @ Vt_r
    else:
        S_w = S
        Ysolve, bsolve = Yr, b
        cov_w = None if rows_w is None else (Vt_r.T / (S * rows_w[0]) ** 2) @ Vt_r
    if method == "ipopt":
        res = solve_lsq(Ysolve, bsolve)
        w, status, iters = res.w, res.return_status, res.iterations
    else:
        w = Vt_r.T @ ((U.T @ bsolve) / S_w)
        status, iters = "closed_form", 0
    theta = B @ w
    residuals = (b - Y @ theta).reshape(k, n)
    return assemble_estimate(
        theta, B, cov_w, u, residuals, sv, S[0] / S[-1], method, status, iters, T
    )


def validate_inputs(
    robot: RobotModel,
    q: np.ndarray,
    tau_before: np.ndarray,
    tau_after: np.ndarray,
    torque_std: float | np.ndarray | None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """(Q (k, n), dtau (k, n), sigma (n,) or None) from the raw inputs, or a clear error."""
    n = robot.nq
    arrays = {}
    for name, value in (("q", q), ("tau_before", tau_before), ("tau_after", tau_after)):
        try:
            arrays[name] = np.asarray(value, dtype=float)
        except (TypeError, ValueError) as exc:
            raise InvalidInputError(f"{name} is not a numeric array: {exc}") from None
    shape = arrays["q"].shape
    if arrays["q"].ndim not in (1, 2) or shape[-1] != n or (len(shape) == 2 and shape[0] < 1):
        raise InvalidInputError(
            f"q must have shape ({n},) for one pose or (k, {n}) for k >= 1 poses (the robot "
            f"has {n} joints), got {shape}"
        )
    for name, a in arrays.items():
        if a.shape != shape:
            raise InvalidInputError(f"{name} has shape {a.shape} but q has shape {shape}")
        bad = ~np.isfinite(a)
        if bad.any():
            where = np.argwhere(bad.reshape(-1, n)).tolist()
            raise InvalidInputError(f"{name} contains NaN or inf at (pose, joint) {where}")
    sigma = None
    if torque_std is not None:
        try:
            sigma = np.broadcast_to(np.asarray(torque_std, dtype=float), (n,)).copy()
        except (TypeError, ValueError):
            raise InvalidInputError(
                f"torque_std must be a scalar or shape ({n},), got {np.shape(torque_std)}"
            ) from None
        if not np.all(np.isfinite(sigma) & (sigma > 0)):
            raise InvalidInputError(f"torque_std must be finite and > 0, got {torque_std}")
    Q = arrays["q"].reshape(-1, n)
    dtau = (arrays["tau_after"] - arrays["tau_before"]).reshape(-1, n)
    if not np.all(np.isfinite(dtau)):
        raise InvalidInputError("tau_after - tau_before overflows (values too large)")
    return Q, dtau, sigma
