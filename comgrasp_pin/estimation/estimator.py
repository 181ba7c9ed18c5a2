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

Paths (the same results to ~1e-12, tests/test_closed_form.py): the closed form by the
normal equations where the regression is well conditioned (``one_pose``, ``several_poses``,
``closed_form`` for per-joint weights), else by SVD (``_estimate`` with
``observability.by_svd``); IPOPT after the Gram reduction (``observability.by_gram``) or,
one pose with a prior, ``map_one_pose``.
"""

from __future__ import annotations

import math

import numpy as np

from comgrasp_pin.errors import InvalidInputError, UnobservableError
from comgrasp_pin.estimation import (
    closed_form,
    ipopt,
    map_one_pose,
    observability,
    one_pose,
    several_poses,
)
from comgrasp_pin.estimation.closed_form import NOISE_FLOOR
from comgrasp_pin.estimation.estimate import (
    ComEstimate,
    delta_method,
    new_estimate,
    refuse_empty_gripper,
)
from comgrasp_pin.estimation.inputs import check_arrays, check_dtau_cov, check_options
from comgrasp_pin.estimation.prior import AxisPrior
from comgrasp_pin.estimation.rod_axis import MIN_AXIS_GRAVITY_ANGLE
from comgrasp_pin.robot import RobotModel

RCOND = 1e-6
"""Singular values of Y below RCOND * (largest) count as unobservable directions."""


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
    dtau_cov: np.ndarray | None = None,
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
        dtau_cov: (k n, k n) covariance of the stacked torque differences tau_after -
            tau_before (N m^2, pose-major: pose 0's n joints first), in place of
            ``torque_std``: readings whose errors are correlated across poses (a torque
            sensor's drift shared by windows that overlap in time) are then weighted by
            generalised least squares, and ``cov`` accounts for the correlation.

    Raises:
        InvalidInputError: an argument has the wrong shape, type or value.
        UnobservableError: the data cannot determine the mass.
        EmptyGripperError: the mass is not measurably above zero: nothing is held.
        SolverError: IPOPT failed (``return_status`` carries its status).

    All four are ``ComGraspError``, a ``ValueError``.
    """
    check_options(method, rcond, loss, huber_delta, com_prior, torque_std)
    q_arr, dtau, sigma = check_arrays(robot, q, tau_before, tau_after, torque_std)
    n = q_arr.shape[-1]
    chol = None if dtau_cov is None else check_dtau_cov(dtau_cov, q_arr.size, torque_std)
    try:
        if chol is not None:
            Q, dtau_k = q_arr.reshape(-1, n), dtau.reshape(-1, n)
            return _estimate(robot, Q, dtau_k, None, method, rcond, loss, huber_delta,
                             com_prior, payload_motion_ee, chol)  # fmt: skip
        if method == "lstsq" and payload_motion_ee is None:
            # the normal equations where well conditioned (None: the SVD path decides)
            floor = max(closed_form.MIN_EIGEN_RATIO, 4.0 * rcond * rcond)
            if isinstance(sigma, np.ndarray):  # per-joint weights
                Q, dtau_k = q_arr.reshape(-1, n), dtau.reshape(-1, n)
                est = closed_form.estimate(robot, Q, dtau_k, sigma, rcond)
            elif q_arr.ndim == 1:
                est = one_pose.estimate(robot, q_arr, dtau, sigma, floor, NOISE_FLOOR)
            elif len(q_arr) == 1:
                est = one_pose.estimate(robot, q_arr[0], dtau[0], sigma, floor, NOISE_FLOOR)
            else:
                est = several_poses.estimate(robot, q_arr, dtau, sigma, floor, NOISE_FLOOR)
            if est is not None:
                return est
        elif com_prior is not None and payload_motion_ee is None and q_arr.ndim == 1:
            if not isinstance(sigma, np.ndarray):  # the MAP estimate at one pose, lean
                floor = max(closed_form.MIN_EIGEN_RATIO, 4.0 * rcond * rcond)
                est = map_one_pose.estimate(robot, q_arr, dtau, sigma, floor, NOISE_FLOOR, loss,
                                            huber_delta, com_prior)  # fmt: skip
                if est is not None:
                    return est
        return _estimate(robot, q_arr.reshape(-1, n), dtau.reshape(-1, n), sigma, method, rcond,
                         loss, huber_delta, com_prior, payload_motion_ee)  # fmt: skip
    except np.linalg.LinAlgError as exc:
        raise UnobservableError(
            f"the regression is numerically singular ({exc}): the poses do not determine the "
            "estimate (a larger rcond refuses such pose sets up front)"
        ) from None


def _estimate(robot, Q, dtau, sigma, method, rcond, loss, huber_delta, com_prior, motion,
              chol=None):  # fmt: skip
    """The general path: any pose set (SVD observability, ``np.linalg.lstsq``) and IPOPT.

    Well-conditioned pose sets without payload motion are reduced through the Gram matrix
    (``observability.by_gram``), and their uniformly weighted least squares solved by it.
    ``chol``: the Cholesky factor L of the differences' covariance (``dtau_cov``): the
    problem is then whitened (L^-1 Y, L^-1 b; generalised least squares) and solved with
    unit weights.
    """
    k, n = Q.shape
    b = dtau.ravel()
    red = None if motion is not None or chol is not None else observability.by_gram(
        robot, Q, b, rcond)  # fmt: skip
    if red is None:
        red = observability.by_svd(robot, Q, rcond, observability.motion_maps(motion, k))
    if chol is not None:
        return _whitened(red, b, chol, method, loss, huber_delta, com_prior, k, n)
    Yr = red.Yr
    uniform = not isinstance(sigma, np.ndarray)
    if red.gram_inv is not None and uniform:  # uniform weights: the plain least squares
        w_plain = red.gram_inv @ red.Yr_b
    else:
        w_plain = np.linalg.lstsq(Yr, b, rcond=None)[0] if sigma is None else None
    # Row weights: 1 / std of each torque difference, given or estimated from the residuals.
    noise_std = None
    rows_w = None
    if isinstance(sigma, float):
        rows_w = np.full(len(b), 1.0 / (math.sqrt(2.0) * sigma))
    elif sigma is not None:
        rows_w = np.tile(1.0 / (math.sqrt(2.0) * sigma), k)
    elif len(b) > Yr.shape[1]:
        residual_norm = float(np.linalg.norm(b - Yr @ w_plain))
        noise_std = max(residual_norm / math.sqrt(len(b) - Yr.shape[1]), NOISE_FLOOR)
        rows_w = np.full(len(b), 1.0 / noise_std)
    weights = np.ones(len(b)) if rows_w is None else rows_w
    if w_plain is not None and uniform:
        w_ls = w_plain  # equal weights do not move the least squares
    else:
        w_ls = np.linalg.lstsq(Yr * weights[:, None], b * weights, rcond=None)[0]
    if method == "lstsq":
        cov = None
        if rows_w is not None:
            Yw = Yr * rows_w[:, None]
            cov = delta_method(red.B @ w_ls, red.B @ np.linalg.inv(Yw.T @ Yw) @ red.B.T)
        theta = red.B @ w_ls
        return _finish(red, theta, cov, red.u, b, k, n, "lstsq", "closed_form", 0, noise_std)
    if com_prior is None:
        res = ipopt.solve(Yr, b, weights, w_ls, loss, huber_delta)
        theta = red.B @ res.x
        cov = None
        if rows_w is not None:
            cov = delta_method(theta, red.B @ _inverse(res.hessian) @ red.B.T)
        return _finish(red, theta, cov, red.u, b, k, n, "ipopt", res.return_status,
                       res.iterations, noise_std)  # fmt: skip
    if rows_w is None:
        raise InvalidInputError(
            "a com_prior needs torque_std when the readings do not outnumber the unknowns "
            "(the noise cannot be estimated from the residuals)"
        )
    return _with_prior(red, b, rows_w, w_ls, loss, huber_delta, com_prior, k, n, noise_std)


def _whitened(red, b, chol, method, loss, delta, prior, k, n):
    """The generalised least squares (or IPOPT on it) of the whitened problem L^-1 (Y, b)."""
    Yr_w = np.linalg.solve(chol, red.Yr)
    b_w = np.linalg.solve(chol, b)
    w_ls = np.linalg.lstsq(Yr_w, b_w, rcond=None)[0]
    ones = np.ones(len(b))
    if method == "lstsq":
        theta = red.B @ w_ls
        cov = delta_method(theta, red.B @ np.linalg.inv(Yr_w.T @ Yr_w) @ red.B.T)
        return _finish(red, theta, cov, red.u, b, k, n, "lstsq", "closed_form", 0, None)
    if prior is None:
        res = ipopt.solve(Yr_w, b_w, ones, w_ls, loss, delta)
        theta = red.B @ res.x
        cov = delta_method(theta, red.B @ _inverse(res.hessian) @ red.B.T)
        return _finish(red, theta, cov, red.u, b, k, n, "ipopt", res.return_status,
                       res.iterations, None)  # fmt: skip
    Y_w = np.linalg.solve(chol, red.Y)
    return _with_prior(red, b, ones, w_ls, loss, delta, prior, k, n, None, (Y_w, b_w))


def _with_prior(red, b, rows_w, w_ls, loss, delta, prior: AxisPrior, k, n, noise_std,
                fit=None):  # fmt: skip
    """The MAP estimate over (m, c_ee) with the axis prior.

    Warm-started from the closed form, moved along the unobservable direction to the point
    nearest the prior's axis. ``fit``: the (Y, b) to fit where not ``red.Y``, ``b`` (the
    whitened ones); the residuals are reported of ``red.Y`` and ``b``.
    """
    theta0 = red.B @ w_ls
    m0 = float(theta0[0])  # m0 = 0: refused after the solve
    c0 = theta0[1:] / m0 if m0 != 0.0 else np.zeros(3)
    if red.u is not None:
        u = red.u
        cos_angle = abs(float(prior.direction_ee @ u))
        if cos_angle > math.cos(MIN_AXIS_GRAVITY_ANGLE):
            raise UnobservableError(
                f"the prior's axis is {math.degrees(math.acos(min(cos_angle, 1.0))):.2f} deg "
                f"from the direction the torques cannot see (minimum "
                f"{math.degrees(MIN_AXIS_GRAVITY_ANGLE):.2f} deg): it cannot settle the CoM "
                "along it; measure at a pose where the rod is not vertical, or at two poses"
            )
        # the point of the line c0 + t u nearest the axis: P (c0 + t u - p) _|_ P u, with
        # P = I - d d^T; P u . P v = u . v - (u . d)(v . d)
        d, v = prior.direction_ee, c0 - prior.point_ee
        ud = float(u @ d)
        t = (float(u @ v) - ud * float(v @ d)) / (1.0 - ud * ud)
        c0 = c0 - t * u
    Y_fit, b_fit = (red.Y, b) if fit is None else fit
    res = ipopt.solve(Y_fit, b_fit, rows_w, np.concatenate(([m0], c0)), loss, delta, prior)
    theta = res.x * res.x[0]
    theta[0] = res.x[0]
    return _finish(red, theta, _inverse(res.hessian), None, b, k, n, "ipopt",
                   res.return_status, res.iterations, noise_std, res.x[1:])  # fmt: skip


def _finish(red, theta, cov, u, b, k, n, method, status, iters, noise_std, com=None):
    """The estimate of theta = (m, m c_ee) and its covariance (of (m, c_ee)), or a refusal."""
    m = float(theta[0])
    refuse_empty_gripper(m, None if cov is None else float(cov[0, 0]), red.cond)
    if com is None:
        com = theta[1:] / m
    r = b - red.Y @ theta
    rms = math.sqrt(float(r @ r) / r.size)
    u = None if u is None else np.array(u)
    return new_estimate(np.array(com), m, cov, u, r.reshape(k, n), rms, red.sv, red.cond,
                        method, status, iters, red.T, noise_std)  # fmt: skip


_inverse = ipopt.laplace_covariance
