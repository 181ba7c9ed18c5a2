"""WrenchLog: a wrist force/torque sensor's readings with the arm's joint positions.

Every wrench source (a ROS 2 bag's ``geometry_msgs/msg/WrenchStamped``, a CSV with
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
from comgrasp_pin.errors import LogError

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
