"""The simulated robot cell: ``procedures.cell.Cell`` on a MuJoCo ``World``.

Skills come from ``simulation.skills``, eyes from ``simulation.eyes``; what the procedures
announce is written on the video (when one is recorded) and logged with its time
(``phases``); the world's truth is kept for each announced phase and marked moment
(``snapshots``), for scoring only, never handed to the procedure.
"""

from __future__ import annotations

from contextlib import AbstractContextManager
from dataclasses import dataclass, replace

import numpy as np

from comgrasp_pin.geometry import GraspPose
from comgrasp_pin.perception import RodDetection, SideView
from comgrasp_pin.procedures.cell import TorqueMeasurement
from comgrasp_pin.simulation import eyes, skills
from comgrasp_pin.simulation.objects import ObjectState
from comgrasp_pin.simulation.scene import World


@dataclass(frozen=True)
class Snapshot:
    """The truth at an announced moment: the rod's state and where the jaws hold it along
    its true axis from its centre (m)."""

    truth: ObjectState
    grasp_offset: float


class SimCell:
    """The robot's skills and eyes in the simulated ``world`` (see ``procedures.cell.Cell``).

    Attributes:
        world: the simulated world. robot: the arm's Pinocchio model.
        snapshots: the truth at each announced phase or marked moment (the latest of each).
        phases: (simulated time (s), phase) of each announcement, in order.
        recorder: an ``EpisodeRecorder`` whose caption follows the announced phases, or None.
    """

    def __init__(self, world: World, recorder=None):
        self.world, self.robot = world, world.robot
        self._sim, self._rig = world.sim, world.rig
        self._motion, self._sensors = world.config.motion, world.config.sensors
        self.snapshots: dict[str, Snapshot] = {}
        self.phases: list[tuple[float, str]] = []
        self.recorder = recorder

    @property
    def q_des(self) -> np.ndarray:
        return self._sim.q_des

    @property
    def grip_force(self) -> float:
        return self._sim.grip_force

    @grip_force.setter
    def grip_force(self, force: float) -> None:
        self._sim.grip_force = force

    def finger_q(self) -> float:
        return float(self._sim.finger_q[0])

    def move_to(self, q, duration=None, v_max=None, a_max=None, settle=0.0) -> None:
        skills.move_to(self._sim, self._motion, q, duration, v_max, a_max, settle)

    def move_linear(self, T_world_ee: np.ndarray, duration: float) -> None:
        skills.move_linear(self._sim, self.robot, self._motion, T_world_ee, duration)

    def hold(self, duration: float) -> None:
        self._sim.hold(duration)

    def open_gripper(self, duration: float) -> None:
        skills.open_gripper(self._sim, self._motion, duration)

    def pick(self, grasp: GraspPose, grip_force: float, lift_height: float,
             lift_time: float) -> None:  # fmt: skip
        skills.pick(self._sim, self.robot, self._motion, grasp, grip_force, lift_height, lift_time)

    def place(self, T_world_ee: np.ndarray, lower_time: float) -> None:
        skills.place(self._sim, self.robot, self._motion, T_world_ee, lower_time)

    def carry_to_drop_box(self) -> None:
        skills.carry_to_drop_box(self._sim, self.robot, self._motion)

    def measure_torques(self, settle: float, window: float) -> TorqueMeasurement:
        torques, wrench = self._sim.measure(settle, window)  # the same window for both
        return replace(torques, wrench=wrench.wrench, wrench_std_error=wrench.std_error,
                       wrench_n_samples=wrench.n_samples)  # fmt: skip

    def look_from_above(self) -> RodDetection:
        return eyes.look_from_above(self._rig, self._sim.data)

    def look_from_side(self, q, rod_length, centre_hint) -> SideView:
        sensors = self._sensors
        return eyes.look_from_side(self._rig, self._sim.data, self.robot, q, rod_length,
                                   centre_hint, finger_q=self.finger_q(),
                                   frames=sensors.side_frames,
                                   frames_tolerance=sensors.side_frames_tolerance)  # fmt: skip

    def slip_watch(self, dt, grip_force, rod_length, centre_hint) -> eyes.SlipWatcher:
        return eyes.SlipWatcher(self._sim, self._rig, self.robot, dt, grip_force, rod_length,
                                centre_hint, self._sensors.watch_stride)  # fmt: skip

    def watching(self, watch: eyes.SlipWatcher) -> AbstractContextManager[None]:
        return self._sim.observing(watch)

    def announce(self, phase: str) -> None:
        self.mark(phase)
        self.phases.append((self._sim.time, phase))
        if self.recorder is not None:
            self.recorder.caption = phase

    def mark(self, moment: str) -> None:
        self.snapshots[moment] = Snapshot(self.world.truth(), self.world.grasp_offset_true())
