"""A motion's linear system: the model's terms filtered like the torques, the extra columns.

Also the rows' noise and pi's derived parts. Rows are sample-major (sample i's n joints,
then sample i + 1's). Shared by the payload's fit (``dynamic``), the arm's identification
(``arm_model``), the gains' calibration (``gain_calibration``) and the wrench's rows
(``wrench_system``).

The torques are low-passed (``motion_signals``: a zero-phase Butterworth at the cutoff) to
take the noise out. The model's side is nonlinear in the motion (Coriolis terms go as qd^2,
Coulomb friction as sign(qd), gravity as sin q): evaluated on low-passed signals it is not
the low-passed model, and the difference depends on the motion. Subtracting an empty run of
the same motion cancels it; an arm model identified on one motion and used on another does
not (in MuJoCo, a 20 s UR5 excitation's arm model read another motion's empty arm as a
16 g payload at a 4 Hz cutoff, 38 g at 2 Hz).

Parallel filtering (Gautier 1997) removes it: the model's terms are computed on signals
filtered only to differentiate them (a cutoff ``DIFF_FACTOR`` times higher, on a grid fast
enough for their products), then low-passed by the same filter as the torques. Since
tau = Y(q, qd, qdd) beta is linear in beta, filter(tau) = filter(Y) beta holds exactly.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.polynomial import legendre

from comgrasp_pin.robot import RobotModel
from comgrasp_pin.robot_io.from_motion.motion_signals import (
    FILTER_ORDER,
    MotionSamples,
    filtered_signals,
)
from comgrasp_pin.robot_io.log_files.joint_readers import JointLog

DRIFT_DEGREE = 3
"""The drift of the efforts' offsets over a motion, a polynomial of this degree per joint
(Legendre, with the offset): a random walk's slow part. Measured on the Panda with the
realistic sensor (24 runs): degree 1 leaves the CoM errors 1.7 times the stated std, 3 cuts
them by a third (rms z 1.3), 5 and 8 fit the noise and do worse."""
COULOMB_SPEED = 0.02
"""Coulomb friction modelled as tanh(qd / COULOMB_SPEED) (rad/s): smooth through zero speed."""


def drift_columns(S: MotionSamples) -> list[np.ndarray]:
    """(k, n) columns of the sensor's drift over the motion, one per degree.

    Legendre polynomials of degree 1 to ``DRIFT_DEGREE`` in time scaled to [-1, 1], the same
    for every joint.
    """
    u = (2 * S.t - S.t[0] - S.t[-1]) / (S.t[-1] - S.t[0])
    n = S.q.shape[1]
    return [np.tile(legendre.legval(u, [0] * d + [1])[:, None], (1, n))
            for d in range(1, DRIFT_DEGREE + 1)]  # fmt: skip


def offset_columns(S: MotionSamples) -> list[np.ndarray]:
    """The offset and its drift, per joint: [ones, drift columns]."""
    return [np.ones_like(S.qd), *drift_columns(S)]


def friction_columns(S: MotionSamples) -> list[np.ndarray]:
    """Viscous and Coulomb friction, per joint."""
    return [S.qd, np.tanh(S.qd / COULOMB_SPEED)]


def joint_columns(columns: list[np.ndarray]) -> np.ndarray:
    """(k n, len(columns) n): column c of joint j acts on joint j's rows only."""
    k, n = columns[0].shape
    out = np.zeros((k, n, len(columns) * n))
    for c, values in enumerate(columns):
        for j in range(n):
            out[:, j, c * n + j] = values[:, j]
    return out.reshape(k * n, -1)


def row_noise(A: np.ndarray, b_rows: np.ndarray, k: int, n: int) -> np.ndarray:
    """(n,) per joint noise std of the rows: a first plain fit's residuals."""
    beta, *_ = np.linalg.lstsq(A, b_rows, rcond=None)
    r = (A @ beta - b_rows).reshape(k, n)
    dof = max(k * n - A.shape[1], 1) / (k * n)
    return np.maximum(np.sqrt(np.mean(r**2, axis=0) / dof), 1e-9)


def prior_of(est):
    """((4,) mean, (4, 4) cov) of (m, c), or None (no prior, or a CoM seen as a line only)."""
    if est is None or isinstance(est, tuple):
        return est
    if est.cov is None or est.unobservable_ee is not None:
        return None
    return np.concatenate([[est.mass], est.com_ee]), np.asarray(est.cov, float)


def _derived(p: np.ndarray) -> np.ndarray:
    """(13,) mass, CoM and the inertia about the CoM (flattened) of the ten parameters p."""
    m = p[0] if abs(p[0]) > 1e-9 else 1e-9
    c = p[1:4] / m
    Ixx, Ixy, Iyy, Ixz, Iyz, Izz = p[4:]
    I_o = np.array([[Ixx, Ixy, Ixz], [Ixy, Iyy, Iyz], [Ixz, Iyz, Izz]])
    I_c = I_o - m * (c @ c * np.eye(3) - np.outer(c, c))  # parallel axis theorem
    return np.concatenate([[p[0]], c, I_c.ravel()])


def derived_jacobian(pi: np.ndarray) -> np.ndarray:
    """(13, 10) d (mass, CoM, inertia about the CoM) / d pi, by central differences."""
    steps = np.diag(1e-6 * np.maximum(np.abs(pi), 1e-6))
    return np.column_stack([(_derived(pi + h) - _derived(pi - h)) / (2 * h[i])
                            for i, h in enumerate(steps)])  # fmt: skip


def about_com(pi: np.ndarray, cov: np.ndarray):
    """Mass, CoM, inertia about the CoM and their covariances (the delta method)."""
    value = _derived(pi)
    D = derived_jacobian(pi)
    C = D @ cov @ D.T
    return float(value[0]), value[1:4], value[4:].reshape(3, 3), C[:4, :4], C[4:, 4:]


DIFF_FACTOR = 4.0
"""The differentiating filter's cutoff, in multiples of the torques' cutoff."""
MAX_DIFF_SHARE = 0.3
"""... at most this share of the log's sample rate (below Nyquist with margin)."""
GRID_PER_DIFF = 4.0
"""The model's terms are computed every 1 / (GRID_PER_DIFF * differentiating cutoff) s:
fast enough for their products' doubled frequencies."""


def fast_signals(robot: RobotModel, log: JointLog, window, cutoff_hz: float) -> MotionSamples:
    """The log's signals filtered only to differentiate them, on a grid thinned to suit."""
    step = float(np.median(np.diff(np.asarray(log.time, float))))
    diff_cutoff = min(DIFF_FACTOR * cutoff_hz, MAX_DIFF_SHARE / step)
    full = filtered_signals(robot, log, window, diff_cutoff, bridge_hz=cutoff_hz)
    stride = max(1, int(full.rate_hz / (GRID_PER_DIFF * diff_cutoff)))
    idx = np.arange(0, len(full.t), stride)
    return MotionSamples(
        full.t[idx], full.q[idx], full.qd[idx], full.qdd[idx], full.tau[idx],
        full.cutoff_hz, full.rate_hz / stride, full.velocity_from,
    )  # fmt: skip


def lowpassed(
    fast: MotionSamples,
    cutoff_hz: float,
    terms: Callable[[MotionSamples], np.ndarray],
    times: np.ndarray,
) -> np.ndarray:
    """``terms(fast)`` ((K, ...) at ``fast``'s times) low-passed at ``cutoff_hz``, at ``times``.

    The filter is the torques' (Butterworth of ``FILTER_ORDER``, forward and backward).
    """
    from scipy.signal import butter, sosfiltfilt

    values = np.asarray(terms(fast), float)
    sos = butter(FILTER_ORDER, cutoff_hz, fs=fast.rate_hz, output="sos")
    smooth = sosfiltfilt(sos, values, axis=0)
    flat = smooth.reshape(len(fast.t), -1)
    out = np.column_stack([np.interp(times, fast.t, col) for col in flat.T])
    return out.reshape((len(times),) + values.shape[1:])


def delay_column(fast: MotionSamples, S: MotionSamples) -> np.ndarray:
    """(k n,) the column of the efforts' delay d behind the positions: -d tau/dt.

    A drive or a logger reports the effort a little after the position it belongs to:
    tau_logged(t) = tau(t - d) = tau(t) - d dtau/dt, one unknown d (s) per run. In MuJoCo
    the logged torque lags by 0.6 ms (the integrator's step), on the real UR10e the motor
    currents by about 10 ms; unmodelled, 1 ms moved a payload identified with another
    motion's arm model by 11 g. The rate is the logged efforts' own, filtered like them.
    """
    rate = lowpassed(fast, S.cutoff_hz, lambda F: np.gradient(F.tau, F.t, axis=0), S.t)
    return -rate.reshape(-1)
