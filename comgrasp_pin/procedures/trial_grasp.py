"""The trial grasp: perceive, measure the empty arm, grasp, lift, watch, measure, estimate.

This is the measurement of the paper's first experiment and the first half of the regrasp
method: the rod is grasped (at its perceived centre plus an offset), lifted back to the
configuration where tau_before was measured while the side camera watches it turn, and the
CoM is estimated from the torques and located along the rod from the side view. With
``roll_deg`` > 0 a second static pose, the first rolled about ee-x, is measured too: gravity
then has a component along the jaw axis, which makes the CoM's height in the jaws
observable. The result is a measurement only: scoring against the truth lives in
``comgrasp_pin.simulation.scoring``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from comgrasp_pin.config import EpisodeConfig
from comgrasp_pin.errors import (
    EmptyGripperError,
    HeldRodUnmeasuredError,
    IKError,
    ObjectNotFoundError,
    PerceptionError,
    RodDroppedError,
    RodSlippedError,
    UntrustedImageError,
)
from comgrasp_pin.estimation.pose_planning import best_next_pose
from comgrasp_pin.geometry import GraspPose, rotation_angle
from comgrasp_pin.motion.ik import grasp_frame, solve_ik, solve_top_down
from comgrasp_pin.perception import RodDetection, SideView
from comgrasp_pin.planning.regrasp import needs_another_pose
from comgrasp_pin.planning.retry import heavy_side_from_tilt
from comgrasp_pin.procedures import phases, torques
from comgrasp_pin.procedures.cell import Cell, SlipWatch, TorqueMeasurement
from comgrasp_pin.procedures.measurement import HeldReadings, TrialMeasurement, locate_com
from comgrasp_pin.procedures.put_back import put_back
from comgrasp_pin.procedures.rod_motion import mid_window_view
from comgrasp_pin.workcell import Q_PARK

MEASURED = "trial grasp: the held rod is measured"
"""Marked (``Cell.mark``) when the side camera has seen the rod at the first measurement
pose."""


@dataclass(frozen=True)
class _Plan:
    """Where to grasp and where to measure: grasp, measurement poses (rad), the rod's centre
    along ee-x from the jaws (m, a hint for the side view), the first pose's T_world_ee."""

    grasp: GraspPose
    poses: list
    centre_hint: float
    T_meas: np.ndarray
    detection: RodDetection


def _rot_x(angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def plan_trial(cell: Cell, detection: RodDetection, offset: float, config: EpisodeConfig) -> _Plan:
    """The grasp ``offset`` m along the rod from its perceived centre, and the measurement
    poses above it (the second rolled by ``roll_deg`` about ee-x)."""
    robot, trial = cell.robot, config.trial
    rod = detection.grasp
    d = np.array([np.cos(rod.yaw), np.sin(rod.yaw)])
    grasp = GraspPose(rod.x + offset * d[0], rod.y + offset * d[1], rod.z, rod.yaw)
    q_pre, T_pre = solve_top_down(robot, grasp, cell.q_des, dz=config.motion.approach)
    centre_hint = -offset * float(np.r_[d, 0.0] @ T_pre[:3, 0])  # rod centre along ee-x
    T_meas = grasp_frame(grasp)
    T_meas[:3, :3] = robot.ee_pose(q_pre)[:3, :3]
    T_meas[2, 3] = trial.lift_height
    poses = [solve_ik(robot, T_meas, q_pre)]
    if trial.roll_deg:
        T_roll = T_meas.copy()
        T_roll[:3, :3] = T_meas[:3, :3] @ _rot_x(np.radians(trial.roll_deg))
        poses.append(solve_ik(robot, T_roll, poses[0]))
    return _Plan(grasp, poses, centre_hint, T_meas, detection)


def measure_empty(cell: Cell, plan: _Plan, config: EpisodeConfig) -> list:
    """At each measurement pose the empty arm's TorqueMeasurement, or None where
    ``tau_before`` is the model's; from the last pose to the first with
    ``trial.empty_first_last``."""
    trial, out = config.trial, []
    order = -1 if trial.empty_first_last else 1
    for q in plan.poses[::order]:
        torques.arrive(cell, q, trial, settle=trial.empty_settle)
        measured = trial.tau_before == "measured"
        out.append(torques.measure(cell, trial.settle, trial) if measured else None)
    return out[::order]


def _heavy_side(watch: SlipWatch, plan: _Plan, config: EpisodeConfig):
    largest = watch.monitor.largest_tilt() if watch.monitor.times else None
    min_tilt = np.radians(config.trial.heavy_side_min_deg)
    return heavy_side_from_tilt(largest, plan.T_meas[:3, 0], min_tilt)


def grasp_and_lift(
    cell: Cell, plan: _Plan, watch: SlipWatch, careful: bool, config: EpisodeConfig
) -> None:
    """Grasp and lift to the measurement height, watched. ``careful``: lift only
    ``careful_lift`` first and, if the rod turns by more than ``careful_abort_deg``, put it
    back where it is and raise RodSlippedError (telling which end went down)."""
    trial, robot, grip = config.trial, cell.robot, config.motion.grip_force
    if not careful:
        with cell.watching(watch):
            cell.pick(plan.grasp, grip, trial.lift_height, trial.lift_time)
        cell.announce(f"{phases.LIFT}: to the measurement pose")
        return
    grasp_z = grasp_frame(plan.grasp)[2, 3]
    with cell.watching(watch):
        cell.pick(plan.grasp, grip, grasp_z + trial.careful_lift,
                  trial.careful_lift_time)  # fmt: skip
        cell.announce(f"{phases.CAREFUL_LIFT}: {100 * trial.careful_lift:.0f} cm up, does it "
                      "turn? then on up")  # fmt: skip
        cell.hold(trial.careful_hold)
        watch.sample_now()
    tilt = abs(watch.monitor.largest_tilt()) if watch.monitor.times else 0.0
    if tilt > np.radians(trial.careful_abort_deg):
        heavy = _heavy_side(watch, plan, config)
        cell.announce(f"{phases.PUT_BACK}: it turned by {np.degrees(tilt):.0f} deg")
        # Let go where it is (its low end is on the table already): lowering the jaws
        # back to the grasp height would push that end into the table.
        cell.place(robot.ee_pose(cell.q_des), trial.careful_release_time)
        cell.move_to(Q_PARK)
        raise RodSlippedError(f"the rod turned by {np.degrees(tilt):.0f} deg", heavy)
    T_up = robot.ee_pose(cell.q_des)
    T_up[2, 3] = trial.lift_height
    with cell.watching(watch):
        cell.move_linear(T_up, trial.lift_time)


def look(cell: Cell, q: np.ndarray, plan: _Plan, trial) -> SideView:
    """The side view at ``q``; a frame refused as untrusted (a real camera's noise and holes
    where the handle's surface is fitted) is taken again, ``look_attempts`` frames in all,
    ``look_period`` s apart: each frame's noise is its own."""
    for attempt in range(trial.look_attempts):
        try:
            return cell.look_from_side(q, plan.detection.length, plan.centre_hint)
        except UntrustedImageError:
            if attempt == trial.look_attempts - 1:
                raise
            cell.hold(trial.look_period)
    raise AssertionError("unreachable")


def _measure_window(cell: Cell, plan: _Plan, config: EpisodeConfig):
    """Settle, look, average the torques, look again: the measurement, the rod where it
    was on average meanwhile (``mid_window_view``, its creep kept) and None, or the
    measurement, None and the end view's PerceptionError. A window must be static: while
    the rod turned in the jaws by more than ``still_turn_deg`` during it, measure again
    (at most ``still_attempts`` windows)."""
    trial = config.trial
    for _ in range(trial.still_attempts):
        cell.hold(trial.settle)
        try:
            start = look(cell, cell.q_des, plan, trial)
        except PerceptionError:
            start = None
        measured = torques.measure(cell, 0.0, trial)
        try:
            view = mid_window_view(start, look(cell, measured.q, plan, trial))
        except PerceptionError as exc:
            return measured, None, exc
        if view.creep is None or rotation_angle(view.creep) <= np.radians(trial.still_turn_deg):
            break
    return measured, view, None


def measure_held(
    cell: Cell, plan: _Plan, watch: SlipWatch, before: list, config: EpisodeConfig
) -> HeldReadings:
    """Back at the first measurement pose: watch, measure the torques and look; then the
    same at the rolled pose (unwatched: the roll is slow), and back. ``before``: the
    empty arm's measurements (``measure_empty``)."""
    trial = config.trial
    with cell.watching(watch):
        torques.arrive(cell, plan.poses[0], trial, duration=trial.return_time)
        cell.hold(trial.hold_before_measuring)
        watch.sample_now()
    cell.announce(f"{phases.MEASURING} 1: torques and side view")
    first, side, failure = _measure_window(cell, plan, config)
    if isinstance(failure, ObjectNotFoundError):
        raise RodDroppedError(str(failure), _heavy_side(watch, plan, config)) from failure
    if failure is not None:
        raise failure
    after: list[TorqueMeasurement] = [first]
    cell.mark(MEASURED)
    slip_seen = watch.slipping_or_tilted()
    moved, side_rolled, dropped = False, None, False
    if len(plan.poses) > 1:
        cell.announce(f"{phases.MEASURING} 2: rolled {trial.roll_deg:.0f} deg")
        torques.arrive(cell, plan.poses[1], trial, duration=trial.roll_time)
        rolled, side_rolled, failure = _measure_window(cell, plan, config)
        after.append(rolled)
        dropped = isinstance(failure, ObjectNotFoundError)
        moved = failure is not None or (
            abs(side_rolled.theta - side.theta) > np.radians(trial.roll_slip_deg)
        )
        cell.move_to(plan.poses[0], duration=trial.roll_time)
    views = [side] if len(plan.poses) == 1 else [side, side_rolled]
    tau_before = [cell.robot.gravity_torques(q) if b is None else b.tau
                  for q, b in zip(plan.poses, before, strict=True)]  # fmt: skip
    return HeldReadings(after, tau_before, list(before), views, moved, dropped, slip_seen)


def measure_another_pose(
    cell: Cell, plan: _Plan, held: HeldReadings, config: EpisodeConfig
) -> HeldReadings:
    """One more static pose: the first rolled about ee-x by the D-optimal one of
    ``extra_rolls_deg``; its empty-arm torques from the model, carried over by the mean
    difference between the measured and the modelled ones at the other poses."""
    robot, trial = cell.robot, config.trial
    candidates = []
    for roll in config.regrasp.extra_rolls_deg:
        T = plan.T_meas.copy()
        T[:3, :3] = plan.T_meas[:3, :3] @ _rot_x(np.radians(roll))
        try:
            candidates.append(solve_ik(robot, T, plan.poses[0]))
        except IKError:
            continue
    if not candidates:
        return held
    measured_q = np.array([m.q for m in held.after])
    q = candidates[best_next_pose(robot, measured_q, np.array(candidates))]
    bias = np.mean([tb - robot.gravity_torques(m.q) for tb, m in zip(held.tau_before,
                    held.after, strict=True)], axis=0)  # fmt: skip
    cell.announce(f"{phases.MEASURING} {len(held.after) + 1}: one more roll")
    torques.arrive(cell, q, trial, duration=trial.roll_time)
    after = torques.measure(cell, trial.settle, trial)
    try:
        view = look(cell, after.q, plan, trial)
    except PerceptionError:
        view = None
    cell.move_to(plan.poses[0], duration=trial.roll_time)
    return held.with_pose(after, robot.gravity_torques(after.q) + bias, view)


def trial_grasp(
    cell: Cell,
    config: EpisodeConfig,
    offset: float = 0.0,
    careful: bool = False,
    detection: RodDetection | None = None,
) -> TrialMeasurement:
    """The paper's measurement: grasp ``offset`` m along the rod from its perceived centre,
    lift, measure, estimate (see the module docstring). ``careful``: see ``grasp_and_lift``.
    ``detection``: the top view of the rod as it lies now, if the caller has looked already.
    Raises RodDroppedError (or RodSlippedError) when the rod fell or turned."""
    if detection is None:
        detection = cell.look_from_above()
    plan = plan_trial(cell, detection, offset, config)
    cell.announce(f"{phases.EMPTY_ARM}: torques at the measurement poses")
    before = measure_empty(cell, plan, config)
    cell.announce(phases.trial_grasp_at(offset))
    watch = cell.slip_watch(config.sensors.watch_dt, config.motion.grip_force, detection.length,
                            plan.centre_hint)  # fmt: skip
    grasp_and_lift(cell, plan, watch, careful, config)
    try:
        held = measure_held(cell, plan, watch, before, config)
    except UntrustedImageError as exc:
        put_back(cell, plan.grasp, detection.length, plan.centre_hint, watch, config)
        raise HeldRodUnmeasuredError(str(exc), _heavy_side(watch, plan, config)) from exc
    try:
        loc = locate_com(cell.robot, held, config)
        extra = needs_another_pose(loc.std, loc.estimate.mass, config.motion.grip_force,
                                   config.regrasp)  # fmt: skip
        if extra:
            held = measure_another_pose(cell, plan, held, config)
            loc = locate_com(cell.robot, held, config)
    except EmptyGripperError as exc:
        raise RodDroppedError(str(exc), _heavy_side(watch, plan, config)) from exc
    return TrialMeasurement(
        theta=held.side.theta,
        slip_seen=held.slip_seen,
        T_ee_obj=held.side.T_ee_obj,
        x_com_obj=loc.x_com,
        x_com_line=loc.x_line,
        rolled_slip=held.moved,
        dropped_at_roll=held.dropped,
        mass_esti=loc.estimate.mass,
        rod_length=detection.length,
        grasp_z=grasp_frame(plan.grasp)[2, 3],
        rod_axis_z=detection.grasp.z,
        estimate=loc.estimate,
        estimate_line=loc.estimate_line,
        q_meas=np.array([m.q for m in held.after]),
        tau_before=np.array(held.tau_before),
        tau_after=np.array([m.tau for m in held.after]),
        T_world_ee=cell.robot.ee_pose(held.after[0].q),
        side_view=held.side,
        x_com_std=loc.std,
        std_parts=loc.std_parts,
        com_path=loc.path,
        extra_pose=extra,
    )
