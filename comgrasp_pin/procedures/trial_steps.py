"""The trial grasp's steps that move the arm and look, and the one way it measures at a pose.

At a measurement pose the arm arrives, settles, averages the torques and looks from the side:
- ``arrive``: reach a measurement pose the same way every time (from the same side in every
  joint). A current-based reading (UR CB3) holds the friction of the last motion: reached
  from one side before the grasp and from the other after, the difference of the two
  readings carries up to twice the drives' Coulomb friction (1-3 N m here), which no
  average removes. Reached from the same side, it cancels.
- ``average``: average the torques over a window long enough for the noise measured in it
  (``window_sem``); the samples' spread, not the sensor's data sheet, says how long that is
  (``extra_window``, ``combine``).
- ``look``: the side view, taken again while the camera refuses it.
- ``measure_window``: settle, look, average, look again: the torques and the rod where it
  was on average meanwhile.

The steps, each driving the ``Cell`` once:
- ``measure_empty``: the empty arm's torques at the measurement poses.
- ``grasp_and_lift``: grasp and lift, watched (carefully: a short lift first, and the rod
  put back if it turns).
- ``measure_held``: back at the first measurement pose, the torques and the side view; then
  the same at the rolled pose.
- ``measure_pose``: one more pose's torques and view.

The steps take the trial's numbers as ``TrialConfig`` (``trial``) and where to go as a
``TrialPlan``; the pose's helpers take the few numbers they use. SI units, angles in rad
unless named ``_deg``.
"""

from __future__ import annotations

from dataclasses import replace

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
from comgrasp_pin.procedures import phases
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


def arrive(cell: Cell, q: np.ndarray, approach_deg: float, approach_time: float,
           duration: float | None = None, settle: float = 0.0) -> None:  # fmt: skip
    """Move to the measurement configuration ``q`` (rad) in ``duration`` s (None: the
    shortest), then hold ``settle`` s. With ``approach_deg`` > 0, by way of ``q`` plus that
    much in every joint, the last ``approach_time`` s: every joint then comes to rest moving
    the same way, before the grasp and after it."""
    if approach_deg > 0:
        cell.move_to(q + np.radians(approach_deg), duration=duration)
        duration = approach_time
    cell.move_to(q, duration=duration, settle=settle)


def combine(a: TorqueMeasurement, b: TorqueMeasurement) -> TorqueMeasurement:
    """One measurement of the samples of two windows at the same configuration, back to
    back: means and variances weighted by their sample counts (the wrist sensor's too)."""
    tau, std, n = _pooled(a.tau, a.std_error, a.n_samples, b.tau, b.std_error, b.n_samples)
    q = (a.n_samples * a.q + b.n_samples * b.q) / n
    both = replace(a, tau=tau, std_error=std, q=q, n_samples=n, duration=a.duration + b.duration)
    if a.wrench is None or b.wrench is None:
        return replace(both, wrench=None, wrench_std_error=None, wrench_n_samples=0)
    w, w_std, w_n = _pooled(a.wrench, a.wrench_std_error, a.wrench_n_samples, b.wrench,
                            b.wrench_std_error, b.wrench_n_samples)  # fmt: skip
    return replace(both, wrench=w, wrench_std_error=w_std, wrench_n_samples=w_n)


def _pooled(mean_a, sem_a, n_a: int, mean_b, sem_b, n_b: int):
    """The mean, standard error and count of two back-to-back windows' samples."""
    n = n_a + n_b
    var = (n_a**2 * sem_a**2 + n_b**2 * sem_b**2) / n**2
    return (n_a * mean_a + n_b * mean_b) / n, np.sqrt(var), n


def extra_window(measured: TorqueMeasurement, sem: float, window_max: float) -> float:
    """How much longer (s) to average after ``measured`` for a standard error of ``sem``
    (N m) in every joint, the whole window at most ``window_max`` s; 0: long enough (or no
    target, ``sem`` 0). The noise is white: the standard error falls as 1 / sqrt(time)."""
    worst = float(np.max(measured.std_error))
    if sem <= 0 or worst <= sem or not np.isfinite(worst):
        return 0.0
    needed = measured.duration * (worst / sem) ** 2
    return max(0.0, min(needed, window_max) - measured.duration)


def average(cell: Cell, settle: float, window: float, window_sem: float,
            window_max: float) -> TorqueMeasurement:  # fmt: skip
    """Settle ``settle`` s, average ``window`` s, and on as long as the measured noise needs
    for a standard error of ``window_sem`` N m, ``window_max`` s in all (``extra_window``)."""
    first = cell.measure_torques(settle, window)
    more = extra_window(first, window_sem, window_max)
    return first if more <= 0 else combine(first, cell.measure_torques(0.0, more))


def look(cell: Cell, q: np.ndarray, plan: TrialPlan, attempts: int, period: float) -> SideView:
    """The side view at ``q``; a frame refused as untrusted (a real camera's noise and holes
    where the handle's surface is fitted) is taken again, ``attempts`` frames in all,
    ``period`` s apart: each frame's noise is its own."""
    for attempt in range(attempts):
        try:
            return cell.look_from_side(q, plan.rod_length, plan.centre_hint)
        except UntrustedImageError:
            if attempt == attempts - 1:
                raise
            cell.hold(period)
    raise AssertionError("unreachable")


def measure_window(cell: Cell, plan: TrialPlan, trial: TrialConfig):
    """Settle, look, average the torques, look again: the measurement, the rod where it
    was on average meanwhile (``mid_window_view``, its creep kept) and None, or the
    measurement, None and the end view's PerceptionError. A window must be static: while
    the rod turned in the jaws by more than ``still_turn_deg`` during it, measure again
    (at most ``still_attempts`` windows)."""
    for _ in range(trial.still_attempts):
        cell.hold(trial.settle)
        try:
            start = look(cell, cell.q_des, plan, trial.look_attempts, trial.look_period)
        except PerceptionError:
            start = None
        measured = average(cell, 0.0, trial.window, trial.window_sem, trial.window_max)
        try:
            end = look(cell, measured.q, plan, trial.look_attempts, trial.look_period)
            view = mid_window_view(start, end)
        except PerceptionError as exc:
            return measured, None, exc
        if view.creep is None or rotation_angle(view.creep) <= np.radians(trial.still_turn_deg):
            break
    return measured, view, None


def measure_empty(cell: Cell, plan: TrialPlan, trial: TrialConfig) -> list:
    """At each measurement pose the empty arm's TorqueMeasurement, or None where
    ``tau_before`` is the model's; from the last pose to the first with
    ``trial.empty_first_last``."""
    out = []
    order = -1 if trial.empty_first_last else 1
    for q in plan.poses[::order]:
        arrive(cell, q, trial.approach_deg, trial.approach_time, settle=trial.empty_settle)
        measured = trial.tau_before == "measured"
        out.append(average(cell, trial.settle, trial.window, trial.window_sem,
                           trial.window_max) if measured else None)  # fmt: skip
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


def measure_held(
    cell: Cell, plan: TrialPlan, watch: SlipWatch, before: list, trial: TrialConfig
) -> HeldReadings:
    """Back at the first measurement pose: watch, measure the torques and look; then the
    same at the rolled pose (unwatched: the roll is slow), and back. ``before``: the
    empty arm's measurements (``measure_empty``). The readings keep which end went down
    as the watch saw it (it watches no more after the first pose). Raises RodDroppedError
    when the side camera finds nothing in the jaws at the first pose."""
    with cell.watching(watch):
        arrive(
            cell, plan.poses[0], trial.approach_deg, trial.approach_time, duration=trial.return_time
        )
        cell.hold(trial.hold_before_measuring)
        watch.sample_now()
    cell.announce(f"{phases.MEASURING} 1: torques and side view")
    first, side, failure = measure_window(cell, plan, trial)
    heavy = heavy_side(watch, plan, trial.heavy_side_min_deg)  # the watch watches no more
    if isinstance(failure, ObjectNotFoundError):
        raise RodDroppedError(str(failure), heavy) from failure
    if failure is not None:
        raise failure
    after: list[TorqueMeasurement] = [first]
    cell.mark(MEASURED)
    slip_seen = watch.slipping_or_tilted()
    moved, side_rolled, dropped = False, None, False
    if len(plan.poses) > 1:
        cell.announce(f"{phases.MEASURING} 2: rolled {trial.roll_deg:.0f} deg")
        arrive(
            cell, plan.poses[1], trial.approach_deg, trial.approach_time, duration=trial.roll_time
        )
        rolled, side_rolled, failure = measure_window(cell, plan, trial)
        after.append(rolled)
        dropped = isinstance(failure, ObjectNotFoundError)
        moved = failure is not None or (
            abs(side_rolled.theta - side.theta) > np.radians(trial.roll_slip_deg)
        )
        cell.move_to(plan.poses[0], duration=trial.roll_time)
    views = [side] if len(plan.poses) == 1 else [side, side_rolled]
    tau_before = [cell.robot.gravity_torques(q) if b is None else b.tau
                  for q, b in zip(plan.poses, before, strict=True)]  # fmt: skip
    return HeldReadings(after, tau_before, list(before), views, moved, dropped, slip_seen,
                        heavy)  # fmt: skip


def measure_pose(
    cell: Cell, q: np.ndarray, plan: TrialPlan, trial: TrialConfig
) -> tuple[TorqueMeasurement, SideView | None]:
    """One more pose ``q`` (rad): its torques and side view (None where the camera saw
    nothing usable), then back to the first measurement pose."""
    cell.announce(f"{phases.MEASURING} {len(plan.poses) + 1}: one more roll")
    arrive(cell, q, trial.approach_deg, trial.approach_time, duration=trial.roll_time)
    after = average(cell, trial.settle, trial.window, trial.window_sem, trial.window_max)
    try:
        view = look(cell, after.q, plan, trial.look_attempts, trial.look_period)
    except PerceptionError:
        view = None
    cell.move_to(plan.poses[0], duration=trial.roll_time)
    return after, view
