"""Regressors filtered like the torques: the filter out of the identification's error budget.

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

from comgrasp_pin.robot import RobotModel
from comgrasp_pin.robot_io.from_motion.motion_signals import (
    FILTER_ORDER,
    MotionSamples,
    filtered_signals,
)
from comgrasp_pin.robot_io.log_files.joint_readers import JointLog

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
