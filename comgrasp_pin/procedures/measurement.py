"""A trial grasp's measurement, and where the CoM lies according to it.

``HeldReadings`` is what the robot read holding the rod (torques at each measurement pose,
the side views); ``locate_com`` turns them, with tau_before, into the estimates;
``TrialMeasurement`` is the trial grasp's result. No ground truth here.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from comgrasp_pin.config import EpisodeConfig
from comgrasp_pin.estimation import AxisPrior, ComEstimate, com_along_axis, estimate_com
from comgrasp_pin.estimation.rod_axis import com_in_rod_frame
from comgrasp_pin.perception import SideView
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
        rolled_slip: the rod turned in the jaws at the rolled pose; the two poses were then
            combined in the rod's frame, each with its own side view (at tilts of at least
            ``rod_frame_min_tilt_deg``; below it the one-pose estimate is kept).
        dropped_at_roll: the side camera found nothing in the jaws at the rolled pose.
        mass_esti: kg. rod_length: as the top view measured it (m).
        grasp_z: eelink height of the grasp (m); rod_axis_z: height of the rod's axis on
            the table, from the top view (m).
        estimate: the ComEstimate used; estimate_line: the single-pose one.
        q_meas: (k, 6) measurement configurations (rad); tau_before, tau_after: (k, 6)
            averaged torque readings there (N m).
        T_world_ee: (4, 4) ee pose at the first measurement configuration.
        side_view: the side camera's view at the first measurement pose.
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


@dataclass(frozen=True)
class HeldReadings:
    """The held rod's readings: torques per pose, the side views, what happened at the roll."""

    after: list
    side: SideView
    side_rolled: SideView | None
    moved: bool
    dropped: bool
    slip_seen: bool


def _same_direction(T: np.ndarray, T_ref: np.ndarray) -> np.ndarray:
    """``T`` turned half a turn about its z if its x points against ``T_ref``'s."""
    if T[:3, 0] @ T_ref[:3, 0] >= 0:
        return T
    T = T.copy()
    T[:3, :2] *= -1.0
    return T


def axis_prior(side: SideView) -> AxisPrior:
    """The prior on the CoM from the side view: near the rod's axis. The CoM lies within the
    rod's cross-section, which the side camera sees reach ``off_axis`` from the axis; half of
    that is one standard deviation across the axis, combined with how well the axis itself
    was located (``axis_std``)."""
    std = float(np.hypot(0.5 * side.off_axis, side.axis_std))
    return AxisPrior.from_rod(side.T_ee_obj, std)


def locate_com(
    robot: RobotModel, held: HeldReadings, tau_before: list, config: EpisodeConfig
) -> tuple[ComEstimate, ComEstimate, float, float]:
    """(estimate used, the paper's estimate, x_com_obj, x_com_line).

    The paper's: one pose, least squares, the vertical CoM line met with the rod's axis.
    Ours (``estimator``: "ipopt" adds the side view's ``axis_prior``; "lstsq" is the closed
    form without it): the two-pose 3-D CoM projected on the axis when the rod stayed put;
    the two poses combined in the rod's frame when it turned (at tilts of at least
    ``rod_frame_min_tilt_deg``); the first pose alone otherwise. A payload not measurably
    above zero: EmptyGripperError.
    """
    trial, after = config.trial, held.after
    n_std = config.sensors.torque.noise_std / np.sqrt(after[0].n_samples)
    pair_std = max(n_std * (1.0 if trial.tau_before == "measured" else np.sqrt(0.5)), 1e-6)
    T_obj = held.side.T_ee_obj

    def estimate(k: int, method: str, prior: AxisPrior | None) -> ComEstimate:
        q = np.array([m.q for m in after[:k]])
        tau_a = np.array([m.tau for m in after[:k]])
        return estimate_com(robot, q, np.array(tau_before[:k]), tau_a, method=method,
                            torque_std=pair_std, com_prior=prior)  # fmt: skip

    est_line = estimate(1, "lstsq", None)
    x_line = com_along_axis(est_line, T_obj)
    prior = axis_prior(held.side) if trial.estimator == "ipopt" else None
    if prior is None:
        est, x_com = est_line, x_line
    else:
        est = estimate(1, "ipopt", prior)
        x_com = com_along_axis(est, T_obj)
    two_poses = len(after) > 1
    if two_poses and not held.moved:
        est = estimate(len(after), trial.estimator, prior)
        x_com = com_along_axis(est, T_obj)
    elif (
        two_poses
        and held.side_rolled is not None
        and abs(held.side.theta) >= np.radians(trial.rod_frame_min_tilt_deg)
    ):
        # The rod turned in the jaws between the poses: the CoM is fixed in the rod, so the
        # two poses still stack when written in the rod's frame, each with its own view.
        T_rolled = _same_direction(held.side_rolled.T_ee_obj, T_obj)
        T_views = [T_obj, T_rolled]
        rod_frame = com_in_rod_frame(robot, [m.q for m in after], tau_before,
                                     [m.tau for m in after], T_views)  # fmt: skip
        if rod_frame.condition_number < trial.max_condition:
            x_com = float(rod_frame.com_obj[0])
    return est, est_line, x_com, x_line
