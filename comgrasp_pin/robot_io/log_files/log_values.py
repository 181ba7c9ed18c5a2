"""Values no sensor gives: the one check every log reader runs on what it read.

A log's numbers reach the fit unseen: NaN, inf, or a finite value past any sensor's range
(``1e300`` A written over a current by a broken export, a time in ns in a column of s)
would give a confident, wrong payload. Every reader (the project's CSV and a UR recording:
``check_table``; a ROS 2 bag's JointState and WrenchStamped messages: ``check_messages``)
refuses them here, naming the file, the line as a text editor numbers it (the header is
line 1) or the message (its time and topic), the column or joint and field, the value and
the valid range. The ceilings are ``comgrasp_pin.config.log_limits``: physical ones, ten
times above any real sensor's readings, never tuned to a data set.

A log's times, for a zero-phase filter that wants them uniform (``uniform_rate``, ``on_grid``):
a logger's jitter and a controller's dropped cycles leave samples unevenly spaced (the UR10e's
RTDE log: 2-13 ms around 10 ms; the Panda's: 9 ms gaps in a 1 ms log). Gaps short against
the filter's cutoff are bridged by linear interpolation; a longer one is refused.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from comgrasp_pin.config import log_limits as lim
from comgrasp_pin.errors import InvalidInputError, LogError, MotionLogError

LIMITS = {
    "time": (lim.MAX_ABS_TIME_S, "a time (s; seconds, not ms or ns)", "MAX_ABS_TIME_S"),
    "position": (lim.MAX_ABS_JOINT_POSITION_RAD, "a joint position (rad, or m)",
                 "MAX_ABS_JOINT_POSITION_RAD"),
    "velocity": (lim.MAX_ABS_JOINT_VELOCITY_RAD_S, "a joint velocity (rad/s, or m/s)",
                 "MAX_ABS_JOINT_VELOCITY_RAD_S"),
    "effort": (lim.MAX_ABS_JOINT_EFFORT, "a joint effort (a torque in N m, a force in N, or a "
               "motor current in A)", "MAX_ABS_JOINT_EFFORT"),
    "force": (lim.MAX_ABS_FORCE_N, "a force (N)", "MAX_ABS_FORCE_N"),
    "torque": (lim.MAX_ABS_TORQUE_NM, "a torque (N m)", "MAX_ABS_TORQUE_NM"),
}  # fmt: skip
"""Per kind of value: (the largest magnitude, what it is, the log_limits constant)."""

_PATTERNS = (
    ("time", r"time|timestamp"),
    ("position", r".+\.position|actual_q_\d+"),
    ("velocity", r".+\.velocity|actual_qd_\d+"),
    ("effort", r".+\.effort|actual_current_\d+|actual_current_as_torque_\d+"),
    ("force", r"force_[xyz]|actual_TCP_force_[012]"),
    ("torque", r"torque_[xyz]|actual_TCP_force_[345]"),
)


def column_kind(name: str) -> str:
    """The kind of value (a key of ``LIMITS``) a log column holds, by its header name.

    The project's CSV (``time``, ``J.position``, ``J.velocity``, ``J.effort``, ``force_x``
    ... ``torque_z``) and UR's RTDE names (``timestamp``, ``actual_q_i``, ``actual_qd_i``,
    ``actual_current_i``, ``actual_current_as_torque_i``, ``actual_TCP_force_i``: force
    i = 0..2, torque 3..5).

    Raises:
        InvalidInputError: a name of none of these kinds.
    """
    for kind, pattern in _PATTERNS:
        if re.fullmatch(pattern, name):
            return kind
    raise InvalidInputError(
        f"no range is known for the log column {name!r}; the columns read are times, joint "
        "positions, velocities and efforts, forces and torques (see log_values._PATTERNS)"
    )


def _out_of_range(values: np.ndarray, kinds: list[str]) -> np.ndarray:
    """(N, k) bool: the finite ``values`` whose magnitude passes their column's ceiling."""
    ceiling = np.array([LIMITS[k][0] for k in kinds], dtype=float)
    return np.isfinite(values) & (np.abs(values) > ceiling)


def _problem(values: np.ndarray, kinds: list[str]) -> tuple[str, int, int, int] | None:
    """(problem, count, row, column) of the first bad value, or None where all are sound.

    The first NaN / inf, else the first value past its ceiling; rows first (the file's order).
    """
    for problem, bad in (("nan", ~np.isfinite(values)), ("range", _out_of_range(values, kinds))):
        found = np.argwhere(bad)
        if len(found):
            return problem, len(found), int(found[0][0]), int(found[0][1])
    return None


def _message(source: str, where: str, label: str, problem: str, count: int, value: float,
             kind: str) -> str:  # fmt: skip
    if problem == "nan":
        return (f"{source} has NaN or inf values ({count}), first {where} in {label!r}; every "
                "value the log is read for must be a number")  # fmt: skip
    limit, what, name = LIMITS[kind]
    return (
        f"{source} has values no sensor gives ({count}), first {where} in {label!r}: "
        f"{value:.6g}, where {what} lies within +-{limit:g} (config.log_limits.{name}); the "
        "file is damaged or the column holds another quantity: repair it or record it again"
    )


def check_table(data: np.ndarray, columns: list[str], path: str | Path, source: str) -> None:
    """Refuse NaN, inf and values no sensor gives in a text log's (N, k) ``data``.

    ``data`` holds the file's rows below its header, in order, under the k ``columns``
    (header names, ``column_kind``); ``path`` is read again, only where a value is refused,
    to name its line as a text editor shows it (the header is line 1; blank and ``#``
    comment lines, which the loader skipped, are counted). ``source`` names the log.

    Raises:
        LogError: how many values are bad, the first one's line, column, value and the
            range of its kind (``LIMITS``).
    """
    kinds = [column_kind(c) for c in columns]
    found = _problem(np.asarray(data, dtype=float), kinds)
    if found is not None:
        problem, count, row, col = found
        where = f"on line {file_line(path, row)}"
        raise LogError(_message(source, where, columns[col], problem, count,
                                float(data[row, col]), kinds[col]))  # fmt: skip


def file_line(path: str | Path, row: int, header_lines: int = 1) -> int:
    """The 1-based line of the text file ``path`` that holds data row ``row`` (0-based).

    Rows as ``numpy.loadtxt`` counts them below ``header_lines`` lines: lines that are empty
    once a ``#`` comment is cut off are not rows.
    """
    with open(path, encoding="utf-8", errors="replace") as f:
        seen = -1
        for number, line in enumerate(f, start=1):
            if number > header_lines and line.split("#", 1)[0].strip():
                seen += 1
                if seen == row:
                    return number
    return header_lines + row + 1  # not reached for a row the loader read


def check_messages(values: np.ndarray, kinds: list[str], labels: list[str], times_ns,
                   topic: str, source: str, t0_ns: int | None = None) -> None:  # fmt: skip
    """Refuse NaN, inf and values no sensor gives in a bag topic's messages.

    Args:
        values: (N, k) one row per message, in the order read.
        kinds: the k columns' kinds (keys of ``LIMITS``).
        labels: the k columns' names (a joint and field, a wrench component).
        times_ns: (N,) each message's time, ns (its header stamp, or where that is zero
            its receive time).
        topic: the messages' topic.
        source: the bag, for the message.
        t0_ns: the time of the topic's first message read (ns); None: the earliest of
            ``times_ns``.

    Raises:
        LogError: how many values are bad; the first one's message (its time, ns since the
            epoch as s, and s from the topic's first message), column, value and range.
    """
    found = _problem(np.asarray(values, dtype=float), kinds)
    if found is not None:
        problem, count, row, col = found
        ns = int(times_ns[row])
        t0 = int(np.min(times_ns)) if t0_ns is None else int(t0_ns)
        where = (f"in the message of topic {topic!r} at {ns // 10**9}.{ns % 10**9:09d} s "
                 f"({(ns - t0) / 1e9:.3f} s after its first message)")  # fmt: skip
        raise LogError(_message(source, where, labels[col], problem, count,
                                float(values[row][col]), kinds[col]))  # fmt: skip


def check_joint_rows(rows: list[tuple], names: tuple[str, ...], topic: str, source: str) -> None:
    """``check_messages`` on JointState rows (stamp, receive time, position, effort, velocity).

    Each field is checked where the messages carry it; times are the header stamps, or the
    receive times where a stamp is zero (as ``logs`` times them).
    """
    stamps = np.array([r[0] for r in rows], dtype=np.int64)
    times = stamps if np.all(stamps > 0) else np.array([r[1] for r in rows], dtype=np.int64)
    for at, field in ((2, "position"), (3, "effort"), (4, "velocity")):
        have = [i for i, r in enumerate(rows) if r[at] is not None]
        if have:
            values = np.array([rows[i][at] for i in have], dtype=float)
            check_messages(values, [field] * len(names), [f"{n} {field}" for n in names],
                           times[have], topic, source, int(times.min()))  # fmt: skip


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
