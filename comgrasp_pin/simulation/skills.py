"""Skills on a running ``Simulation``: joint moves, straight-line moves, gripper, pick, place.

Each skill only commands the servo (``sim.q_des``) and the gripper (``sim.grip_force``) and
steps the physics; physics decides what the object does. Kinematics come from Pinocchio
(``RobotModel``, ``comgrasp_pin.motion.ik``). All poses in the world frame, SI units.

Every skill takes an optional ``callback(sim)`` run after each physics step (logging, slip
watching); it must not step the simulation itself.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from comgrasp_pin.motion.ik import GraspPose, grasp_frame, solve_ik, solve_top_down, top_down_frame
from comgrasp_pin.motion.trajectory import (
    DEFAULT_A_MAX,
    DEFAULT_V_MAX,
    EMPTY_A_MAX,
    EMPTY_V_MAX,
    Quintic,
    min_duration,
)
from comgrasp_pin.robot import RobotModel
from comgrasp_pin.simulation.sim import Simulation

Callback = Callable[[Simulation], None] | None

FINGER_CLOSED = 0.0445  # finger joint value when the jaws touch each other (m)
DROP_BOX_XY = (0.05, 0.58)  # centre of the drop box (m)
DROP_BOX_WALL_Z = 0.06  # top of its walls (m)
OPEN_FORCE = 10.0  # force that opens the fingers (N)
CONTACT_FORCE = 2.0  # gentle force while the jaws close onto the object (N)


def _run(sim: Simulation, n: int, callback: Callback) -> None:
    if callback is None:
        sim.step(n)
        return
    for _ in range(n):
        sim.step(1)
        callback(sim)


def hold(sim: Simulation, duration: float, callback: Callback = None) -> None:
    """Keep the commanded configuration for ``duration`` s."""
    _run(sim, int(round(duration / sim.model.opt.timestep)), callback)


def follow(sim: Simulation, traj: Quintic, callback: Callback = None) -> None:
    """Track ``traj`` (started now) with the servo, one sample per physics step."""
    dt = sim.model.opt.timestep
    qs = traj.sample(np.arange(1, int(np.ceil(traj.duration / dt)) + 1) * dt)[0]
    for q in qs:
        sim.q_des = q
        _run(sim, 1, callback)


def move_to(
    sim: Simulation,
    q_goal: np.ndarray,
    duration: float | None = None,
    v_max: float | None = None,
    a_max: float | None = None,
    settle: float = 0.0,
    callback: Callback = None,
) -> None:
    """Joint-space quintic from the commanded configuration to ``q_goal`` (6,) (rad), in
    ``duration`` s (default: the shortest within v_max, a_max), then hold ``settle`` s.
    The default limits are the gentle DEFAULT_* ones while the jaws grip (an object may be
    held), the faster EMPTY_* ones while they are open."""
    q0 = sim.q_des.copy()
    q_goal = np.asarray(q_goal, dtype=float)
    gripping = sim.grip_force > 0.0
    if v_max is None:
        v_max = DEFAULT_V_MAX if gripping else EMPTY_V_MAX
    if a_max is None:
        a_max = DEFAULT_A_MAX if gripping else EMPTY_A_MAX
    if duration is None:
        duration = min_duration(q0, q_goal, v_max, a_max)
    follow(sim, Quintic(q0, q_goal, duration), callback)
    hold(sim, settle, callback)


def move_linear(
    sim: Simulation,
    robot: RobotModel,
    T_world_goal: np.ndarray,
    duration: float,
    callback: Callback = None,
    ik_dt: float = 0.02,
) -> None:
    """Straight-line ee motion (position, and orientation by SE(3) interpolation) from the
    commanded pose to ``T_world_goal`` (4, 4) with a minimum-jerk time law; IK every
    ``ik_dt`` s seeded by the previous solution, joints linear in between."""
    dt = sim.model.opt.timestep
    q = sim.q_des.copy()
    T0 = pin.SE3(robot.ee_pose(q))
    T1 = pin.SE3(np.asarray(T_world_goal, dtype=float))
    n = max(1, int(np.ceil(duration / ik_dt)))
    s_knots = Quintic(np.zeros(1), np.ones(1), 1.0).sample(np.linspace(0, 1, n + 1))[0][:, 0]
    knots = [q]
    for s in s_knots[1:]:
        q = solve_ik(robot, pin.SE3.Interpolate(T0, T1, s).homogeneous, q)
        knots.append(q)
    knots = np.array(knots)
    steps = int(round(duration / dt))
    for k in range(1, steps + 1):
        x = k / steps * n
        i = min(int(x), n - 1)
        sim.q_des = knots[i] + (x - i) * (knots[i + 1] - knots[i])
        _run(sim, 1, callback)


def open_gripper(sim: Simulation, duration: float = 0.3, callback: Callback = None) -> None:
    """Open the jaws with ``OPEN_FORCE`` and wait ``duration`` s."""
    sim.grip_force = -OPEN_FORCE
    hold(sim, duration, callback)


def close_gripper(
    sim: Simulation,
    force: float,
    ramp: float = 0.1,
    timeout: float = 1.5,
    callback: Callback = None,
) -> float:
    """Close gently (``CONTACT_FORCE``) until the fingers stop, ramp to ``force`` (N per
    finger) over ``ramp`` s, and wait until the fingers stop again (speed < 1 mm/s for
    30 ms). Returns the finger closing (m): ``FINGER_CLOSED`` means nothing is held."""
    dt = sim.model.opt.timestep

    def wait_still(limit: float) -> None:
        still, last = 0, sim.finger_q[0]
        for _ in range(int(round(limit / dt))):
            _run(sim, 1, callback)
            q = sim.finger_q[0]
            still = still + 1 if abs(q - last) < 1e-3 * dt else 0
            last = q
            if still * dt >= 0.03:
                return

    sim.grip_force = min(CONTACT_FORCE, force)
    wait_still(timeout)
    n_ramp = max(1, int(round(ramp / dt)))
    for k in range(1, n_ramp + 1):
        sim.grip_force = CONTACT_FORCE + (force - CONTACT_FORCE) * k / n_ramp
        sim.step(1)  # grip_force is applied at the start of step()
        if callback is not None:
            callback(sim)
    wait_still(timeout)
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
    grasp: GraspPose,
    grip_force: float = 20.0,
    lift_height: float = 0.30,
    approach: float = 0.15,
    descend_time: float = 1.0,
    lift_time: float = 1.0,
    callback: Callback = None,
) -> PickResult:
    """Approach ``approach`` m above the top-down ``grasp`` (joint move), descend in a
    straight line, close with ``grip_force`` (N per finger), lift in a straight line until
    the eelink is ``lift_height`` m above the table (z = 0)."""
    q_pre, T_pre = solve_top_down(robot, grasp, sim.q_des, dz=approach)
    T_grasp = T_pre.copy()
    T_grasp[2, 3] -= approach
    open_gripper(sim, 0.0)
    move_to(sim, q_pre, settle=0.1, callback=callback)
    move_linear(sim, robot, T_grasp, descend_time, callback)
    hold(sim, 0.1, callback)
    q_grasp = sim.q_des.copy()
    finger_q = close_gripper(sim, grip_force, callback=callback)
    T_lift = T_grasp.copy()
    T_lift[2, 3] = lift_height
    move_linear(sim, robot, T_lift, lift_time, callback)
    return PickResult(q_grasp, T_grasp, sim.q_des.copy(), finger_q, finger_q < FINGER_CLOSED - 5e-4)


def place(
    sim: Simulation,
    robot: RobotModel,
    T_world_ee_release: np.ndarray,
    lower_time: float = 1.0,
    retreat: float = 0.15,
    callback: Callback = None,
) -> None:
    """Lower in a straight line to ``T_world_ee_release`` (4, 4), open, retreat ``retreat``
    m straight up."""
    move_linear(sim, robot, T_world_ee_release, lower_time, callback)
    open_gripper(sim, 0.4, callback)
    T_up = np.asarray(T_world_ee_release, dtype=float).copy()
    T_up[2, 3] += retreat
    move_linear(sim, robot, T_up, 0.6, callback)


def drop_box_pose(height: float, yaw: float = 0.0) -> np.ndarray:
    """(4, 4) top-down T_world_ee above the drop box centre, eelink ``height`` m above its
    floor, rod along world x (``yaw``) so that it fits the box's long side."""
    return top_down_frame(DROP_BOX_XY[0], DROP_BOX_XY[1], height, yaw)


def carry_to_drop_box(
    sim: Simulation,
    robot: RobotModel,
    carry_height: float = 0.30,
    release_height: float = 0.12,
    callback: Callback = None,
) -> None:
    """From a lifted grasp: joint move to ``carry_height`` m above the drop box centre
    (gripper x along world x, keeping the wrist close to the current yaw), then ``place``
    lowering to ``release_height`` m above the box floor."""
    q_now = sim.q_des.copy()
    x_ee = robot.ee_pose(q_now)[:3, 0]
    yaw = 0.0 if x_ee[0] >= 0.0 else np.pi  # the yaw of (0, pi) closest to the current one
    T_carry = drop_box_pose(carry_height, yaw)
    q_carry = solve_ik(robot, T_carry, q_now)
    move_to(sim, q_carry, settle=0.1, callback=callback)
    place(sim, robot, drop_box_pose(release_height, yaw), callback=callback)


__all__ = [
    "PickResult",
    "carry_to_drop_box",
    "close_gripper",
    "drop_box_pose",
    "follow",
    "hold",
    "grasp_frame",
    "move_linear",
    "move_to",
    "open_gripper",
    "pick",
    "place",
]
