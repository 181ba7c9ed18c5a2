"""The empty-arm run aligned in time with the loaded run: the same motion, wherever it starts.

Two runs of one planned motion, one holding the payload and one empty, start the motion at
different moments of their logs. The empty run's filtered signals (``filtered_signals``) are
wanted at the loaded samples' states, i.e. at ``S.t + shift`` (empty time = loaded time +
shift). The shift is the one that brings the two runs' joint positions closest (rms over the
samples and joints), searched over every shift at which the runs overlap:

1. coarse: both runs' positions on one uniform grid (``COARSE_PER_CUTOFF`` points per second
   per Hz of cutoff, above the positions' Nyquist rate), the mean squared distance at every
   grid lag from cross-correlations (``scipy.signal.correlate``, FFT), counting only the
   samples where the runs overlap, at least ``MIN_OVERLAP`` of the loaded span; of the lags
   within ``REPEAT_RAD`` (rms) of the best, the one that overlaps most: a motion of
   repeated periods (plan-motion's) matches itself one period off as well over a shorter
   overlap;
2. fine: around the coarse best, every shift at the empty log's own rate, the loaded samples'
   own times interpolated exactly, then a parabola through the three best for a fraction of a
   sample.

Refused, each a ``MotionLogError`` that says why and what would work:
- the positions still ``MAX_GAP_RAD`` apart (rms) at the best shift: not the same motion;
- the empty run (or its window) misses the start or the end of the loaded samples at the best
  shift: which part, how many seconds, and the loaded window both runs cover.

The loaded samples should hold the motion only (``motion_samples(..., crop=True)``): the
still parts before and after it are not needed to align, and an empty run with shorter still
parts would otherwise miss them.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from comgrasp_pin.errors import MotionLogError
from comgrasp_pin.robot import RobotModel
from comgrasp_pin.robot_io.from_motion.motion_signals import (
    CUTOFF_HZ,
    MOTION_SPEED,
    MotionSamples,
    at_times,
    filtered_signals,
    find_motion,
)
from comgrasp_pin.robot_io.log_files.joint_readers import JointLog

__all__ = ["MAX_GAP_RAD", "MOTION_SPEED", "Alignment", "align_empty", "find_motion"]

MAX_GAP_RAD = 0.05
"""Largest rms distance (rad) of the two runs' positions at the best shift: further apart, the
logs are not the same motion (a replayed motion repeats within a few mrad)."""
MIN_OVERLAP = 0.5
"""Shortest overlap searched, a share of the loaded samples' span: a shorter one can match
still parts (the same rest pose) instead of the motion."""
COARSE_PER_CUTOFF = 4.0
"""The coarse grid's points per second per Hz of cutoff (4 Hz -> every 1/16 s): twice the
filtered positions' Nyquist rate, so the distance between grid lags is not aliased."""
REPEAT_RAD = 1e-3
"""Shifts whose rms position distance is within this (rad) of the best match as well: the
coarse search takes the one with the longest overlap."""
REFINE_COARSE_STEPS = 2
"""The fine search spans this many coarse steps either side of the coarse best."""


@dataclass(frozen=True)
class Alignment:
    """How the empty run was laid on the loaded one.

    Attributes:
        shift_s: empty time = loaded time + shift (s, each from its log's first message).
        rms_gap_rad: the positions' rms distance at that shift, over samples and joints (rad).
        loaded_motion_s: (t0, t1) s of the loaded log compared: its samples' span (the found
            motion, or the window given).
        empty_motion_s: (t0, t1) s of the empty log they fall on (the loaded span + shift).
        method: "found" (the motion found in the logs) or "windows" (a window was given).
    """

    shift_s: float
    rms_gap_rad: float
    loaded_motion_s: tuple[float, float]
    empty_motion_s: tuple[float, float]
    method: str

    def as_dict(self) -> dict:
        """JSON-ready, for RESULT.json's ``alignment``."""
        return {
            "shift_s": self.shift_s,
            "rms_gap_rad": self.rms_gap_rad,
            "loaded_motion_s": list(self.loaded_motion_s),
            "empty_motion_s": list(self.empty_motion_s),
            "method": self.method,
        }


def align_empty(
    robot: RobotModel,
    S: MotionSamples,
    empty_log: JointLog,
    empty_window: tuple[float, float] | None = None,
    cutoff_hz: float = CUTOFF_HZ,
    *,
    window: tuple[float, float] | None = None,
) -> tuple[MotionSamples, Alignment]:
    """The empty run's filtered signals at the loaded samples' states, and the alignment.

    Args:
        robot: the arm (the logs' joints in its order).
        S: the loaded run's samples (``motion_samples``; best cropped to the motion).
        empty_log: the same motion with the empty arm.
        empty_window: (t0, t1) s of ``empty_log`` to search, or None for all of it.
        cutoff_hz: the low-pass filter's cutoff (Hz), the loaded run's.
        window: the loaded run's window if one was given (``S`` is already cut to it); only
            recorded in ``Alignment.method``.

    Returns:
        (E, alignment): E at times ``S.t + alignment.shift_s`` of the empty log.

    Raises:
        MotionLogError: the empty log is unusable (``filtered_signals``), is not the same
            motion, or misses part of the loaded samples.
    """
    full = filtered_signals(robot, empty_log, empty_window, cutoff_hz)
    where = "the empty run's window" if empty_window is not None else "the empty log"
    span_s, span_e = float(S.t[-1] - S.t[0]), float(full.t[-1] - full.t[0])
    if span_e < MIN_OVERLAP * span_s:
        raise MotionLogError(
            f"{where} lasts {span_e:.1f} s, less than {MIN_OVERLAP:.0%} of the loaded motion's "
            f"{span_s:.1f} s ({S.t[0]:.2f}-{S.t[-1]:.2f} s): record the whole motion with the "
            "empty arm" + (", or widen its window" if empty_window is not None else "")
        )
    coarse = _coarse_shift(S, full, cutoff_hz)
    shift = _fine_shift(S, full, coarse)
    gap = np.sqrt(_mean_square(S, full, np.array([shift]))[0])
    if not gap <= MAX_GAP_RAD:
        raise MotionLogError(
            f"the empty run does not follow the loaded motion: at the best alignment (empty "
            f"time = loaded time {shift:+.2f} s) their positions are {gap:.3f} rad apart (rms; "
            f"at most {MAX_GAP_RAD} for the same motion): the two logs are not the same "
            "motion; record the same planned motion with the empty arm"
            + (", or check the windows" if window or empty_window else "")
        )
    shift = _covering(S, full, shift, gap, where)
    E = at_times(full, S.t + shift)
    gap = float(np.sqrt(np.mean((E.q - S.q) ** 2)))
    method = "windows" if window is not None or empty_window is not None else "found"
    t0, t1 = float(S.t[0]), float(S.t[-1])
    return E, Alignment(shift, gap, (t0, t1), (t0 + shift, t1 + shift), method)


def _coarse_shift(S: MotionSamples, full: MotionSamples, cutoff_hz: float) -> float:
    """The best shift on a uniform grid, from cross-correlations (partial overlaps counted)."""
    from scipy.signal import correlate, correlation_lags

    h = 1.0 / (COARSE_PER_CUTOFF * cutoff_hz)
    grid_s = S.t[0] + h * np.arange(int(np.floor((S.t[-1] - S.t[0]) / h)) + 1)
    grid_e = full.t[0] + h * np.arange(int(np.floor((full.t[-1] - full.t[0]) / h)) + 1)
    mean = S.q.mean(axis=0)  # a common offset: the distances stay, the sums stay small
    s = _resampled(S.t, S.q - mean, grid_s)
    e = _resampled(full.t, full.q - mean, grid_e)
    ones_s, ones_e = np.ones(len(s)), np.ones(len(e))
    # sum over the overlap of |e[n + k] - s[n]|^2 = sum |e|^2 - 2 sum e.s + sum |s|^2
    cross = sum(correlate(e[:, j], s[:, j]) for j in range(s.shape[1]))
    ee = correlate(np.sum(e**2, axis=1), ones_s)
    ss = correlate(ones_e, np.sum(s**2, axis=1))
    count = np.rint(correlate(ones_e, ones_s))
    lags = correlation_lags(len(e), len(s))
    enough = count >= MIN_OVERLAP * len(s)
    mean_square = np.where(enough, (ee - 2 * cross + ss) / np.maximum(count, 1), np.inf)
    rms = np.sqrt(np.maximum(mean_square, 0.0))
    near = rms <= rms.min() + REPEAT_RAD
    k = int(lags[np.lexsort((mean_square, -np.where(near, count, -1)))[0]])
    return float(grid_e[0] + k * h - grid_s[0])


def _fine_shift(S: MotionSamples, full: MotionSamples, coarse: float) -> float:
    """The best shift at the empty log's rate near ``coarse``, then to a fraction of a step."""
    step = 1.0 / full.rate_hz
    half = int(np.ceil(REFINE_COARSE_STEPS / (COARSE_PER_CUTOFF * S.cutoff_hz) / step))
    offsets = np.arange(-half, half + 1)
    centre = coarse
    for _ in range(5):  # re-centred while the best is at the span's edge
        shifts = centre + step * offsets
        ms = _mean_square(S, full, shifts)
        i = int(np.argmin(ms))
        centre = float(shifts[i])
        if 0 < i < len(shifts) - 1:
            break
    if not (0 < i < len(shifts) - 1 and np.all(np.isfinite(ms[i - 1 : i + 2]))):
        return centre
    a, b, c = ms[i - 1 : i + 2]
    curvature = a - 2 * b + c
    delta = float(np.clip(0.5 * (a - c) / curvature, -0.5, 0.5)) if curvature > 0 else 0.0
    best = centre + delta * step
    return best if _mean_square(S, full, np.array([best]))[0] <= b else centre


def _mean_square(S: MotionSamples, full: MotionSamples, shifts: np.ndarray) -> np.ndarray:
    """(len(shifts),) mean squared position distance over the overlap (inf if too short)."""
    times = S.t[None, :] + shifts[:, None]
    inside = (times >= full.t[0]) & (times <= full.t[-1])
    total = np.zeros(len(shifts))
    for j in range(S.q.shape[1]):
        e = np.interp(times, full.t, full.q[:, j])
        total += np.sum(np.where(inside, (e - S.q[None, :, j]) ** 2, 0.0), axis=1)
    count = inside.sum(axis=1)
    enough = count >= MIN_OVERLAP * len(S.t)
    return np.where(enough, total / np.maximum(count * S.q.shape[1], 1), np.inf)


def _covering(S: MotionSamples, full: MotionSamples, shift: float, gap: float, where: str):
    """``shift`` where the empty run covers every loaded sample (to half a sample).

    Else a refusal that says which part it misses and the loaded window both runs cover.
    """
    lo, hi = float(full.t[0] - S.t[0]), float(full.t[-1] - S.t[-1])
    missing_start, missing_end = max(0.0, lo - shift), max(0.0, shift - hi)
    tolerance = 0.5 / full.rate_hz
    if missing_start <= tolerance and missing_end <= tolerance:
        return float(np.clip(shift, lo, hi)) if lo <= hi else shift
    t0, t1 = float(S.t[0]), float(S.t[-1])
    parts = []
    if missing_start > tolerance:
        parts.append(
            f"the start of the loaded motion: its first {missing_start:.2f} s (loaded "
            f"{t0:.2f}-{t0 + missing_start:.2f} s) fall before {where} starts"
        )
    if missing_end > tolerance:
        parts.append(
            f"the end of the loaded motion: its last {missing_end:.2f} s (loaded "
            f"{t1 - missing_end:.2f}-{t1:.2f} s) fall after {where} ends"
        )
    if "window" in where:
        fix = f"Widen the empty run's window ({full.t[0]:.2f}-{full.t[-1]:.2f} s now)"
    else:
        fix = (
            "Record the empty run a little longer before and after the motion (a second or "
            "two still at each end)"
        )
    raise MotionLogError(
        f"the empty run misses {' and '.join(parts)}, at the best alignment (empty time = "
        f"loaded time {shift:+.2f} s, positions {gap:.4f} rad apart rms). {fix}, or give the "
        f"loaded run --window {t0 + missing_start:.2f}:{t1 - missing_end:.2f} to use only "
        "the part both runs cover"
    )


def _resampled(t: np.ndarray, a: np.ndarray, grid: np.ndarray) -> np.ndarray:
    return np.column_stack([np.interp(grid, t, col) for col in a.T])
