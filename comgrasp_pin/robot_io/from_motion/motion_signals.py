"""A motion's joint signals for dynamic identification, filtered without phase lag.

Positions, velocities, accelerations and efforts, thinned to nearly independent samples.

Accelerations are never in a log, and a drive's reported velocity is noisy: both come from
the positions by a zero-phase low-pass filter (Butterworth, run forward and backward:
``scipy.signal.sosfiltfilt``) and differentiation. The efforts go through the same filter,
so that every signal has the same (zero) delay and the same pass band. Where the log has
velocities (``JointLog.velocity``) they are filtered and used, and differentiated for the
accelerations. The filtered signals are then kept every ``1 / (SAMPLES_PER_CUTOFF * cutoff)``
seconds: closer samples carry no new information past the cutoff and only correlate the
residuals.

What makes a log unusable, each a ``MotionLogError`` that says what and where:
- too short (``MIN_DURATION_S``) or sampled too slowly for the cutoff (Nyquist);
- no motion (the fastest joint below ``MIN_PEAK_SPEED``): a still arm cannot see inertia;
- a joint within ``LIMIT_MARGIN`` of its limit: the limit's stop torques are not the payload;
- too jerky: more of the positions' motion above the cutoff than ``MAX_ABOVE_CUTOFF`` (the
  filter would cut real motion and the accelerations come out wrong; raise the cutoff or
  plan a smoother motion).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from comgrasp_pin.errors import MotionLogError
from comgrasp_pin.robot import RobotModel
from comgrasp_pin.robot_io.log_files.joint_readers import JointLog
from comgrasp_pin.robot_io.log_files.log_values import on_grid, uniform_rate

CUTOFF_HZ = 4.0
"""Default low-pass cutoff (Hz): above an excitation motion's harmonics (<= 1-2 Hz)."""
FILTER_ORDER = 4
"""Butterworth order; run forward and backward, so the effective order is twice this."""
SAMPLES_PER_CUTOFF = 2.5
"""Samples kept per cutoff period's inverse: the kept rate is 2.5 x the cutoff."""
MIN_DURATION_S = 3.0
"""Shortest usable motion (s): a few periods of the filter, edges dropped."""
EDGE_S = 0.5
"""Seconds dropped at each end after filtering (the filter's start-up transient); with
``crop``, also after the arm starts moving and before it stops: at rest each joint holds the
stuck friction its stop left (up to its Coulomb friction), which differs between an empty and
a loaded run and does not cancel, and the filter spreads it over about this much."""
MIN_PEAK_SPEED = 0.2
"""The fastest joint must reach this speed (rad/s) somewhere, or inertia is not seen."""
LIMIT_MARGIN = 1e-3
"""A joint closer than this to its limit (rad or m) is at its stop."""
MAX_ABOVE_CUTOFF = 0.05
"""Largest share (rms) of a joint's motion above the cutoff before a log is too jerky."""
MOTION_SPEED = 0.05
"""A joint faster than this (rad/s, filtered) is moving: where a log's motion starts and ends
(``find_motion``). Well above a still arm's filtered velocity noise (UR, Panda: < 0.005)."""
MOTION_MARGIN_S = 0.25
"""Seconds kept before the first and after the last moving sample (``find_motion``): the
motion's slow start and end below ``MOTION_SPEED``. Short, so that an empty run recorded with
little still time around the same motion still covers the loaded one's found motion."""


@dataclass(frozen=True)
class MotionSamples:
    """Filtered, thinned samples of one motion, in the robot model's joint order.

    Attributes:
        t: (k,) s from the log's first message.
        q, qd, qdd: (k, n) positions (rad), velocities (rad/s), accelerations (rad/s^2).
        tau: (k, n) efforts, filtered like the positions (N m).
        cutoff_hz: the low-pass filter's cutoff.
        rate_hz: the log's (median) sample rate.
        velocity_from: "log" (the drive's velocities, filtered) or "positions".
    """

    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray
    tau: np.ndarray
    cutoff_hz: float
    rate_hz: float
    velocity_from: str


def motion_samples(
    robot: RobotModel,
    log: JointLog,
    window: tuple[float, float] | None = None,
    cutoff_hz: float = CUTOFF_HZ,
    crop: bool = False,
) -> MotionSamples:
    """``filtered_signals`` thinned to nearly independent samples (the edges dropped).

    Args:
        robot: the arm, as ``filtered_signals``.
        log: the motion's readings.
        window: (t0, t1) s from the log's first message, or None for the whole log.
        cutoff_hz: low-pass cutoff (Hz).
        crop: keep only the motion, for an empty run's subtraction: from ``EDGE_S`` after
            the first to ``EDGE_S`` before the last moving sample (``moving_span``). The still
            parts before and after it are left out: their stuck friction differs from run to
            run, and an empty run of the same motion with shorter still parts still covers
            the samples (``alignment.align_empty``). Where ``window`` is None, the motion
            (``find_motion``) must last ``MIN_DURATION_S``.

    Raises:
        MotionLogError: as ``filtered_signals``; with ``crop``, a motion shorter than
            ``MIN_DURATION_S``.
    """
    full = filtered_signals(robot, log, window, cutoff_hz)
    stride = max(1, int(round(full.rate_hz / (SAMPLES_PER_CUTOFF * cutoff_hz))))
    keep = (full.t >= full.t[0] + EDGE_S) & (full.t <= full.t[-1] - EDGE_S)
    if crop:
        first, last = moving_span(full)
        t0, t1 = _with_margins(full, first, last)
        if window is None and t1 - t0 < MIN_DURATION_S:
            raise MotionLogError(
                f"{log.source or 'the log'}'s motion lasts {t1 - t0:.2f} s ({t0:.2f}-{t1:.2f} "
                f"s); at least {MIN_DURATION_S} s are needed: play an excitation motion "
                "(comgrasp plan-motion), or give --window around the motion"
            )
        keep &= (full.t >= first + EDGE_S) & (full.t <= last - EDGE_S)
    return _take(full, np.flatnonzero(keep)[::stride])


def find_motion(full: MotionSamples, speed: float = MOTION_SPEED) -> tuple[float, float]:
    """(t0, t1) s: the first and last time any joint moves faster than ``speed`` (rad/s).

    ``full`` is a log's filtered signals (``filtered_signals``, velocities filtered). The span
    is widened by ``MOTION_MARGIN_S`` at each end and clipped to the log's.

    Raises:
        MotionLogError: no joint reaches ``speed``.
    """
    return _with_margins(full, *moving_span(full, speed))


def _with_margins(full: MotionSamples, first: float, last: float) -> tuple[float, float]:
    """(t0, t1) s: ``first`` to ``last`` with MOTION_MARGIN_S around, within the log."""
    return max(first - MOTION_MARGIN_S, float(full.t[0])), min(last + MOTION_MARGIN_S,
                                                                 float(full.t[-1]))  # fmt: skip


def moving_span(full: MotionSamples, speed: float = MOTION_SPEED) -> tuple[float, float]:
    """(first, last) s: the first and last sample where a joint is faster than ``speed``.

    ``speed`` in rad/s; a MotionLogError where no joint is.
    """
    fastest = np.max(np.abs(full.qd), axis=1)
    moving = np.flatnonzero(fastest > speed)
    if not moving.size:
        raise MotionLogError(
            f"nothing moves in {full.t[0]:.2f}-{full.t[-1]:.2f} s: the fastest joint reaches "
            f"{float(fastest.max()):.3f} rad/s, a motion is found above {speed} rad/s; give "
            "the log of an excitation motion (comgrasp plan-motion) or a lower speed"
        )
    return float(full.t[moving[0]]), float(full.t[moving[-1]])


def filtered_signals(
    robot: RobotModel,
    log: JointLog,
    window: tuple[float, float] | None = None,
    cutoff_hz: float = CUTOFF_HZ,
    bridge_hz: float | None = None,
) -> MotionSamples:
    """Filtered positions, velocities, accelerations and efforts at the log's own rate.

    Args:
        robot: the arm (its joint limits; the log's columns in its joint order).
        log: the motion's readings.
        window: (t0, t1) s from the log's first message, or None for the whole log.
        cutoff_hz: low-pass cutoff (Hz), below half the log's sample rate.
        bridge_hz: the bandwidth the longest gap bridged is judged against (default: the
            cutoff; a filter run only to differentiate passes the estimation's cutoff).

    Raises:
        MotionLogError: see the module's list.
    """
    from scipy.signal import butter, sosfiltfilt

    if tuple(log.joint_names) != tuple(robot.joint_names):
        raise MotionLogError(
            f"the log's joints {log.joint_names} are not the arm's {robot.joint_names}"
        )
    t, q, tau, qd_log = _cut(log, window)
    rate = uniform_rate(t, log.source, cutoff_hz if bridge_hz is None else bridge_hz)
    t, q, tau, qd_log = on_grid(t, rate, q, tau, qd_log)
    if not (np.isfinite(cutoff_hz) and 0 < cutoff_hz < rate / 2):
        raise MotionLogError(
            f"the cutoff {cutoff_hz} Hz must be > 0 and below half the log's sample rate "
            f"({rate:.1f} Hz): record faster or choose a lower cutoff"
        )
    _check_limits(robot, q, t)
    sos = butter(FILTER_ORDER, cutoff_hz, fs=rate, output="sos")
    q_f = sosfiltfilt(sos, q, axis=0)
    _check_smooth(robot, q, q_f, cutoff_hz)
    if qd_log is not None:
        qd_f, velocity_from = sosfiltfilt(sos, qd_log, axis=0), "log"
    else:
        qd_f, velocity_from = np.gradient(q_f, t, axis=0), "positions"
    qdd_f = np.gradient(qd_f, t, axis=0)
    tau_f = sosfiltfilt(sos, tau, axis=0)
    peak = float(np.max(np.abs(qd_f)))
    if peak < MIN_PEAK_SPEED:
        raise MotionLogError(
            f"the arm barely moves in {log.source or 'the log'} (fastest joint "
            f"{peak:.3f} rad/s < {MIN_PEAK_SPEED}): inertia is seen only in motion; play an "
            "excitation motion (comgrasp plan-motion)"
        )
    return MotionSamples(t, q_f, qd_f, qdd_f, tau_f, float(cutoff_hz), rate, velocity_from)


def at_times(full: MotionSamples, times: np.ndarray) -> MotionSamples:
    """``full`` (at the log's rate) interpolated linearly at ``times`` (s), within its span."""
    times = np.asarray(times, float)
    if times.min() < full.t[0] or times.max() > full.t[-1]:
        raise MotionLogError(
            f"times {times.min():.2f}-{times.max():.2f} s fall outside the motion's "
            f"{full.t[0]:.2f}-{full.t[-1]:.2f} s: the two logs' motions do not overlap"
        )

    def interp(a):
        return np.column_stack([np.interp(times, full.t, col) for col in a.T])

    return MotionSamples(
        times, interp(full.q), interp(full.qd), interp(full.qdd), interp(full.tau),
        full.cutoff_hz, full.rate_hz, full.velocity_from,
    )  # fmt: skip


def _take(full: MotionSamples, idx: np.ndarray) -> MotionSamples:
    return MotionSamples(
        full.t[idx], full.q[idx], full.qd[idx], full.qdd[idx], full.tau[idx], full.cutoff_hz,
        full.rate_hz, full.velocity_from,
    )  # fmt: skip


def _cut(log: JointLog, window):
    """(t, q, tau, qd or None) within ``window``, at least ``MIN_DURATION_S`` long."""
    t = np.asarray(log.time, float)
    if window is None:
        sel = np.ones(len(t), bool)
    else:
        t0, t1 = window
        if not (t0 < t1) or t1 <= t[0] or t0 >= t[-1]:
            raise MotionLogError(
                f"the window {t0}:{t1} s is empty or outside the log (0 to {t[-1]:.2f} s)"
            )
        sel = (t >= t0) & (t <= t1)
    span = float(t[sel][-1] - t[sel][0]) if sel.sum() > 1 else 0.0
    if span < MIN_DURATION_S:
        raise MotionLogError(
            f"the motion lasts {span:.2f} s; at least {MIN_DURATION_S} s are needed (the "
            "filter's edges are dropped; a planned excitation motion lasts 10-20 s)"
        )
    qd = None if log.velocity is None else np.asarray(log.velocity, float)[sel]
    return t[sel], np.asarray(log.position, float)[sel], np.asarray(log.effort, float)[sel], qd


def _check_limits(robot: RobotModel, q: np.ndarray, t: np.ndarray) -> None:
    low = q - robot.q_lower < LIMIT_MARGIN
    high = robot.q_upper - q < LIMIT_MARGIN
    hit = np.flatnonzero((low | high).any(axis=0))
    if hit.size:
        j = int(hit[0])
        at = np.flatnonzero(low[:, j] | high[:, j])
        beyond = float(max(robot.q_lower[j] - q[:, j].min(), q[:, j].max() - robot.q_upper[j]))
        where = f"{t[at[0]]:.2f}-{t[at[-1]]:.2f} s"
        why = (
            f"it goes {beyond:.4g} beyond the URDF's limit: a limit that is not this robot's "
            "or an offset in the positions; if the arm really was at its stop there, "
            if beyond > LIMIT_MARGIN
            else "a stop's torques are not the payload's; "
        )
        raise MotionLogError(
            f"joint {robot.joint_names[j]} reaches its limit ({robot.q_lower[j]:.3f} to "
            f"{robot.q_upper[j]:.3f}) at {where}: {why}give a --window that leaves {where} "
            "out, or plan the motion within the limits"
        )


def _check_smooth(robot: RobotModel, q, q_f, cutoff_hz: float) -> None:
    above = np.sqrt(np.mean((q - q_f) ** 2, axis=0))
    spread = np.maximum(np.std(q, axis=0), 1e-9)
    share = above / spread
    j = int(np.argmax(share))
    if share[j] > MAX_ABOVE_CUTOFF and above[j] > 1e-4:
        raise MotionLogError(
            f"joint {robot.joint_names[j]} moves too jerkily for the {cutoff_hz} Hz filter: "
            f"{100 * share[j]:.0f} % of its motion (rms) is above the cutoff (at most "
            f"{100 * MAX_ABOVE_CUTOFF:.0f} %); raise the cutoff or play a smoother motion"
        )
