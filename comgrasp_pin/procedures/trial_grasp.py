"""The trial grasp: perceive, measure the empty arm, grasp, lift, watch, measure, estimate.

This is the measurement of the paper's first experiment and the first half of the regrasp
method: the rod is grasped (at its perceived centre plus an offset), lifted back to the
configuration where tau_before was measured while the side camera watches it turn, and the
CoM is estimated from the torques and located along the rod from the side view. With
``roll_deg`` > 0 a second static pose, the first rolled about ee-x, is measured too: gravity
then has a component along the jaw axis, which makes the CoM's height in the jaws
observable. When the CoM is still known too poorly, one more rolled pose is measured
(``needs_another_pose``). The result is a measurement only: scoring against the truth lives
in ``comgrasp_pin.simulation.scoring``.

``trial_grasp`` is the orchestration; it reads the config tree and hands each part the few
numbers it uses. Where to go is planned in ``trial_plan`` (pure); each step that moves the
arm, and the one way to measure at a pose (arrive, settle, average, look), is in
``trial_steps``; where the CoM lies, and how well that is known, is found in
``com_location`` (pure).
"""

from __future__ import annotations

import numpy as np

from comgrasp_pin.config import EpisodeConfig
from comgrasp_pin.errors import (
    ComGraspError,
    EmptyGripperError,
    HeldRodUnmeasuredError,
    RodDroppedError,
    UntrustedImageError,
)
from comgrasp_pin.perception import RodDetection
from comgrasp_pin.planning.regrasp import needs_another_pose
from comgrasp_pin.procedures import phases
from comgrasp_pin.procedures.cell import Cell
from comgrasp_pin.procedures.com_location import ComLocation, NoiseRule, locate_com
from comgrasp_pin.procedures.measurement import HeldReadings, TrialMeasurement
from comgrasp_pin.procedures.put_back import put_back
from comgrasp_pin.procedures.trial_plan import (
    TrialPlan,
    extra_pose,
    modelled_tau_before,
    plan_trial,
)
from comgrasp_pin.procedures.trial_steps import (
    MEASURED,
    grasp_and_lift,
    heavy_side,
    measure_empty,
    measure_held,
    measure_pose,
)
from comgrasp_pin.procedures.wrench_readings import BOTH, WRENCH, has_wrench
from comgrasp_pin.robot import RobotModel

__all__ = ["MEASURED", "trial_grasp", "trial_measurement"]


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
    trial = config.trial
    motion = config.motion
    sensors = config.sensors
    regrasp = config.regrasp
    noise = NoiseRule(trial.torque_std_from, sensors.torque, trial.tau_before != "measured")
    depth_bounds = (trial.max_depth_shift, np.radians(trial.max_depth_turn_deg))
    if detection is None:
        detection = cell.look_from_above()
    plan = plan_trial(cell.robot, cell.q_des, detection, offset, motion.approach,
                      trial.lift_height, trial.roll_deg)  # fmt: skip
    cell.announce(f"{phases.EMPTY_ARM}: torques at the measurement poses")
    before = measure_empty(cell, plan, trial)
    cell.announce(phases.trial_grasp_at(offset))
    watch = cell.slip_watch(sensors.watch_dt, motion.grip_force, plan.rod_length,
                            plan.centre_hint)  # fmt: skip
    grasp_and_lift(cell, plan, watch, careful, trial, motion.grip_force)
    try:
        held = measure_held(cell, plan, watch, before, trial)
    except UntrustedImageError as exc:
        heavy = heavy_side(watch, plan, trial.heavy_side_min_deg)  # it watches no more
        put_back(cell, plan.grasp, plan.rod_length, plan.centre_hint, watch,
                 trial.put_back_time, trial.put_back_margin, regrasp.put_back_margin)  # fmt: skip
        raise HeldRodUnmeasuredError(str(exc), heavy) from exc
    try:
        loc = locate_com(cell.robot, held, trial.estimator, noise, depth_bounds,
                         sensors.side_depth, sensors.side_depth_line)  # fmt: skip
        if needs_another_pose(loc.std, loc.estimate.mass, motion.grip_force, regrasp):
            q_measured = [m.q for m in held.after]
            q = extra_pose(cell.robot, plan, np.array(q_measured), regrasp.extra_rolls_deg)
            if q is not None:
                after, view = measure_pose(cell, q, plan, trial)
                tau_before = modelled_tau_before(cell.robot, after.q, q_measured,
                                                 held.tau_before)  # fmt: skip
                held = held.with_pose(after, tau_before, view)
                loc = locate_com(cell.robot, held, trial.estimator, noise, depth_bounds,
                                 sensors.side_depth, sensors.side_depth_line)  # fmt: skip
    except EmptyGripperError as exc:
        raise RodDroppedError(str(exc), held.heavy_side) from exc
    others = {}
    if has_wrench(held):  # the same poses from the wrist sensor, and from both: recorded
        for source in (WRENCH, BOTH):
            try:
                others[source] = locate_com(
                    cell.robot, held, trial.estimator, noise, depth_bounds, sensors.side_depth,
                    sensors.side_depth_line, source, sensors.wrench
                )  # fmt: skip
            except ComGraspError as exc:
                others[source] = str(exc)
    return trial_measurement(cell.robot, plan, held, loc, others)


def trial_measurement(
    robot: RobotModel,
    plan: TrialPlan,
    held: HeldReadings,
    loc: ComLocation,
    others: dict | None = None,
) -> TrialMeasurement:
    """The trial grasp's result from its plan, readings and CoM location. ``extra_pose`` is
    true only when the readings hold a pose beyond the plan's: one more pose was asked for
    and measured, not merely asked for. ``others``: the CoM located from the other sources
    of the same readings ({source: ComLocation, or why it failed}), recorded only."""
    return TrialMeasurement(
        theta=held.side.theta,
        slip_seen=held.slip_seen,
        T_ee_obj=held.side.T_ee_obj,
        x_com_obj=loc.x_com,
        x_com_line=loc.x_line,
        rolled_slip=held.moved,
        dropped_at_roll=held.dropped,
        mass_esti=loc.estimate.mass,
        rod_length=plan.rod_length,
        grasp_z=plan.grasp_z,
        rod_axis_z=plan.detection.grasp.z,
        estimate=loc.estimate,
        estimate_line=loc.estimate_line,
        q_meas=np.array([m.q for m in held.after]),
        tau_before=np.array(held.tau_before),
        tau_after=np.array([m.tau for m in held.after]),
        T_world_ee=robot.ee_pose(held.after[0].q),
        side_view=held.side,
        x_com_std=loc.std,
        std_parts=loc.std_parts,
        com_path=loc.path,
        extra_pose=len(held.after) > len(plan.poses),
        by_source=others or {},
    )
