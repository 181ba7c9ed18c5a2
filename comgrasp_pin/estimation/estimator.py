"""Payload mass and CoM from joint torques before/after grasping, at one or several poses.

The model (``regressor``) is linear in theta = (m, m*c_ee): dtau = Y(q) theta, with gravity
from the robot model. Writing the unknowns in the ee frame lets k static poses stack into
one (k*n, 4) problem. One path solves it:

1. the stacked regression Y and its SVD decide what is observed (``least_squares.observe``:
   one pose loses the CoM along gravity, ``unobservable_ee``; an unobservable mass raises);
2. the whitened least squares gives theta and its covariance, the inverse Fisher information
   (the Cramer-Rao bound) for Gaussian noise of the given std (each difference of two
   readings: 2 sigma^2), of the given covariance ``dtau_cov``, or of the std the residuals
   show (``least_squares.fit``);
3. ``method="ipopt"`` solves the same whitened problem with CasADi and IPOPT (``ipopt``),
   started at the least squares: a robust loss, and an ``AxisPrior`` that settles what the
   torques cannot see; the covariance is the inverse Hessian of the negative log posterior
   at the optimum (Laplace);
4. (m, c_ee) = (theta_0, theta_1:/theta_0) gets theta's covariance by the delta method, and a
   mass not measurably above zero is refused.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from comgrasp_pin.errors import InvalidInputError, UnobservableError
from comgrasp_pin.estimation import ipopt
from comgrasp_pin.estimation.estimate import (
    ComEstimate,
    check_finite_result,
    delta_method,
    mc_jacobian,
    refuse_empty_gripper,
)
from comgrasp_pin.estimation.inputs import check_arrays, check_dtau_cov, check_options
from comgrasp_pin.estimation.least_squares import Fit, Observed, fit, observe, whitened
from comgrasp_pin.estimation.prior import AxisPrior
from comgrasp_pin.estimation.regressor import stacked_regressor
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
        robot: the arm; its model's gravity is the one the torques were measured under.
        q: (n,) one static configuration (rad / m) or (k, n) for k poses.
        tau_before: same shape as q, joint torques without the object (N m).
        tau_after: same shape as q, joint torques holding the object (N m).
        method: "lstsq" (closed form) or "ipopt" (CasADi + IPOPT, problem built once).
        torque_std: std of each (averaged) torque reading (N m), scalar or (n,) per joint;
            weights the least squares and sets ``cov``.
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
    """
    check_options(method, rcond, loss, huber_delta, com_prior, torque_std)
    q_arr, dtau, sigma = check_arrays(robot, q, tau_before, tau_after, torque_std)
    n = q_arr.shape[-1]
    Q, b = q_arr.reshape(-1, n), dtau.ravel()
    chol = check_dtau_cov(dtau_cov, b.size, torque_std)
    g = robot.model.gravity.linear
    Y, T = stacked_regressor(robot, Q, g)
    if payload_motion_ee is not None:
        Y = carried(Y, payload_motion_ee, len(Q))
    row_std = None if sigma is None else math.sqrt(2.0) * sigma  # of a difference
    if isinstance(row_std, np.ndarray):
        row_std = np.tile(row_std, len(Q))
    return solve_rows(Y, b, T, g, row_std, chol, method, rcond, loss, huber_delta, com_prior)


def carried(Y: np.ndarray, payload_motion_ee: np.ndarray, k: int) -> np.ndarray:
    """The rows of k poses (pose-major, equal blocks) in theta at the first pose."""
    maps = motion_maps(payload_motion_ee, k)
    r = len(Y) // k
    return np.concatenate([Y[i * r : (i + 1) * r] @ maps[i] for i in range(k)])


def solve_rows(
    Y: np.ndarray,
    b: np.ndarray,
    T: np.ndarray,
    g: np.ndarray,
    row_std: float | np.ndarray | None,
    chol: np.ndarray | None,
    method: str,
    rcond: float = RCOND,
    loss: str = "l2",
    huber_delta: float = 3.0,
    com_prior: AxisPrior | None = None,
) -> ComEstimate:
    """Steps 1-4 of the module docstring on any stacked rows b = Y theta + noise.

    Args:
        Y: (rows, 4) the rows in theta = (m, m c_ee): joint torques' (``stacked_regressor``),
            a wrist sensor's (``wrench_com``), or both stacked.
        b: (rows,) the measured differences (N m, N).
        T: (k, 4, 4) T_world_ee at the poses.
        g: (3,) the model's gravity (m/s^2).
        row_std: each row's std (scalar or (rows,)); None: from the residuals.
        chol: the lower Cholesky factor of the rows' covariance, in place of ``row_std``.
        method: as ``estimate_com``.
        rcond: as ``estimate_com``.
        loss: as ``estimate_com``.
        huber_delta: as ``estimate_com``.
        com_prior: as ``estimate_com``.
    """
    g_norm = math.sqrt(float(g @ g))
    seen = observe(Y, rcond, lambda: (g @ T[0, :3, :3]) / g_norm)  # gravity in the ee frame
    data = _Data(Y, b, T, g_norm)
    ls = fit(Y, b, seen, row_std, chol)
    if method == "lstsq":
        cov = None
        if ls.cov_root is not None:  # the delta method on cov(theta)'s root
            root = mc_jacobian(ls.theta) @ ls.cov_root
            cov = root @ root.T
        return _finish(ls.theta, cov, seen, data, ls.torque_std, "closed_form", 0)
    if ls.cov_root is None:
        raise InvalidInputError(
            "method='ipopt' needs torque_std (or dtau_cov) when the readings do not "
            "outnumber the unknowns: the noise cannot be estimated from the residuals"
        )
    if com_prior is None:
        return _ipopt_free(ls, seen, data, loss, huber_delta)
    return _with_prior(ls, seen, data, loss, huber_delta, com_prior)


class _Data(NamedTuple):
    """The problem: Y (k n, 4), the differences b (k n,) (N m), T_world_ee (k, 4, 4), |g|."""

    Y: np.ndarray
    b: np.ndarray
    T_world_ee: np.ndarray
    g_norm: float


def motion_maps(motion: np.ndarray, k: int) -> np.ndarray:
    """(k, 4, 4) maps A_i: theta at pose i = A_i theta (theta at the first pose).

    From the payload's rigid motions M_i = (R_i, p_i): m c_i = R_i (m c) + m p_i.
    """
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


def _ipopt_free(ls: Fit, seen: Observed, data: _Data, loss: str, delta: float) -> ComEstimate:
    """IPOPT without a prior, over the observed directions x = Vt theta."""
    A, b_w, w = _for_ipopt(ls, data.Y, data.b)
    res = ipopt.solve(A @ ls.Vt.T, b_w, w, ls.Vt @ ls.theta, loss, delta)
    theta = ls.Vt.T @ res.x
    cov = delta_method(theta, ls.Vt.T @ ipopt.laplace_covariance(res.hessian) @ ls.Vt)
    return _finish(theta, cov, seen, data, ls.torque_std, res.return_status, res.iterations)


def _with_prior(ls: Fit, seen: Observed, data: _Data, loss, delta, prior: AxisPrior) -> ComEstimate:
    """The MAP estimate over x = (m, c_ee) with the axis prior (IPOPT).

    Started from the least squares, moved along the unobserved direction to the point
    nearest the prior's axis.
    """
    m0 = float(ls.theta[0])  # m0 = 0: refused after the solve
    c0 = ls.theta[1:] / m0 if m0 != 0.0 else np.zeros(3)
    if seen.u is not None:
        u, d = seen.u, prior.direction_ee
        ud = float(u @ d)
        if abs(ud) > math.cos(MIN_AXIS_GRAVITY_ANGLE):
            raise UnobservableError(
                f"the prior's axis is {math.degrees(math.acos(min(abs(ud), 1.0))):.2f} deg "
                f"from the direction the torques cannot see (minimum "
                f"{math.degrees(MIN_AXIS_GRAVITY_ANGLE):.2f} deg): it cannot settle the CoM "
                "along it; measure at a pose where the rod is not vertical, or at two poses"
            )
        # the point of the line c0 + t u nearest the axis: P (c0 + t u - p) _|_ P u, with
        # P = I - d d^T; P u . P v = u . v - (u . d)(v . d)
        v = c0 - prior.point_ee
        c0 = c0 - (float(u @ v) - ud * float(v @ d)) / (1.0 - ud * ud) * u
    x0 = np.concatenate(([m0], c0))
    res = ipopt.solve(*_for_ipopt(ls, data.Y, data.b), x0, loss, delta, prior)
    m = float(res.x[0])
    theta = np.concatenate(([m], m * res.x[1:]))
    seen_full = seen._replace(u=None)
    return _finish(theta, ipopt.laplace_covariance(res.hessian), seen_full, data, ls.torque_std,
                   res.return_status, res.iterations)  # fmt: skip


def _for_ipopt(ls: Fit, Y: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(A / c, b_w / c, weights c) of the whitened problem (A, b_w), c its scale against Y.

    IPOPT's residuals w (A / c theta - b_w / c) are the whitened ones (in standard deviations,
    as the Huber threshold), and its objective is scaled to Y's units (``ipopt.parameters``
    divides by max(w)^2): its tolerances then hold for any noise level.
    """
    A, b_w = whitened(Y, b, ls.row_std, ls.chol)
    c = float(np.linalg.norm(A) / np.linalg.norm(Y))
    return A / c, b_w / c, np.full(len(b_w), c)


def _finish(theta, cov, seen: Observed, data: _Data, torque_std, status, iterations) -> ComEstimate:
    """The frozen estimate of theta = (m, m c_ee) with ``cov`` of (m, c_ee), or a refusal."""
    m = float(theta[0])
    refuse_empty_gripper(m, None if cov is None else float(cov[0, 0]), seen.condition_number)
    com = theta[1:] / m
    T = data.T_world_ee
    k = len(T)
    residuals = (data.b - data.Y @ theta).reshape(k, -1)
    rms = math.sqrt(float(residuals.ravel() @ residuals.ravel()) / residuals.size)
    # Python float sums never warn: NaN or inf anywhere shows here, then named
    screen = m + rms + sum(com.tolist()) + (0.0 if cov is None else sum(cov.ravel().tolist()))
    if not math.isfinite(screen):
        check_finite_result(mass=m, com_ee=com, cov=cov, residual_rms=rms)
    sv = seen.singular_values.copy()
    for a in (com, seen.u, cov, residuals, sv, T):
        if a is not None:
            a.setflags(write=False)
    return ComEstimate(com, m, m * data.g_norm, seen.u, cov, rms, residuals,
                       seen.condition_number, sv, "lstsq" if status == "closed_form" else "ipopt",
                       status, iterations, k, T, torque_std)  # fmt: skip
