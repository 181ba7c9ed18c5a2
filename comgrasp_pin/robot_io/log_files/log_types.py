"""The two kinds of log every reader returns: ``JointLog`` and ``WrenchLog``.

``JointLog``: the joint readings (positions, efforts, velocities where logged), and their
common assembly (``assemble_log``; ``assemble_wrench_log`` for a ``WrenchLog``), so that
each reader (``joint_readers``: bags and the project's CSV; ``rtde``: Universal Robots
recordings; ``wrench_files``, ``wrench_sources``) builds one the same way without importing
the others.

``WrenchLog``: a wrist force/torque sensor's readings with the arm's joint positions. Every
wrench source (a ROS 2 bag's ``geometry_msgs/msg/WrenchStamped``, a CSV with
``force_x ... torque_z``, a UR recording's ``actual_TCP_force``, the simulated sensor) is
turned into one of these, the wrench in the sensor's own frame, so that the estimators see
one convention:

- ``wrench[:, :3]`` is the force (N) and ``wrench[:, 3:]`` the torque (N m) about the sensor
  frame's origin, both in the sensor frame's axes;
- it is the wrench the tool side (gripper and payload) applies to the sensor: at rest a
  hanging mass m reads f = m g (along gravity) and tau = c x m g (c its CoM in the sensor
  frame). This is the convention of ATI's and Robotiq's sensors and of UR's
  ``actual_TCP_force`` once moved to the sensor (``wrench_sources``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from comgrasp_pin import validate
from comgrasp_pin.errors import InvalidInputError, LogError

WRENCH_COLUMNS = ("force_x", "force_y", "force_z", "torque_x", "torque_y", "torque_z")
"""The CSV columns of a wrench, in the sensor frame (N, N m)."""


@dataclass(frozen=True)
class WrenchLog:
    """A wrist sensor's wrench and the arm's joint readings at the same times.

    Attributes:
        time: (N,) seconds from the log's first sample, non-decreasing.
        joint_names: the n arm joint names, in the order of the columns.
        position: (N, n) joint positions at the wrench's times (rad).
        wrench: (N, 6) force (N) and torque (N m) the tool side applies to the sensor, in
            ``sensor_frame`` (see the module docstring).
        sensor_frame: the URDF frame the wrench is measured in.
        source: the file (or simulation) the log came from.
        velocity: (N, n) joint velocities (rad/s), or None where the log has none.
        effort: (N, n) joint torques (N m) logged alongside, or None: with them, the
            estimators use both sources.
    """

    time: np.ndarray
    joint_names: tuple[str, ...]
    position: np.ndarray
    wrench: np.ndarray
    sensor_frame: str
    source: str = ""
    velocity: np.ndarray | None = None
    effort: np.ndarray | None = None

    def __post_init__(self) -> None:
        """Refuse bad arrays: real, finite, the shapes above."""
        for name in ("time", "position", "wrench", "velocity", "effort"):
            value = getattr(self, name)
            if value is not None:
                object.__setattr__(self, name, validate.real_array(value, f"WrenchLog.{name}"))
        n_samples, n = len(self.time), len(self.joint_names)
        shapes = {"position": (n_samples, n), "wrench": (n_samples, 6)}
        if self.velocity is not None:
            shapes["velocity"] = (n_samples, n)
        if self.effort is not None:
            shapes["effort"] = (n_samples, n)
        for name, shape in shapes.items():
            value = getattr(self, name)
            if value.shape != shape:
                raise LogError(
                    f"{self.source or 'wrench log'}: {name} has shape {value.shape}, "
                    f"expected {shape} ({n_samples} samples, {n} joints)"
                )
            if not np.all(np.isfinite(value)):
                raise LogError(f"{self.source or 'wrench log'} has NaN or inf in its {name}")
        if n_samples < 2 or not np.all(np.isfinite(self.time)):
            raise LogError(
                f"{self.source or 'wrench log'} needs at least two samples with finite times"
            )
        if np.any(np.diff(self.time) < 0):
            raise LogError(f"{self.source or 'wrench log'}: times must not decrease")

    @property
    def duration(self) -> float:
        """Seconds from the first to the last sample."""
        return float(self.time[-1] - self.time[0])


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


def sensor_frame_name(sensor_frame: object) -> str:
    """``sensor_frame`` when it is a non-empty string.

    Raises:
        InvalidInputError: anything else (None, an empty string, not a string).
    """
    if not isinstance(sensor_frame, str) or not sensor_frame:
        raise InvalidInputError(
            f"the sensor frame must be named (a frame of the URDF, the one the wrench is "
            f"measured in: sensor_frame=..., --sensor-frame), got {sensor_frame!r}"
        )
    return sensor_frame


def assemble_wrench_log(
    t: np.ndarray,
    position: np.ndarray,
    wrench: np.ndarray,
    names: tuple[str, ...],
    sensor_frame: str,
    source: str,
    velocity: np.ndarray | None = None,
    effort: np.ndarray | None = None,
) -> WrenchLog:
    """The read-only WrenchLog of a log's (N,) times (s) and (N, k) columns.

    Sorted by time (stable: samples with the same time keep the file's order), time from the
    first sample.

    Raises:
        LogError: fewer than two samples (WrenchLog refuses NaN, inf and wrong shapes).
    """
    if len(t) < 2:
        raise LogError(f"{source} has {len(t)} usable sample(s); a wrench log needs at least two")
    t = np.asarray(t, dtype=float)
    order = np.argsort(t, kind="stable")
    v, e = (None if a is None else _sorted(a, order) for a in (velocity, effort))
    return WrenchLog(_sorted(t - t[order[0]], order), names, _sorted(position, order),
                     _sorted(wrench, order), sensor_frame, source, v, e)  # fmt: skip


def _sorted(a: np.ndarray, order: np.ndarray) -> np.ndarray:
    """A read-only float copy of ``a``'s rows in ``order``."""
    out = np.asarray(a, dtype=float)[order]
    out.flags.writeable = False
    return out
