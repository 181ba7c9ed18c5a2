"""Payload mass and CoM from joint torques before/after grasping, at one or several poses.

The model (see ``regressor``) is linear in theta = (m, m*c_ee): dtau = Y(q) theta. Writing
the unknowns in the ee frame lets k static poses stack into one (k*n, 4) problem.

Observability (threshold ``rcond``, relative to the largest singular value of Y):
- one pose: the CoM component along gravity never changes the torques; least squares gives
  the solution whose CoM has no component along gravity (in the ee frame), and
  ``unobservable_ee`` is the gravity direction in the ee frame;
- several poses: if the smallest singular value of Y exceeds ``rcond`` times the largest,
  the full 3-D CoM is estimated (``unobservable_ee`` None); if exactly one direction is
  lost and it is a pure CoM direction (the wrist orientation never changed relative to
  gravity), it is treated as for one pose; anything else leaves the mass unobservable and
  raises ``UnobservableError``;
- with an ``AxisPrior`` (IPOPT) the component the torques cannot see is the prior's: the
  CoM is fully estimated unless the prior's axis runs along the unseen direction.

Uncertainty: with iid Gaussian noise of std sigma on each torque reading, each difference
has variance 2 sigma^2 and least squares theta has covariance 2 sigma^2 (Y^T Y)^-1, the
inverse Fisher information (the Cramer-Rao bound); (m, c_ee) = (theta_0, theta_1:/theta_0)
gets it by the delta method. Without torque_std the noise is estimated from the residuals
where readings outnumber unknowns. With IPOPT the covariance is the inverse Hessian of the
negative log posterior at the optimum (Laplace), prior and robust loss included.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from comgrasp_pin.errors import InvalidInputError, UnobservableError
from comgrasp_pin.estimation import closed_form, ipopt
from comgrasp_pin.estimation.closed_form import NOISE_FLOOR
from comgrasp_pin.estimation.estimate import (
    ComEstimate,
    assemble_estimate,
    delta_method,
)
from comgrasp_pin.estimation.inputs import check_options, validate_inputs
from comgrasp_pin.estimation.prior import AxisPrior
from comgrasp_pin.estimation.regressor import (
    gravity_in_ee,
    one_pose_basis,
    perpendicular_basis,
    stacked_regressor,
)
from comgrasp_pin.estimation.rod_axis import MIN_AXIS_GRAVITY_ANGLE
from comgrasp_pin.robot import RobotModel

RCOND = 1e-6
"""Singular values of Y below RCOND * (largest) count as unobservable directions."""
MASS_NULL_TOL = 1e-3
"""A lost direction whose mass component exceeds this (unit null vector) makes m unobservable."""


@dataclass(frozen=True)
class _Reduced:
    """The torque regression and what of theta it observes: theta = B w.

    Y (rows, 4), T (k, 4, 4), B (4, p), u the unobservable direction (ee) or None, sv the
    singular values of Y (padded with 0 for one pose), cond the condition number of Y B.
    """

    Y: np.ndarray
    T: np.ndarray
    B: np.ndarray
    u: np.ndarray | None
    sv: np.ndarray
    cond: float


def estimate_com(
    robot: RobotModel,
    q: np.ndarray,
    tau_before: np.ndarray,
    tau_after: np.ndarray,
    method: str = "lstsq",
    torque_std: float | np.ndarray | None = None,
    rcond: float = RCOND,
    loss: str = "l2",
    huber_delta: float = 3.0,
    com_prior: AxisPrior | None = None,
    payload_motion_ee: np.ndarray | None = None,
) -> ComEstimate:
    """Estimate the held payload's mass and CoM (ee frame) from static joint torques.

    An estimated mass at or below 3 standard deviations (1 g without any covariance) is
    refused as an empty gripper, or as unobservable where the poses are near singular.

    Args:
        robot: the arm.
        q: (n,) one static configuration (rad / m) or (k, n) for k poses.
        tau_before: same shape as q, joint torques without the object (N m).
        tau_after: same shape as q, joint torques holding the object (N m).
        method: "lstsq" (closed form) or "ipopt" (CasADi + IPOPT, problem built once).
        torque_std: std of each torque reading (N m), scalar or (n,) per joint; weights the
            least squares and sets ``cov``.
        rcond: relative singular-value threshold deciding observability.
        loss: "l2" or "huber" (ipopt; needs torque_std): a pseudo-Huber loss that barely
            follows a bump or a spike on one reading.
        huber_delta: the Huber threshold, in standard deviations of a torque difference.
        com_prior: an ``AxisPrior`` (ipopt): the CoM near the rod's axis.
        payload_motion_ee: (k, 4, 4) rigid motions in the ee frame that carry the payload
            from where it sat at the first pose to where it sat at each pose (a held object
            that shifted or turned in the jaws; the first is the identity), or None (it
            stayed put). The CoM is estimated where it was at the first pose.

    Raises:
        InvalidInputError, UnobservableError, EmptyGripperError, SolverError (all
        ComGraspError, a ValueError).
    """
    check_options(method, rcond, loss, huber_delta, com_prior, torque_std)
    Q, dtau, sigma = validate_inputs(robot, q, tau_before, tau_after, torque_std)
    try:
        if method == "lstsq" and payload_motion_ee is None:
            est = closed_form.estimate(robot, Q, dtau, sigma, rcond)
            if est is not None:
                return est
        return _estimate(robot, Q, dtau, sigma, method, rcond, loss, huber_delta, com_prior,
                         payload_motion_ee)  # fmt: skip
    except np.linalg.LinAlgError as exc:
        raise UnobservableError(
            f"the regression is numerically singular ({exc}): the poses do not determine the "
            "estimate (a larger rcond refuses such pose sets up front)"
        ) from None


def _estimate(robot, Q, dtau, sigma, method, rcond, loss, huber_delta, com_prior, motion):
    """The general path: SVD observability and ``np.linalg.lstsq`` (any pose set), IPOPT."""
    red = _reduce(robot, Q, rcond, _motion_maps(motion, len(Q)))
    k, n = Q.shape
    b = dtau.ravel()
    Yr = red.Y @ red.B
    # Row weights: 1 / std of each torque difference, given or estimated from the residuals.
    noise_std = None
    if sigma is not None:
        rows_w = np.tile(1.0 / (math.sqrt(2.0) * np.broadcast_to(sigma, (n,))), k)
    else:
        w_plain = np.linalg.lstsq(Yr, b, rcond=None)[0]
        dof = len(b) - Yr.shape[1]
        rows_w = None
        if dof > 0:
            noise_std = max(float(np.linalg.norm(b - Yr @ w_plain)) / math.sqrt(dof), NOISE_FLOOR)
            rows_w = np.full(len(b), 1.0 / noise_std)
    weights = np.ones(len(b)) if rows_w is None else rows_w
    w_ls = np.linalg.lstsq(Yr * weights[:, None], b * weights, rcond=None)[0]
    if method == "lstsq":
        cov = None
        if rows_w is not None:
            Yw = Yr * rows_w[:, None]
            cov = delta_method(red.B @ w_ls, red.B @ np.linalg.inv(Yw.T @ Yw) @ red.B.T)
        theta = red.B @ w_ls
        return _finish(red, *_split(theta), cov, red.u, b, theta, k, n,
                       "lstsq", "closed_form", 0, noise_std)  # fmt: skip
    if com_prior is None:
        res = ipopt.solve(Yr, b, weights, w_ls, loss, huber_delta)
        theta = red.B @ res.x
        cov = None
        if rows_w is not None:
            cov = delta_method(theta, red.B @ _inverse(res.hessian) @ red.B.T)
        return _finish(red, *_split(theta), cov, red.u, b, theta, k, n,
                       "ipopt", res.return_status, res.iterations, noise_std)  # fmt: skip
    if rows_w is None:
        raise InvalidInputError(
            "a com_prior needs torque_std when the readings do not outnumber the unknowns "
            "(the noise cannot be estimated from the residuals)"
        )
    return _with_prior(red, b, rows_w, w_ls, loss, huber_delta, com_prior, k, n, noise_std)


def _with_prior(red, b, rows_w, w_ls, loss, delta, prior: AxisPrior, k, n, noise_std):
    """The MAP estimate over (m, c_ee) with the axis prior.

    Warm-started from the closed form, moved along the unobservable direction to the point
    nearest the prior's axis.
    """
    theta0 = red.B @ w_ls
    m0, c0 = _split(theta0)  # m0 = 0: refused after the solve
    if red.u is not None:
        cos_angle = abs(float(prior.direction_ee @ red.u))
        if cos_angle > math.cos(MIN_AXIS_GRAVITY_ANGLE):
            raise UnobservableError(
                f"the prior's axis is {math.degrees(math.acos(min(cos_angle, 1.0))):.2f} deg "
                f"from the direction the torques cannot see (minimum "
                f"{math.degrees(MIN_AXIS_GRAVITY_ANGLE):.2f} deg): it cannot settle the CoM "
                "along it; measure at a pose where the rod is not vertical, or at two poses"
            )
        P = prior.across()
        Pu = P @ red.u
        c0 = c0 - red.u * float(Pu @ (P @ (c0 - prior.point_ee))) / float(Pu @ Pu)
    res = ipopt.solve(red.Y, b, rows_w, np.r_[m0, c0], loss, delta, prior)
    m, com = res.x[0], res.x[1:]
    theta = np.r_[m, m * com]
    return _finish(red, m, com, _inverse(res.hessian), None, b, theta, k, n, "ipopt",
                   res.return_status, res.iterations, noise_std)  # fmt: skip


def _split(theta: np.ndarray) -> tuple[float, np.ndarray]:
    """(m, c) from theta = (m, m c); c is NaN for m = 0 (refused as an empty gripper)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        return float(theta[0]), theta[1:] / theta[0]


def _finish(red, m, com, cov, u, b, theta, k, n, method, status, iters, noise_std):
    residuals = (b - red.Y @ theta).reshape(k, n)
    return assemble_estimate(m, com, cov, u, residuals, red.sv, red.cond, method, status,
                             iters, red.T, noise_std)  # fmt: skip


def _inverse(H: np.ndarray) -> np.ndarray:
    """The covariance from the posterior's Hessian; UnobservableError where it is singular."""
    eig = np.linalg.eigvalsh(0.5 * (H + H.T))
    if not eig[0] > RCOND * RCOND * eig[-1]:
        raise UnobservableError(
            f"the posterior is flat in some direction (Hessian eigenvalues "
            f"{np.array2string(eig, precision=3)}): the data and the prior do not determine "
            "the estimate"
        )
    return np.linalg.inv(H)


def _motion_maps(motion: np.ndarray | None, k: int) -> np.ndarray | None:
    """(k, 4, 4) maps A_i: theta at pose i = A_i theta (theta at the first pose).

    From the payload's rigid motions M_i = (R_i, p_i): m c_i = R_i (m c) + m p_i.
    """
    if motion is None:
        return None
    M = np.asarray(motion, dtype=float)
    if M.shape != (k, 4, 4) or not np.all(np.isfinite(M)):
        raise InvalidInputError(
            f"payload_motion_ee must be ({k}, 4, 4) finite transforms (one per pose), got "
            f"shape {M.shape}"
        )
    A = np.zeros((k, 4, 4))
    A[:, 0, 0] = 1.0
    A[:, 1:, 0] = M[:, :3, 3]
    A[:, 1:, 1:] = M[:, :3, :3]
    return A


def _reduce(
    robot: RobotModel, Q: np.ndarray, rcond: float, maps: np.ndarray | None = None
) -> _Reduced:
    """The regression and the observable combination of theta, or UnobservableError."""
    k = len(Q)
    Y, T = stacked_regressor(robot, Q)
    if maps is not None:
        n = Q.shape[1]
        Y = np.concatenate([Y[i * n : (i + 1) * n] @ maps[i] for i in range(k)])
    if k == 1:
        u, B = gravity_in_ee(T[0, :3, :3]), one_pose_basis(T[0, :3, :3])
        s_full = None
    else:
        _, s_full, Vt = np.linalg.svd(Y, full_matrices=False)
        rank = int(np.sum(s_full > rcond * s_full[0])) if s_full[0] > 0 else 0
        if rank == 4:
            u, B = None, np.eye(4)
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
    S = np.linalg.svd(Y @ B, compute_uv=False)
    if not S[-1] > rcond * S[0]:
        raise UnobservableError(
            "the pose set leaves the mass unobservable: singular values of the regression "
            f"for (mass, CoM across gravity) are {np.array2string(S, precision=3)}, below "
            f"rcond={rcond}; no joint torque separates mass from CoM offset at this q"
        )
    sv = np.append(S, 0.0) if s_full is None else s_full
    return _Reduced(Y, T, B, u, sv, float(S[0] / S[-1]))
