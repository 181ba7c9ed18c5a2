"""The whole payload from a motion: mass, CoM and inertia with their covariance.

The arm moves along an excitation motion (``comgrasp plan-motion``) holding the payload. Per
kept sample (``motion_signals``), the measured efforts minus the arm's own are the payload's:

    tau - tau_arm(q, qd, qdd) = Y(q, qd, qdd) pi + offsets + friction

with Y the payload regressor (``estimation.payload_regressor``, ee frame). The arm's own
torques come from one of two places:
- an empty-arm run of the same motion (``empty_log``): its residual against the URDF's model
  (model errors and friction at the same state) is subtracted sample by sample, the runs
  aligned in time on their positions; per joint an offset and its drift over the motion (a
  cubic, ``DRIFT_DEGREE``) stay unknown (the sensor's drift between and within the runs);
- without one, the URDF's model (RNEA) stands for the arm, and per joint an offset, its
  drift, a viscous and a Coulomb friction coefficient are identified with the payload.

The ten parameters are fitted physically consistent (``estimation.inertial_fit``), the static
estimate as prior where one is given. Noise: per joint, the residuals' std of a first plain
fit weighs the rows; the covariance is widened for the residuals' correlation in time (the
filtered samples and the sensor's drift are not white) by Newey and West's estimator.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin
from numpy.polynomial import legendre

from comgrasp_pin.errors import InvalidInputError
from comgrasp_pin.estimation import ComEstimate
from comgrasp_pin.estimation.inertial_fit import fit_inertial
from comgrasp_pin.estimation.payload_regressor import (
    condition_number,
    parameter_scale,
    regressor_rows,
)
from comgrasp_pin.robot import RobotModel
from comgrasp_pin.robot_io.logs import JointLog
from comgrasp_pin.robot_io.motion_signals import (
    CUTOFF_HZ,
    MotionSamples,
    at_times,
    filtered_signals,
    motion_samples,
    motion_start,
)

DRIFT_DEGREE = 3
"""The drift of the efforts' offsets over a motion, a polynomial of this degree per joint
(Legendre, with the offset): a random walk's slow part. Measured on the Panda with the
realistic sensor (24 runs): degree 1 leaves the CoM errors 1.7 times the stated std, 3 cuts
them by a third (rms z 1.3), 5 and 8 fit the noise and do worse."""
COULOMB_SPEED = 0.02
"""Coulomb friction modelled as tanh(qd / COULOMB_SPEED) (rad/s): smooth through zero speed."""
ALIGN_SPAN_S = 0.25
"""The empty run is aligned within this many seconds (s) of its motion start's offset."""


@dataclass(frozen=True)
class DynamicEstimate:
    """A payload identified from a motion (ee frame, SI units).

    Attributes:
        mass: kg.
        com_ee: (3,) CoM (m).
        inertia_com_ee: (3, 3) inertia about the CoM, ee axes (kg m^2).
        params: (10,) m, m c, I at the ee origin (Pinocchio's order).
        params_cov: (10, 10) their covariance.
        cov: (4, 4) covariance of (mass, com_ee).
        inertia_std: (3, 3) std of each entry of ``inertia_com_ee``.
        inertia_cov: (9, 9) covariance of ``inertia_com_ee`` flattened row-major.
        condition_number: of the payload regressor along the motion, columns scaled by a
            1 kg payload 0.1 m out (``payload_regressor.parameter_scale``).
        residual_rms: (n,) per joint (N m).
        torque_std: (n,) the noise per joint that weighs the rows (N m, white).
        arm_model: "empty run" or "URDF model + friction".
        offsets: (n,) the efforts' offsets found (N m), their mean over the motion.
        offset_drift: (n,) their change from the motion's start to its end (N m): the
            sensor's drift, a cubic over the motion (``DRIFT_DEGREE``).
        friction: (n, 2) viscous (N m s/rad) and Coulomb (N m) per joint, or None.
        n_samples, duration_s: samples fitted and the motion's length (s).
        cutoff_hz: the filter's cutoff; velocity_from: "log" or "positions".
        solver_status: IPOPT's.
        unconstrained_params: (10,) the plain least squares' parameters (maybe inconsistent).
        t: (k,) the fitted samples' times (s from the log's start).
        tau_payload: (k, n) the payload's torques as measured: efforts minus the arm's own,
            the offsets and friction found (N m).
        tau_payload_fit: (k, n) the fitted payload's torques, Y pi (N m).
    """

    mass: float
    com_ee: np.ndarray
    inertia_com_ee: np.ndarray
    params: np.ndarray
    params_cov: np.ndarray
    cov: np.ndarray
    inertia_std: np.ndarray
    inertia_cov: np.ndarray
    condition_number: float
    residual_rms: np.ndarray
    torque_std: np.ndarray
    arm_model: str
    offsets: np.ndarray
    offset_drift: np.ndarray
    friction: np.ndarray | None
    n_samples: int
    duration_s: float
    cutoff_hz: float
    velocity_from: str
    solver_status: str
    unconstrained_params: np.ndarray
    t: np.ndarray
    tau_payload: np.ndarray
    tau_payload_fit: np.ndarray


def estimate_payload_dynamic(
    robot: RobotModel,
    log: JointLog,
    empty_log: JointLog | None = None,
    window: tuple[float, float] | None = None,
    empty_window: tuple[float, float] | None = None,
    cutoff_hz: float = CUTOFF_HZ,
    prior: ComEstimate | tuple[np.ndarray, np.ndarray] | None = None,
) -> DynamicEstimate:
    """Identify the held payload's ten inertial parameters from a motion's log.

    Args:
        robot: the arm; its model's gravity is the one the torques were measured under.
        log: the motion holding the payload (positions and efforts; velocities if logged).
        empty_log: the same motion with the empty arm, or None (the URDF's model then).
        window: (t0, t1) s of ``log`` to use, or None for all of it.
        empty_window: the same for ``empty_log``.
        cutoff_hz: the low-pass filter's cutoff (Hz).
        prior: a static estimate of the same payload in the same ee frame (a ComEstimate,
            or ((4,) mass and CoM, (4, 4) their covariance)), or None.

    Raises:
        MotionLogError: a log too short, still, jerky, at a joint limit, with gaps.
        UnobservableError: the motion does not determine the parameters.
        SolverError: IPOPT did not converge.
    """
    S = motion_samples(robot, log, window, cutoff_hz)
    b = S.tau - _arm_torques(robot, S)
    if empty_log is not None:
        E = _aligned_empty(robot, S, empty_log, empty_window, cutoff_hz)
        b = b - (E.tau - _arm_torques(robot, E))
        columns = [np.ones_like(S.qd), *_drift(S)]
        arm_model = "empty run"
    else:
        columns = [np.ones_like(S.qd), *_drift(S), S.qd, np.tanh(S.qd / COULOMB_SPEED)]
        arm_model = "URDF model + friction"
    k, n = S.q.shape
    Y = regressor_rows(robot, S.q, S.qd, S.qdd)
    A_pi, A_x, b_rows = Y.reshape(-1, 10), _joint_columns(columns), b.reshape(-1)
    sigma = _noise(A_pi, A_x, b_rows, k, n)
    w = np.tile(1.0 / sigma, k)
    fit = fit_inertial(A_pi, A_x, b_rows, w, _prior(prior))
    tau_fit = (A_pi @ fit.pi).reshape(k, n)
    tau_payload = (b_rows - A_x @ fit.x).reshape(k, n)
    residual = tau_fit - tau_payload
    params_cov = _widened(fit, A_pi, A_x, w, residual)
    extras = fit.x.reshape(len(columns), n)
    mass, com, inertia_c, cov4, inertia_cov = _about_com(fit.pi, params_cov)
    inertia_std = np.sqrt(np.clip(np.diag(inertia_cov), 0, None)).reshape(3, 3)
    return DynamicEstimate(
        mass, com, inertia_c, fit.pi, params_cov, cov4, inertia_std, inertia_cov,
        condition_number(Y, parameter_scale()), np.sqrt(np.mean(residual**2, axis=0)), sigma,
        arm_model, extras[0], 2 * extras[1 : 1 + DRIFT_DEGREE : 2].sum(axis=0),
        None if empty_log is not None else extras[1 + DRIFT_DEGREE :].T,
        k, float(S.t[-1] - S.t[0]), S.cutoff_hz, S.velocity_from, fit.return_status,
        fit.unconstrained_pi, S.t, tau_payload, tau_fit,
    )  # fmt: skip


def _arm_torques(robot: RobotModel, S: MotionSamples) -> np.ndarray:
    """(k, n) the URDF model's inverse dynamics (RNEA) at the samples (N m)."""
    model, data = robot.model, robot.data
    return np.array([pin.rnea(model, data, q, qd, qdd).copy()
                     for q, qd, qdd in zip(S.q, S.qd, S.qdd)])  # fmt: skip


def _aligned_empty(robot, S: MotionSamples, empty_log, empty_window, cutoff_hz) -> MotionSamples:
    """The empty run at the loaded samples' times, shifted to match their positions."""
    full = filtered_signals(robot, empty_log, empty_window, cutoff_hz)
    loaded_start = motion_start(S)
    guess = motion_start(full) - loaded_start
    lo = max(guess - ALIGN_SPAN_S, full.t[0] - S.t[0])
    hi = min(guess + ALIGN_SPAN_S, full.t[-1] - S.t[-1])
    if hi < lo:
        raise InvalidInputError(
            f"the empty run ({full.t[-1] - full.t[0]:.1f} s) does not cover the loaded "
            f"motion ({S.t[-1] - S.t[0]:.1f} s): record the same motion empty"
        )
    shifts = np.arange(lo, hi + 1e-9, 1.0 / full.rate_hz)
    errors = [np.mean((at_times(full, S.t + d).q - S.q) ** 2) for d in shifts]
    best = float(shifts[int(np.argmin(errors))])
    E = at_times(full, S.t + best)
    gap = float(np.sqrt(np.min(errors)))
    if gap > 0.05:
        raise InvalidInputError(
            f"the empty run does not follow the loaded motion (rms {gap:.3f} rad apart at "
            "the best alignment): record the same planned motion with the empty arm"
        )
    return E


def _drift(S: MotionSamples) -> list[np.ndarray]:
    """(k, n) columns of the sensor's drift over the motion, one per degree.

    Legendre polynomials of degree 1 to ``DRIFT_DEGREE`` in time scaled to [-1, 1], the same
    for every joint.
    """
    u = (2 * S.t - S.t[0] - S.t[-1]) / (S.t[-1] - S.t[0])
    n = S.q.shape[1]
    return [np.tile(legendre.legval(u, [0] * d + [1])[:, None], (1, n))
            for d in range(1, DRIFT_DEGREE + 1)]  # fmt: skip


def _joint_columns(columns: list[np.ndarray]) -> np.ndarray:
    """(k n, len(columns) n): column c of joint j acts on joint j's rows only."""
    k, n = columns[0].shape
    out = np.zeros((k, n, len(columns) * n))
    for c, values in enumerate(columns):
        for j in range(n):
            out[:, j, c * n + j] = values[:, j]
    return out.reshape(k * n, -1)


def _noise(A_pi, A_x, b_rows, k: int, n: int) -> np.ndarray:
    """(n,) per joint noise std of the rows: a first plain fit's residuals."""
    A = np.column_stack([A_pi, A_x])
    beta, *_ = np.linalg.lstsq(A, b_rows, rcond=None)
    r = (A @ beta - b_rows).reshape(k, n)
    dof = max(k * n - A.shape[1], 1) / (k * n)
    return np.maximum(np.sqrt(np.mean(r**2, axis=0) / dof), 1e-9)


def _widened(fit, A_pi, A_x, w, residual: np.ndarray) -> np.ndarray:
    """The fit's covariance of pi, each std widened by Newey-West over white noise.

    The residuals are correlated in time (the filter, the sensor's drift) and across joints
    at one time. Newey and West's estimator (Bartlett weights, ``L`` lags by their rule of
    thumb) sums the scores' products over the lags; its stds of pi against the white
    noise's give a factor per parameter, applied to the Laplace covariance (which holds the
    consistency constraint and the prior).
    """
    k, n = residual.shape
    A = np.column_stack([A_pi, A_x]) * w[:, None]
    bread = np.linalg.inv(A.T @ A)
    scores = (A * (w * residual.reshape(-1))[:, None]).reshape(k, n, -1).sum(axis=1)
    lags = int(np.ceil(4 * (k / 100) ** (2 / 9)))
    meat = scores.T @ scores
    for lag in range(1, lags + 1):
        product = scores[lag:].T @ scores[:-lag]
        meat += (1 - lag / (lags + 1)) * (product + product.T)
    hac = (bread @ meat @ bread)[:10, :10]
    white = bread[:10, :10] * np.mean((w * residual.reshape(-1)) ** 2)
    factor = np.sqrt(np.maximum(np.diag(hac), 0) / np.diag(white))
    return fit.cov * np.outer(factor, factor)


def _prior(est):
    """((4,) mean, (4, 4) cov) of (m, c), or None (no prior, or a CoM seen as a line only)."""
    if est is None or isinstance(est, tuple):
        return est
    if est.cov is None or est.unobservable_ee is not None:
        return None
    return np.concatenate([[est.mass], est.com_ee]), np.asarray(est.cov, float)


def _about_com(pi: np.ndarray, cov: np.ndarray):
    """Mass, CoM, inertia about the CoM and their covariances (the delta method)."""

    def derived(p):
        m, c = p[0], p[1:4] / p[0]
        Ixx, Ixy, Iyy, Ixz, Iyz, Izz = p[4:]
        I_o = np.array([[Ixx, Ixy, Ixz], [Ixy, Iyy, Iyz], [Ixz, Iyz, Izz]])
        I_c = I_o - m * (c @ c * np.eye(3) - np.outer(c, c))  # parallel axis theorem
        return np.concatenate([[m], c, I_c.ravel()])

    value = derived(pi)
    steps = np.diag(1e-6 * np.maximum(np.abs(pi), 1e-6))
    D = np.column_stack([(derived(pi + h) - derived(pi - h)) / (2 * h[i])
                         for i, h in enumerate(steps)])  # fmt: skip
    C = D @ cov @ D.T
    return float(value[0]), value[1:4], value[4:].reshape(3, 3), C[:4, :4], C[4:, 4:]
