"""The robot cell a procedure drives: its skills, its eyes and its readings.

A procedure (``trial_grasp``, ``pick_and_place``) sees only what a real robot sees: joint
readings, averaged torques, camera measurements. ``Cell`` is the interface it needs; the
simulated cell (``comgrasp_pin.simulation.cell.SimCell``) implements it on MuJoCo, and a real
robot's driver can implement it on its own API. Poses in the world frame, SI units.
"""

from __future__ import annotations

from contextlib import AbstractContextManager
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from comgrasp_pin.geometry import GraspPose
from comgrasp_pin.perception import RodDetection, SideView, SlipMonitor
from comgrasp_pin.robot import RobotModel


@dataclass(frozen=True)
class TorqueMeasurement:
    """Averaged readings over a settling window at one arm configuration.

    Attributes:
        tau: (n,) mean reading (N m).
        std_error: (n,) standard error of the mean, from the samples' spread (N m).
        q: (n,) arm configuration during the window (rad), its mean.
        n_samples: number of samples averaged.
        duration: length of the window (s).
        time: the robot's clock when the window began (s; NaN: not known).
        wrench: (6,) the wrist force/torque sensor's mean over the same window: force (N)
            and torque (N m) the tool side applies to it, in its frame
            (``robot_io.log_files.wrench_log``'s convention); None: no wrist sensor.
        wrench_std_error: (6,) its standard error from the samples' spread; None without.
        wrench_n_samples: the wrist sensor's samples averaged (0 without one).
    """

    tau: np.ndarray
    std_error: np.ndarray
    q: np.ndarray
    n_samples: int
    duration: float
    time: float = float("nan")
    wrench: np.ndarray | None = None
    wrench_std_error: np.ndarray | None = None
    wrench_n_samples: int = 0


class SlipWatch(Protocol):
    """The side camera watching the held rod's tilt while it is attached (``Cell.watching``).

    Attributes:
        monitor: the tilt samples and the slip verdict (``perception.SlipMonitor``).
    """

    monitor: SlipMonitor

    def sample_now(self) -> None:
        """Take a frame now, whatever the period."""

    def slipping_or_tilted(self) -> bool:
        """True when slip was seen, or the rod is slipping at the last sample."""


class Cell(Protocol):
    """What a procedure can do and see. Durations in s, forces in N per finger.

    Attributes:
        robot: the arm's kinematic model (the same URDF the cell runs).
        q_des: (n,) the commanded configuration (rad).
        grip_force: the commanded force of each finger (N); positive closes.
    """

    robot: RobotModel
    q_des: np.ndarray
    grip_force: float

    def finger_q(self) -> float:
        """The fingers' closing reading (m; 0 is open)."""

    def move_to(self, q: np.ndarray, duration: float | None = None, v_max: float | None = None,
                a_max: float | None = None, settle: float = 0.0) -> None:  # fmt: skip
        """Joint move to ``q`` (None: shortest within the cell's limits), then hold."""

    def move_linear(self, T_world_ee: np.ndarray, duration: float) -> None:
        """Straight-line ee move to ``T_world_ee`` (4, 4)."""

    def hold(self, duration: float) -> None:
        """Keep the commanded configuration."""

    def open_gripper(self, duration: float) -> None:
        """Open the jaws and wait."""

    def pick(self, grasp: GraspPose, grip_force: float, lift_height: float,
             lift_time: float) -> None:  # fmt: skip
        """Approach, descend, close with ``grip_force``, lift the eelink to ``lift_height``."""

    def place(self, T_world_ee: np.ndarray, lower_time: float) -> None:
        """Lower to ``T_world_ee``, open, retreat upwards."""

    def carry_to_drop_box(self) -> None:
        """Carry what is held to the drop box and release it there."""

    def measure_torques(self, settle: float, window: float) -> TorqueMeasurement:
        """Hold still ``settle`` s, then average the joint torques over ``window`` s."""

    def look_from_above(self) -> RodDetection:
        """The rod on the table, from the top-down camera."""

    def look_from_side(self, q: np.ndarray, rod_length: float | None,
                       centre_hint: float | None) -> SideView:  # fmt: skip
        """The held rod in the jaws, from the side camera, at joint reading ``q``."""

    def slip_watch(self, dt: float, grip_force: float, rod_length: float | None,
                   centre_hint: float | None) -> SlipWatch:  # fmt: skip
        """A side-camera watch sampling every ``dt`` s once the jaws grip with ``grip_force``."""

    def watching(self, watch: SlipWatch) -> AbstractContextManager[None]:
        """Run ``watch`` during every motion inside the ``with`` block."""

    def announce(self, phase: str) -> None:
        """Say what the robot does now, until the next announcement (a log line, a video
        caption)."""

    def mark(self, moment: str) -> None:
        """Note a moment within a phase (a log line; the phase goes on)."""
