"""A trial grasp's measurement, and where the CoM lies according to it.

``HeldReadings`` is what the robot read holding the rod (torques at each measurement pose,
the side views); ``locate_com`` turns them, with tau_before, into the estimates;
``TrialMeasurement`` is the trial grasp's result. No ground truth here.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from comgrasp_pin.config import EpisodeConfig
from comgrasp_pin.estimation import AxisPrior, ComEstimate, com_along_axis, estimate_com
from comgrasp_pin.perception import SideView
from comgrasp_pin.procedures import torques, uncertainty
from comgrasp_pin.procedures.rod_motion import depth_agrees, rod_motion
from comgrasp_pin.robot import RobotModel


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
    """

    after: list
    tau_before: list
    before: list
    views: list
    moved: bool
    dropped: bool
    slip_seen: bool

    @property
    def side(self) -> SideView:
        """The view at the first pose (always there)."""
        return self.views[0]

    def with_pose(self, after, tau_before: np.ndarray, view: SideView | None) -> HeldReadings:
        """These readings and one more pose's."""
        return replace(self, after=[*self.after, after], tau_before=[*self.tau_before,
                       tau_before], before=[*self.before, None],
                       views=[*self.views, view])  # fmt: skip


def axis_prior(side: SideView) -> AxisPrior:
    """The prior on the CoM from the side view: near the rod's axis. The CoM lies within the
    rod's cross-section, which the side camera sees reach ``off_axis`` from the axis; half of
    that is one standard deviation across the axis, combined with how well the axis itself
    was located (``axis_std``)."""
    std = float(np.hypot(0.5 * side.off_axis, side.axis_std))
    return AxisPrior.from_rod(side.T_ee_obj, std)


@dataclass(frozen=True)
class ComLocation:
    """Where the CoM lies along the rod, by which path, and how well it is known.

    Attributes:
        estimate: the estimate used; estimate_line: the paper's (one pose, least squares).
        x_com: CoM along the perceived rod from its perceived centre (m); x_line: the
            paper's (the vertical CoM line met with the axis).
        path: "one pose", or "k poses" with k their number (see ``locate_com``).
        std: the standard deviation of the CoM point along the rod (m), from every source
            in ``std_parts`` (``procedures.uncertainty``): estimator, slip, tilt, views.
    """

    estimate: ComEstimate
    estimate_line: ComEstimate
    x_com: float
    x_line: float
    path: str
    std: float
    std_parts: dict


def locate_com(robot: RobotModel, held: HeldReadings, config: EpisodeConfig) -> ComLocation:
    """The CoM along the rod from the readings.

    The paper's: one pose, least squares, the vertical CoM line met with the rod's axis.
    Ours (``estimator``: "ipopt" adds the side view's ``axis_prior``; "lstsq" is the closed
    form without it): every pose whose view saw the rod, stacked with the rod's motion in
    the jaws since the first (``rod_motion``), the 3-D CoM projected on the axis; the first
    pose alone when no other view saw it. A payload not measurably above zero:
    EmptyGripperError.
    """
    trial, after = config.trial, held.after
    side, T_obj = held.side, held.side.T_ee_obj
    use = [i for i, view in enumerate(held.views) if view is not None]
    noise = torques.pair_noise([held.before[i] for i in use], [after[i] for i in use], config)
    q = np.array([after[i].q for i in use])
    tau_a = np.array([after[i].tau for i in use])
    tau_b = np.array([held.tau_before[i] for i in use])
    views = [held.views[i] for i in use]

    def estimate(k: int, method: str, prior: AxisPrior | None) -> ComEstimate:
        first = noise.first(k, robot.nq)
        return estimate_com(robot, q[:k], tau_b[:k], tau_a[:k], method=method,
                            torque_std=first.std, com_prior=prior,
                            dtau_cov=first.cov)  # fmt: skip

    est_line = estimate(1, "lstsq", None)
    x_line = com_along_axis(est_line, T_obj)
    prior = axis_prior(side) if trial.estimator == "ipopt" else None
    est = est_line if prior is None else estimate(1, "ipopt", prior)
    x_com, path = com_along_axis(est, T_obj), "one pose"
    parts = {"tilt": uncertainty.tilt_std_one_view(est, T_obj, side.tilt_std)}
    if len(use) > 1:
        # Several poses, the rod where each view saw it: the CoM is fixed in the rod, so
        # the poses stack with the rod's motion since the first (the grasp's compliance, a
        # slip).
        bounds = (trial.max_depth_shift, np.radians(trial.max_depth_turn_deg))
        depth = [depth_agrees(side, v, *bounds) for v in views[1:]]
        motion = np.stack(
            [np.eye(4)]
            + [rod_motion(side, v, depth=d) for v, d in zip(views[1:], depth, strict=True)]
        )
        est = estimate_com(robot, q, tau_b, tau_a, method=trial.estimator,
                           torque_std=noise.std, com_prior=prior, payload_motion_ee=motion,
                           dtau_cov=noise.cov)  # fmt: skip
        x_com, path = com_along_axis(est, T_obj), f"{len(use)} poses"
        parts = uncertainty.motion_stds(robot, q, tau_b, tau_a, est, T_obj, views, depth,
                                        bounds, trial.estimator, noise, prior)  # fmt: skip
    parts["estimator"] = uncertainty.estimator_std(est, T_obj)
    cal = config.sensors.side_depth
    if side.camera_ee is not None and cal.enabled:
        parts["calibration"] = uncertainty.calibration_std(
            est, T_obj, side.camera_ee, cal.extrinsic_shift,
            np.radians(cal.extrinsic_turn_deg), cal.scale_std)  # fmt: skip
    if path == "one pose" and prior is None:
        # the closed form meets the vertical CoM line with the axis: a CoM off the axis by
        # h moves that point by h tan(theta) (the prior's std is the h the view allows)
        parts["off axis"] = axis_prior(side).std * abs(np.tan(side.theta))
    std = float(np.sqrt(sum(v * v for v in parts.values())))
    return ComLocation(est, est_line, x_com, x_line, path, std, parts)
