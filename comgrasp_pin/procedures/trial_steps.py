"""The trial grasp's steps that move the arm and look: each drives the ``Cell`` once.

- ``measure_empty``: the empty arm's torques at the measurement poses.
- ``grasp_and_lift``: grasp and lift, watched (carefully: a short lift first, and the rod
  put back if it turns).
- ``measure_held``: back at the first measurement pose, the torques and the side view; then
  the same at the rolled pose.
- ``measure_pose``: one more pose's torques and view.

The trial's numbers come as ``TrialConfig`` (``trial``); where to go, as a ``TrialPlan``.
"""

from __future__ import annotations

import numpy as np

from comgrasp_pin.config import TrialConfig
from comgrasp_pin.errors import (
    ObjectNotFoundError,
    PerceptionError,
    RodDroppedError,
    RodSlippedError,
    UntrustedImageError,
)
from comgrasp_pin.geometry import rotation_angle
from comgrasp_pin.perception import SideView
from comgrasp_pin.planning.retry import heavy_side_from_tilt
from comgrasp_pin.procedures import phases, torques
from comgrasp_pin.procedures.cell import Cell, SlipWatch, TorqueMeasurement
from comgrasp_pin.procedures.measurement import HeldReadings
from comgrasp_pin.procedures.rod_motion import mid_window_view
from comgrasp_pin.procedures.trial_plan import TrialPlan
from comgrasp_pin.workcell import Q_PARK

MEASURED = "trial grasp: the held rod is measured"
"""Marked (``Cell.mark``) when the side camera has seen the rod at the first measurement
pose."""


def heavy_side(watch: SlipWatch, plan: TrialPlan, min_tilt_deg: float) -> np.ndarray | None:
    """(3,) the world direction of the rod's end that went down, from the largest tilt the
    watch saw (``heavy_side_from_tilt``); None below ``min_tilt_deg`` or if it saw nothing."""
    largest = watch.monitor.largest_tilt() if watch.monitor.times else None
    x_world_ee = plan.T_world_ee_meas[:3, 0]
    return heavy_side_from_tilt(largest, x_world_ee, np.radians(min_tilt_deg))


def measure_empty(cell: Cell, plan: TrialPlan, trial: TrialConfig) -> list:
    """At each measurement pose the empty arm's TorqueMeasurement, or None where
    ``tau_before`` is the model's; from the last pose to the first with
    ``trial.empty_first_last``."""
    out = []
    order = -1 if trial.empty_first_last else 1
    for q in plan.poses[::order]:
        torques.arrive(cell, q, trial, settle=trial.empty_settle)
        measured = trial.tau_before == "measured"
        out.append(torques.measure(cell, trial.settle, trial) if measured else None)
    return out[::order]


def grasp_and_lift(cell: Cell, plan: TrialPlan, watch: SlipWatch, careful: bool,
                   trial: TrialConfig, grip_force: float) -> None:  # fmt: skip
    """Grasp at ``grip_force`` (N per finger) and lift to the measurement height, watched.
    ``careful``: lift only ``careful_lift`` first and, if the rod turns by more than
    ``careful_abort_deg``, put it back where it is and raise RodSlippedError (telling which
    end went down)."""
    if not careful:
        with cell.watching(watch):
            cell.pick(plan.grasp, grip_force, trial.lift_height, trial.lift_time)
        cell.announce(f"{phases.LIFT}: to the measurement pose")
        return
    with cell.watching(watch):
        cell.pick(plan.grasp, grip_force, plan.grasp_z + trial.careful_lift,
                  trial.careful_lift_time)  # fmt: skip
        cell.announce(f"{phases.CAREFUL_LIFT}: {100 * trial.careful_lift:.0f} cm up, does it "
                      "turn? then on up")  # fmt: skip
        cell.hold(trial.careful_hold)
        watch.sample_now()
    tilt = abs(watch.monitor.largest_tilt()) if watch.monitor.times else 0.0
    if tilt > np.radians(trial.careful_abort_deg):
        heavy = heavy_side(watch, plan, trial.heavy_side_min_deg)
        cell.announce(f"{phases.PUT_BACK}: it turned by {np.degrees(tilt):.0f} deg")
        # Let go where it is (its low end is on the table already): lowering the jaws
        # back to the grasp height would push that end into the table.
        cell.place(cell.robot.ee_pose(cell.q_des), trial.careful_release_time)
        cell.move_to(Q_PARK)
        raise RodSlippedError(f"the rod turned by {np.degrees(tilt):.0f} deg", heavy)
    T_world_ee_up = cell.robot.ee_pose(cell.q_des)
    T_world_ee_up[2, 3] = trial.lift_height
    with cell.watching(watch):
        cell.move_linear(T_world_ee_up, trial.lift_time)


def look(cell: Cell, q: np.ndarray, plan: TrialPlan, trial: TrialConfig) -> SideView:
    """The side view at ``q``; a frame refused as untrusted (a real camera's noise and holes
    where the handle's surface is fitted) is taken again, ``look_attempts`` frames in all,
    ``look_period`` s apart: each frame's noise is its own."""
    for attempt in range(trial.look_attempts):
        try:
            return cell.look_from_side(q, plan.rod_length, plan.centre_hint)
        except UntrustedImageError:
            if attempt == trial.look_attempts - 1:
                raise
            cell.hold(trial.look_period)
    raise AssertionError("unreachable")


def _measure_window(cell: Cell, plan: TrialPlan, trial: TrialConfig):
    """Settle, look, average the torques, look again: the measurement, the rod where it
    was on average meanwhile (``mid_window_view``, its creep kept) and None, or the
    measurement, None and the end view's PerceptionError. A window must be static: while
    the rod turned in the jaws by more than ``still_turn_deg`` during it, measure again
    (at most ``still_attempts`` windows)."""
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
    cell: Cell, plan: TrialPlan, watch: SlipWatch, before: list, trial: TrialConfig
) -> HeldReadings:
    """Back at the first measurement pose: watch, measure the torques and look; then the
    same at the rolled pose (unwatched: the roll is slow), and back. ``before``: the
    empty arm's measurements (``measure_empty``). Raises RodDroppedError when the side
    camera finds nothing in the jaws at the first pose."""
    with cell.watching(watch):
        torques.arrive(cell, plan.poses[0], trial, duration=trial.return_time)
        cell.hold(trial.hold_before_measuring)
        watch.sample_now()
    cell.announce(f"{phases.MEASURING} 1: torques and side view")
    first, side, failure = _measure_window(cell, plan, trial)
    if isinstance(failure, ObjectNotFoundError):
        heavy = heavy_side(watch, plan, trial.heavy_side_min_deg)
        raise RodDroppedError(str(failure), heavy) from failure
    if failure is not None:
        raise failure
    after: list[TorqueMeasurement] = [first]
    cell.mark(MEASURED)
    slip_seen = watch.slipping_or_tilted()
    moved, side_rolled, dropped = False, None, False
    if len(plan.poses) > 1:
        cell.announce(f"{phases.MEASURING} 2: rolled {trial.roll_deg:.0f} deg")
        torques.arrive(cell, plan.poses[1], trial, duration=trial.roll_time)
        rolled, side_rolled, failure = _measure_window(cell, plan, trial)
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


def measure_pose(
    cell: Cell, q: np.ndarray, plan: TrialPlan, trial: TrialConfig
) -> tuple[TorqueMeasurement, SideView | None]:
    """One more pose ``q`` (rad): its torques and side view (None where the camera saw
    nothing usable), then back to the first measurement pose."""
    cell.announce(f"{phases.MEASURING} {len(plan.poses) + 1}: one more roll")
    torques.arrive(cell, q, trial, duration=trial.roll_time)
    after = torques.measure(cell, trial.settle, trial)
    try:
        view = look(cell, after.q, plan, trial)
    except PerceptionError:
        view = None
    cell.move_to(plan.poses[0], duration=trial.roll_time)
    return after, view
