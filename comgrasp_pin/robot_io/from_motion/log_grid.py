"""A log's samples on a uniform grid, as a zero-phase filter expects them.

A logger's jitter and a controller's dropped cycles leave samples unevenly spaced (the
UR10e's RTDE log: 2-13 ms around 10 ms; the Panda's: 9 ms gaps in a 1 ms log). Gaps short
against the filter's cutoff are bridged by linear interpolation; a longer one is refused.
"""

from __future__ import annotations

import numpy as np

from comgrasp_pin.errors import MotionLogError

MAX_GAP_PERIODS = 0.1
"""Longest gap in a log bridged by interpolation, in periods of the cutoff (25 ms at 4 Hz)."""


def uniform_rate(t: np.ndarray, source: str, cutoff_hz: float) -> float:
    """The median sample rate (Hz); refuses a gap the filter cannot bridge.

    A gap up to ``MAX_GAP_PERIODS`` periods of the cutoff, or 5 samples, is bridged (a
    controller's dropped cycles, a logger's jitter): linear interpolation across it errs by
    less than (2 pi f_c gap)^2 / 8 of the motion's amplitude at the cutoff.
    """
    dt = np.diff(t)
    step = float(np.median(dt))
    if not step > 0:
        raise MotionLogError(f"{source or 'the log'}: the samples' times do not increase")
    longest = max(5 * step, MAX_GAP_PERIODS / cutoff_hz) if cutoff_hz > 0 else 5 * step
    if dt.max() > longest:
        i = int(np.argmax(dt))
        raise MotionLogError(
            f"{source or 'the log'} has a gap of {dt[i]:.3f} s at {t[i]:.2f} s (samples every "
            f"{step * 1e3:.1f} ms; gaps up to {longest * 1e3:.0f} ms are bridged): record "
            "without gaps, or give a --window that leaves it out"
        )
    return 1.0 / step


def on_grid(t, rate: float, *arrays):
    """The samples interpolated onto a uniform grid at ``rate`` (the filter assumes one)."""
    grid = t[0] + np.arange(int(np.floor((t[-1] - t[0]) * rate + 1e-9)) + 1) / rate
    if len(grid) == len(t) and np.allclose(grid, t, rtol=0, atol=1e-9):
        return (t, *arrays)

    def interp(a):
        if a is None:
            return None
        return np.column_stack([np.interp(grid, t, col) for col in np.asarray(a).T])

    return (grid, *(interp(a) for a in arrays))
