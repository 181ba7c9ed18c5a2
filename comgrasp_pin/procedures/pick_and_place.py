"""Pick and place, the paper's second experiment, as the robot runs it.

``baseline`` grasps at the geometric centre the top view sees. ``regrasp`` makes careful
trial grasps (``trial_with_retry``) and, when the planner says so, lays the rod down on the
put-down spot and grasps it again at the graspable point nearest the estimated CoM.
``deliver`` then carries the rod to the drop box. No ground truth: whether the rod arrives
is for the world to say.
"""

from __future__ import annotations

from dataclasses import dataclass

from comgrasp_pin.config import EpisodeConfig
from comgrasp_pin.errors import ObjectCutByBorderError, RodDroppedError
from comgrasp_pin.motion.ik import solve_ik
from comgrasp_pin.perception import RodDetection
from comgrasp_pin.perception.top_view.grasp_points import (
    check_seen_whole,
    nearest_graspable,
    nearest_on_handle,
    with_known_length,
)
from comgrasp_pin.planning import retry
from comgrasp_pin.planning.put_down import PutDownPlan, axis_hint_after_put_down, plan_put_down
from comgrasp_pin.planning.regrasp import com_grasp, decide
from comgrasp_pin.procedures import phases
from comgrasp_pin.procedures.cell import Cell
from comgrasp_pin.procedures.measurement import TrialMeasurement
from comgrasp_pin.procedures.trial_grasp import trial_grasp
from comgrasp_pin.workcell import PUT_DOWN_XY, Q_PARK

BASELINE = f"{phases.BASELINE_GRASP}: the baseline"
CARRYING = f"{phases.CARRY}: to the drop box"
"""Announced to the cell (``Cell.announce``; the others in ``procedures.phases``)."""


@dataclass(frozen=True)
class Grasped:
    """How the carrying grasp came about.

    Attributes:
        trial: the trial grasp's measurement (regrasp only, else None).
        regrasped: the rod was put down and grasped again at the estimated CoM.
        reason: the planner's reason (or the baseline's).
    """

    trial: TrialMeasurement | None
    regrasped: bool
    reason: str


def baseline(cell: Cell, config: EpisodeConfig) -> Grasped:
    """Grasp the rod at the geometric centre the top view sees, and lift it."""
    cell.announce(BASELINE)
    rod = cell.look_from_above().grasp
    m = config.motion
    cell.pick(rod, m.grip_force, m.carry_lift_height, m.carry_lift_time)
    return Grasped(None, False, "geometric-centre grasp")


def regrasp(cell: Cell, config: EpisodeConfig) -> Grasped:
    """Trial grasp; if the planner says so, put the rod down and grasp it at the CoM."""
    trial = trial_with_retry(cell, config)
    decision = decide(trial.theta, trial.slip_seen, trial.x_com_obj,
                      trial.side_view.grasp_offset, config.regrasp)  # fmt: skip
    if not decision.regrasp:
        return Grasped(trial, False, decision.reason)
    cell.announce(f"{phases.PUT_DOWN}: {decision.reason}")
    plan = put_down(cell, trial, config)
    cell.announce(f"{phases.REGRASP}: {100 * decision.x_com_obj:+.1f} cm from the centre")
    rod = look_again(cell, trial.rod_length, config)
    axis_hint = axis_hint_after_put_down(plan, (rod.grasp.x, rod.grasp.y))
    # The CoM lies x_com along the rod from its centre (the side view measures both within
    # millimetres), and the top view sees the centre where the rod now lies; measured from
    # where the jaws let go instead, the rod sliding in the jaws as it pivots flat would
    # carry over (centimetres).
    target = com_grasp(rod.grasp, axis_hint, decision.x_com_obj,
                       lambda s: nearest_graspable(rod, s))  # fmt: skip
    m = config.motion
    cell.pick(target, m.grip_force, m.carry_lift_height, m.carry_lift_time)
    return Grasped(trial, True, decision.reason)


def put_down(cell: Cell, trial: TrialMeasurement, config: EpisodeConfig) -> PutDownPlan:
    """Lay the held rod down on the put-down spot (``planning.put_down``) and park."""
    r, robot, held = config.regrasp, cell.robot, trial.side_view
    plan = plan_put_down(robot.ee_pose(cell.q_des), trial.T_ee_obj, trial.rod_length,
                         held.grasp_offset, trial.rod_axis_z, PUT_DOWN_XY, r)  # fmt: skip
    # Gently: the rod may be held close to its slip limit (that is why it is put down).
    cell.move_to(solve_ik(robot, plan.T_above, cell.q_des), v_max=r.put_down_v_max,
                 a_max=r.put_down_a_max, settle=r.put_down_settle)  # fmt: skip
    # Slowly: a rod held near its slip limit turns if the descent brakes hard.
    cell.move_linear(plan.T_touch, r.descend_time)
    # Loosen the grip so that the rod turns in the jaws as it lays down, as a hand would;
    # held firmly, it would be pushed into the table until it slipped out.
    cell.grip_force = min(r.pivot_grip, cell.grip_force)
    cell.place(plan.T_flat, r.lay_time)
    cell.move_to(Q_PARK)
    cell.hold(r.rest_after_put_down)
    return plan


def deliver(cell: Cell, config: EpisodeConfig) -> None:
    """Carry the held rod to the drop box, release it, and park."""
    cell.announce(CARRYING)
    cell.carry_to_drop_box()
    cell.announce(f"{phases.DROP}: let go in the drop box, the arm parks")
    cell.move_to(Q_PARK)
    cell.hold(config.motion.park_rest)


def look_again(cell: Cell, length: float, config: EpisodeConfig) -> RodDetection:
    """The top view of the rod seen whole before, ``length`` (m) long: when it was laid
    back at the edge of the camera's view and runs out of it at one end, the part seen
    completed with the length it is known to have (``with_known_length``, at least
    ``regrasp.min_seen_share`` of it in view; the detection's ``cut_end`` says so); seen
    whole but shorter than that by ``regrasp.length_tolerance``, refused
    (``check_seen_whole``: part of it hangs out of sight)."""
    r = config.regrasp
    try:
        rod = cell.look_from_above()
    except ObjectCutByBorderError as exc:
        if exc.seen is None:
            raise
        return with_known_length(exc.seen, length, r.min_seen_share)
    return check_seen_whole(rod, length, r.length_tolerance)


def trial_with_retry(cell: Cell, config: EpisodeConfig) -> TrialMeasurement:
    """Careful trial grasps (``planning.retry``): if the rod turns as it is lifted (or falls),
    put it down, look again (``look_again``: its length is the first view's) and grasp it
    again where it now lies, towards the end that went down; the last of
    ``regrasp.attempts`` is not careful."""
    attempts = config.regrasp.attempts
    state = retry.RetryState()
    length = None
    for attempt in range(attempts):
        rod = cell.look_from_above() if length is None else look_again(cell, length, config)
        length = rod.length if length is None else length  # the first, whole view's
        offset = nearest_on_handle(rod, retry.grasp_offset(state, rod.grasp.yaw))
        try:
            trial = trial_grasp(cell, config, offset, careful=attempt < attempts - 1,
                                detection=rod)  # fmt: skip
            if trial.dropped_at_roll:
                heavy = retry.heavy_side_from_estimate(trial.T_world_ee, trial.T_ee_obj,
                                                       trial.x_com_obj,
                                                       trial.side_view.grasp_offset)  # fmt: skip
                raise RodDroppedError("it fell out at the rolled pose", heavy)
            return trial
        except retry.GRASPED_AGAIN as exc:
            action = retry.on_failed_grasp(exc)  # by the table, not by inheritance
            if action is None or not action.grasp_again or attempt == attempts - 1:
                raise
            if not action.laid_back:
                cell.announce(f"{phases.PUT_BACK}: {exc}")
            cell.open_gripper(config.motion.open_time)
            cell.move_to(Q_PARK)
            cell.hold(config.regrasp.rest_time)  # the rod comes to rest on the table
            state = retry.after_failure(state, exc.heavy_side_world, rod.length,
                                        config.regrasp.retry_shift)  # fmt: skip
    raise AssertionError("unreachable")
