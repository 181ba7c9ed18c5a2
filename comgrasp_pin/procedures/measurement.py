"""A trial grasp's measurement: what the robot read, and what it made of it.

``HeldReadings`` is what the robot read holding the rod (torques at each measurement pose,
the side views); ``com_location.locate_com`` turns them, with tau_before, into the
estimates; ``TrialMeasurement`` is the trial grasp's result. No ground truth here.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from comgrasp_pin.estimation import ComEstimate
from comgrasp_pin.perception import SideView


@dataclass(frozen=True)
class TrialMeasurement:
    """What one trial grasp measured (no ground truth in it).

    Attributes:
        theta: tilt of the rod in the jaws seen by the side camera (rad).
        slip_seen: the slip monitor's verdict.
        T_ee_obj: (4, 4) rod pose in the ee frame from the side camera.
        x_com_obj: estimated CoM along the perceived rod from its perceived centre (m).
        x_com_line: the same from the paper's single-pose estimate (the CoM line met with
            the rod axis), from the same measurements.
        rolled_slip: the rod turned in the jaws by more than ``roll_slip_deg`` at the rolled
            pose (the two poses are stacked with the rod's motion all the same).
        dropped_at_roll: the side camera found nothing in the jaws at the rolled pose.
        mass_esti: kg. rod_length: as the top view measured it (m).
        grasp_z: eelink height of the grasp (m); rod_axis_z: height of the rod's axis on
            the table, from the top view (m).
        estimate: the ComEstimate used; estimate_line: the single-pose one.
        q_meas: (k, 6) measurement configurations (rad); tau_before, tau_after: (k, 6)
            averaged torque readings there (N m).
        T_world_ee: (4, 4) ee pose at the first measurement configuration.
        side_view: the side camera's view at the first measurement pose.
        x_com_std: standard deviation of the estimated CoM point along the rod (m), from
            every source the robot knows (``ComLocation.std``); std_parts: by source.
        com_path: how the CoM was located: "one pose" or "k poses".
        extra_pose: the CoM was known too poorly after the planned poses
            (``planning.regrasp.needs_another_pose``), so one more was measured.
        by_source: the CoM located from the same readings' other sources, recorded beside
            the one the robot used: {"wrench": the wrist sensor's, "both": the wrench and the
            joint torques stacked}, each a ``ComLocation`` or the message of why it failed;
            empty without a wrist sensor.
    """

    theta: float
    slip_seen: bool
    T_ee_obj: np.ndarray
    x_com_obj: float
    x_com_line: float
    rolled_slip: bool
    dropped_at_roll: bool
    mass_esti: float
    rod_length: float
    grasp_z: float
    rod_axis_z: float
    estimate: ComEstimate
    estimate_line: ComEstimate
    q_meas: np.ndarray
    tau_before: np.ndarray
    tau_after: np.ndarray
    T_world_ee: np.ndarray
    side_view: SideView
    x_com_std: float
    std_parts: dict
    com_path: str
    extra_pose: bool
    by_source: dict = field(default_factory=dict)


@dataclass(frozen=True)
class HeldReadings:
    """The held rod's readings at each measurement pose.

    Attributes:
        after: the averaged torques per pose (``TorqueMeasurement``).
        tau_before: (n,) the empty arm's torques per pose (N m).
        before: their measurements (``TorqueMeasurement``), None where the model gave them.
        views: the side view per pose, None where the camera saw nothing usable.
        moved: the rod turned in the jaws by more than ``roll_slip_deg`` at a later pose.
        dropped: the camera found nothing in the jaws at a later pose.
        slip_seen: the slip monitor's verdict while the rod was lifted and held.
        heavy_side: (3,) the world direction of the rod's end that went down, from the
            largest tilt the watch saw meanwhile (``trial_steps.heavy_side``); None: none
            seen.
    """

    after: list
    tau_before: list
    before: list
    views: list
    moved: bool
    dropped: bool
    slip_seen: bool
    heavy_side: np.ndarray | None = None

    @property
    def side(self) -> SideView:
        """The view at the first pose (always there)."""
        return self.views[0]

    def with_pose(self, after, tau_before: np.ndarray, view: SideView | None) -> HeldReadings:
        """These readings and one more pose's."""
        return replace(self, after=[*self.after, after], tau_before=[*self.tau_before,
                       tau_before], before=[*self.before, None],
                       views=[*self.views, view])  # fmt: skip
