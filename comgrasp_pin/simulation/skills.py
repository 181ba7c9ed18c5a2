"""Skills on a running ``Simulation``: joint moves, straight-line moves, gripper, pick, place.

Each skill only commands the servo (``sim.q_des``) and the gripper (``sim.grip_force``) and
steps the physics; physics decides what the object does. Kinematics come from Pinocchio
(``RobotModel``, ``comgrasp_pin.motion``); every tuning number from ``MotionConfig``. All
poses in the world frame, SI units. Whatever watches the world while a skill runs (slip
watch, video, viewer) is a ``Simulation`` observer.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from comgrasp_pin.config import MotionConfig
from comgrasp_pin.geometry import GraspPose
from comgrasp_pin.motion.ik import solve_ik, solve_top_down, top_down_frame
from comgrasp_pin.motion.trajectory import Quintic, min_duration
from comgrasp_pin.robot import RobotModel
from comgrasp_pin.simulation.sim import Simulation
from comgrasp_pin.workcell import DROP_BOX_XY, GRIPPER


def follow(sim: Simulation, traj: Quintic) -> None:
    """Track ``traj`` (started now) with the servo, one sample per physics step."""
    dt = sim.model.opt.timestep
    sim.track(traj.sample(np.arange(1, int(np.ceil(traj.duration / dt)) + 1) * dt)[0])


def move_to(
    sim: Simulation,
    config: MotionConfig,
    q_goal: np.ndarray,
    duration: float | None = None,
    v_max: float | None = None,
    a_max: float | None = None,
    settle: float = 0.0,
) -> None:
    """Joint-space quintic from the commanded configuration to ``q_goal`` (6,) (rad), in
    ``duration`` s (None: the shortest within v_max, a_max), then hold ``settle`` s. Limits
    left None are the config's: the gentle ``*_holding`` ones while the jaws grip (an
    object may be held), the faster ``*_empty`` ones while they are open."""
    q0 = sim.q_des.copy()
    q_goal = np.asarray(q_goal, dtype=float)
    gripping = sim.grip_force > 0.0
    if v_max is None:
        v_max = config.v_max_holding if gripping else config.v_max_empty
    if a_max is None:
        a_max = config.a_max_holding if gripping else config.a_max_empty
    if duration is None:
        duration = min_duration(q0, q_goal, v_max, a_max)
    follow(sim, Quintic(q0, q_goal, duration))
    sim.hold(settle)


def move_linear(
    sim: Simulation,
    robot: RobotModel,
    config: MotionConfig,
    T_world_goal: np.ndarray,
    duration: float,
) -> None:
    """Straight-line ee motion (position, and orientation by SE(3) interpolation) from the
    commanded pose to ``T_world_goal`` (4, 4) with a minimum-jerk time law; IK every
    ``config.ik_dt`` s seeded by the previous solution, joints linear in between."""
    dt = sim.model.opt.timestep
    q = sim.q_des.copy()
    T0 = pin.SE3(robot.ee_pose(q))
    T1 = pin.SE3(np.asarray(T_world_goal, dtype=float))
    n = max(1, int(np.ceil(duration / config.ik_dt)))
    s_knots = Quintic(np.zeros(1), np.ones(1), 1.0).sample(np.linspace(0, 1, n + 1))[0][:, 0]
    knots = [q]
    for s in s_knots[1:]:
        q = solve_ik(robot, pin.SE3.Interpolate(T0, T1, s).homogeneous, q)
        knots.append(q)
    knots = np.array(knots)
    steps = int(round(duration / dt))
    x = np.arange(1, steps + 1) / steps * n  # knot intervals covered at each step
    i = np.minimum(x.astype(int), n - 1)
    sim.track(knots[i] + (x - i)[:, None] * (knots[i + 1] - knots[i]))


def open_gripper(sim: Simulation, config: MotionConfig, duration: float) -> None:
    """Open the jaws with ``config.open_force`` and wait ``duration`` s."""
    sim.grip_force = -config.open_force
    sim.hold(duration)


def close_gripper(sim: Simulation, config: MotionConfig, force: float) -> float:
    """Close gently (``contact_force``) until the fingers stop, ramp to ``force`` (N per
    finger) over ``close_ramp`` s, and wait until the fingers stop again. Returns the
    finger closing (m): ``GRIPPER.finger_travel`` means nothing is held."""
    dt = sim.model.opt.timestep

    def wait_still(limit: float) -> None:
        still, last = 0, sim.finger_q[0]
        for _ in range(int(round(limit / dt))):
            sim.step(1)
            q = sim.finger_q[0]
            still = still + 1 if abs(q - last) < config.still_speed * dt else 0
            last = q
            if still * dt >= config.still_time:
                return

    contact = config.contact_force
    sim.grip_force = min(contact, force)
    wait_still(config.close_timeout)
    n_ramp = max(1, int(round(config.close_ramp / dt)))
    for k in range(1, n_ramp + 1):
        sim.grip_force = contact + (force - contact) * k / n_ramp
        sim.step(1)  # grip_force is applied at the start of step()
    wait_still(config.close_timeout)
    return float(sim.finger_q[0])


@dataclass(frozen=True)
class PickResult:
    """What ``pick`` did.

    Attributes:
        q_grasp: (6,) joints at the grasp (rad); T_world_ee_grasp: (4, 4) its ee pose.
        q_lift: (6,) joints at the end of the lift (rad).
        finger_q: finger closing after the close (m).
        closed_on_object: False when the jaws closed on nothing.
    """

    q_grasp: np.ndarray
    T_world_ee_grasp: np.ndarray
    q_lift: np.ndarray
    finger_q: float
    closed_on_object: bool


def pick(
    sim: Simulation,
    robot: RobotModel,
    config: MotionConfig,
    grasp: GraspPose,
    grip_force: float,
    lift_height: float,
    lift_time: float,
) -> PickResult:
    """Approach ``config.approach`` m above the top-down ``grasp`` (joint move), descend in
    a straight line, close with ``grip_force`` (N per finger), lift in a straight line in
    ``lift_time`` s until the eelink is ``lift_height`` m above the table (z = 0)."""
    q_pre, T_pre = solve_top_down(robot, grasp, sim.q_des, dz=config.approach)
    T_grasp = T_pre.copy()
    T_grasp[2, 3] -= config.approach
    open_gripper(sim, config, 0.0)
    move_to(sim, config, q_pre, settle=config.approach_settle)
    move_linear(sim, robot, config, T_grasp, config.descend_time)
    sim.hold(config.grasp_pause)
    q_grasp = sim.q_des.copy()
    finger_q = close_gripper(sim, config, grip_force)
    T_lift = T_grasp.copy()
    T_lift[2, 3] = lift_height
    move_linear(sim, robot, config, T_lift, lift_time)
    closed = finger_q < GRIPPER.finger_travel - 5e-4
    return PickResult(q_grasp, T_grasp, sim.q_des.copy(), finger_q, closed)


def place(
    sim: Simulation,
    robot: RobotModel,
    config: MotionConfig,
    T_world_ee_release: np.ndarray,
    lower_time: float,
) -> None:
    """Lower in a straight line to ``T_world_ee_release`` (4, 4) in ``lower_time`` s, open,
    retreat ``config.retreat`` m straight up."""
    move_linear(sim, robot, config, T_world_ee_release, lower_time)
    open_gripper(sim, config, config.release_time)
    T_up = np.asarray(T_world_ee_release, dtype=float).copy()
    T_up[2, 3] += config.retreat
    move_linear(sim, robot, config, T_up, config.retreat_time)


def drop_box_pose(height: float, yaw: float = 0.0) -> np.ndarray:
    """(4, 4) top-down T_world_ee above the drop box centre, eelink ``height`` m above its
    floor, rod along world x (``yaw``) so that it fits the box's long side."""
    return top_down_frame(DROP_BOX_XY[0], DROP_BOX_XY[1], height, yaw)


def carry_to_drop_box(sim: Simulation, robot: RobotModel, config: MotionConfig) -> None:
    """From a lifted grasp: joint move to ``carry_height`` above the drop box centre
    (gripper x along world x, keeping the wrist close to the current yaw), then ``place``
    lowering to ``release_height`` above the box floor."""
    q_now = sim.q_des.copy()
    x_ee = robot.ee_pose(q_now)[:3, 0]
    yaw = 0.0 if x_ee[0] >= 0.0 else np.pi  # the yaw of (0, pi) closest to the current one
    q_carry = solve_ik(robot, drop_box_pose(config.carry_height, yaw), q_now)
    move_to(sim, config, q_carry, settle=config.carry_settle)
    place(sim, robot, config, drop_box_pose(config.release_height, yaw), config.place_time)
