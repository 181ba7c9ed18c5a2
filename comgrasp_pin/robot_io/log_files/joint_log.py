"""JointLog, the joint readings every log reader returns, and their common assembly.

Its own module so that each reader (``logs``: bags and the project's CSV; ``rtde``: Universal
Robots recordings) builds a JointLog the same way without importing the others;
``comgrasp_pin.robot_io.log_files.joint_readers`` re-exports ``JointLog``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from comgrasp_pin import validate
from comgrasp_pin.errors import LogError


@dataclass(frozen=True)
class JointLog:
    """Joint readings over time for the arm's joints, in the robot model's joint order.

    Attributes:
        time: (N,) seconds from the log's first message, non-decreasing.
        joint_names: the n joint names, in the order of the columns.
        position: (N, n) joint positions (rad for revolute, m for prismatic joints).
        effort: (N, n) joint efforts (N m for revolute, N for prismatic joints).
        source: the file the log was read from.
        velocity: (N, n) joint velocities (rad/s or m/s) as the robot reported them, or
            None where the log has none (a motion's estimate then differentiates positions).
        current_gains: (n,) drive gains, N m per A, that made ``effort`` from the log's motor
            currents (a UR arm logs currents, not torques), or None where the efforts are
            the joint torques as logged.
    """

    time: np.ndarray
    joint_names: tuple[str, ...]
    position: np.ndarray
    effort: np.ndarray
    source: str = ""
    velocity: np.ndarray | None = None
    current_gains: np.ndarray | None = None

    def __post_init__(self) -> None:
        """Refuse complex, boolean, string and object arrays (validate.real_array)."""
        for name in ("time", "position", "effort", "velocity", "current_gains"):
            value = getattr(self, name)
            if value is not None:
                object.__setattr__(self, name, validate.real_array(value, f"JointLog.{name}"))

    @property
    def duration(self) -> float:
        """Seconds from the first to the last sample."""
        return float(self.time[-1] - self.time[0]) if len(self.time) else 0.0


def assemble_log(
    t: np.ndarray,
    position: np.ndarray,
    effort: np.ndarray,
    velocity: np.ndarray | None,
    names: tuple[str, ...],
    source: str,
    current_gains: np.ndarray | None = None,
) -> JointLog:
    """The read-only JointLog of a log's columns: (N,) times (s), (N, n) readings.

    Sorted by time (stable: samples with the same time keep the file's order), time from the
    first sample.

    Raises:
        LogError: fewer than two samples; a time, position, effort or velocity NaN or inf.
    """
    if len(t) < 2:
        raise LogError(f"{source} has {len(t)} usable sample(s); a log needs at least two")
    t = np.asarray(t, dtype=float)
    if not np.all(np.isfinite(t)):
        raise LogError(f"{source} has NaN or inf times; every sample needs a time (s)")
    order = np.argsort(t, kind="stable")
    t = t[order] - t[order[0]]
    position = np.asarray(position, dtype=float)[order]
    effort = np.asarray(effort, dtype=float)[order]
    if not (np.all(np.isfinite(position)) and np.all(np.isfinite(effort))):
        raise LogError(f"{source} has NaN or inf joint positions or efforts")
    if velocity is not None:
        velocity = np.asarray(velocity, dtype=float)[order]
        if not np.all(np.isfinite(velocity)):
            raise LogError(f"{source} has NaN or inf joint velocities")
    if current_gains is not None:
        current_gains = np.array(current_gains, dtype=float)
    for a in (t, position, effort, velocity, current_gains):
        if a is not None:
            a.flags.writeable = False
    return JointLog(t, names, position, effort, source, velocity, current_gains)
