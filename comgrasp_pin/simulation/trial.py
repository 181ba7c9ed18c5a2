"""The trial grasp: perceive, measure the torques, grasp, lift, watch, measure, estimate.

This is the measurement of the paper's first experiment and the first half of the regrasp
method: the rod is grasped (at its perceived centre plus an offset), lifted back to the
configuration where tau_before was measured while the side camera watches it turn, and the
CoM is estimated from the torques and located along the rod from the side view.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from comgrasp_pin.errors import EmptyGripperError, ObjectNotFoundError, PerceptionError
from comgrasp_pin.estimation.estimator import estimate_com
from comgrasp_pin.estimation.regressor import pose_regressor
from comgrasp_pin.geometry import com_along_axis, invert_transform
from comgrasp_pin.motion.ik import Q_PARK, GraspPose, grasp_frame, solve_ik, solve_top_down
from comgrasp_pin.perception import RodDetection, SideView
from comgrasp_pin.perception.top_down import nearest_on_handle
from comgrasp_pin.simulation import skills as motion
from comgrasp_pin.simulation.eyes import SlipWatcher, look_from_above, look_from_side
from comgrasp_pin.simulation.scene import World

CAREFUL_LIFT = 0.04  # a careful trial grasp first lifts the rod this much (m) ...
# ... briskly: its peak acceleration (10/sqrt(3) 0.04 / 0.6^2 = 0.64 m/s^2) exceeds that of
# the lift that follows (EpisodeConfig.lift_time), so a grasp that passes holds through it.
CAREFUL_LIFT_TIME = 0.6
CAREFUL_ABORT_DEG = 3.0  # ... and puts it back down if it turns more than this (deg)
RETRY_SHIFT = 0.15  # a turning rod is grasped again this fraction of its length further
ROLL_SLIP_DEG = 0.5  # a tilt change above this at the rolled pose means the rod moved (deg)
# Below this tilt the rod that turned at the rolled pose keeps the one-pose estimate: the
# vertical CoM line meets a nearly level axis where the CoM is (off by its height times
# tan(theta)), while the moved second view adds its own error (measured: equal below 10 deg,
# the two-pose estimate better above).
ROD_FRAME_MIN_TILT = np.radians(12.0)
MAX_CONDITION = 1e4  # the rod-frame two-pose problem is used below this condition number


@dataclass(frozen=True)
class TrialGrasp:
    """What one trial grasp measured, with the ground truth beside it.

    Attributes:
        theta: tilt of the rod in the jaws seen by the side camera (rad); theta_true from
            the simulator. slip_seen: the slip monitor's verdict.
        T_ee_obj: (4, 4) rod pose in the ee frame from the side camera.
        x_com_obj: estimated CoM along the perceived rod from its perceived centre (m).
        pos_esti: the estimated CoM point expressed along the TRUE rod frame (m), to compare
            with pos_real; accuracy = 1 - 5 |pos_esti - pos_real| / length.
        pos_esti_line: the same for the paper's single-pose estimate (CoM line met with the
            rod axis), from the same measurements.
        rolled_slip: the rod turned in the jaws at the rolled pose; the two poses were then
            combined in the rod's frame, each with its own side view (at tilts of at least
            ROD_FRAME_MIN_TILT; below it the one-pose estimate is kept).
        dropped_at_roll: the side camera found nothing in the jaws at the rolled pose: the
            rod fell after the first pose was measured; the single-pose estimate stands.
        mass_esti, mass_real: kg. grasp_offset: where the jaws hold the rod (true, m).
        length: the rod's true length (m); rod_length: as the top view measured it (m).
        grasp_z: eelink height of the grasp (m); rod_axis_z: height of the rod's axis on
            the table, from the top view (m).
        estimate: the ComEstimate used; estimate_line: the single-pose one.
        q_meas: (k, 6) measurement configurations (rad); tau_before, tau_after: (k, 6)
            averaged torque readings there (N m).
        T_world_ee: (4, 4) ee pose at the first measurement configuration.
    """

    theta: float
    theta_true: float
    slip_seen: bool
    T_ee_obj: np.ndarray
    x_com_obj: float
    pos_esti: float
    pos_esti_line: float
    rolled_slip: bool
    dropped_at_roll: bool
    pos_real: float
    mass_esti: float
    mass_real: float
    grasp_offset: float
    length: float
    rod_length: float
    grasp_z: float
    rod_axis_z: float
    estimate: object
    estimate_line: object
    q_meas: np.ndarray
    tau_before: np.ndarray
    tau_after: np.ndarray
    T_world_ee: np.ndarray
    side_view: SideView

    @property
    def accuracy(self) -> float:
        """The paper's metric, 1 - 5 |pos_esti - pos_real| / l."""
        return 1.0 - 5.0 * abs(self.pos_esti - self.pos_real) / self.length

    @property
    def accuracy_line(self) -> float:
        """The paper's metric for the paper's single-pose estimate."""
        return 1.0 - 5.0 * abs(self.pos_esti_line - self.pos_real) / self.length


class RodDroppedError(EmptyGripperError):
    """The rod fell out of the jaws during the trial grasp. ``heavy_side_world``: (3,) unit
    horizontal direction of the end that went down first (from the side camera's tilt
    samples), or None if no tilt was seen."""

    def __init__(self, message: str, heavy_side_world: np.ndarray | None):
        super().__init__(f"the rod was dropped in the trial grasp: {message}")
        self.heavy_side_world = heavy_side_world


def _heavy_side(watcher: SlipWatcher, T_world_ee: np.ndarray) -> np.ndarray | None:
    """Direction (world, horizontal) of the rod's end that went down, from the largest tilt
    the side camera saw (robust to one bad frame): a positive tilt raises the ee +x end, so
    the heavy end lies towards -x. None if no tilt was seen."""
    if not watcher.monitor.times:
        return None
    theta = watcher.monitor.largest_tilt()
    if abs(theta) < np.radians(2.0):
        return None
    x_world = T_world_ee[:3, 0] * np.array([1.0, 1.0, 0.0])
    return -np.sign(theta) * x_world / np.linalg.norm(x_world)


class RodSlippedError(RodDroppedError):
    """The rod turned in the jaws as a careful trial grasp began to lift it, and was put
    back down; ``heavy_side_world`` tells where its CoM lies."""

    def __init__(self, message: str, heavy_side_world: np.ndarray | None):
        EmptyGripperError.__init__(self, f"the rod slipped as it was lifted: {message}")
        self.heavy_side_world = heavy_side_world


def trial_grasp(
    world: World, offset: float = 0.0, careful: bool = False, detection: RodDetection | None = None
) -> TrialGrasp:
    """The paper's measurement: grasp ``offset`` m along the rod from the perceived centre.

    With ``config.roll_deg`` > 0 a second static pose, the measurement pose rolled about
    ee-x, is measured too: gravity then has a component along the jaw axis, which makes the
    CoM's height in the jaws observable, and the 3-D CoM is projected on the rod's axis. The
    roll lowers the gravity moment about the jaw axis, so a settled rod rarely slips; the
    side camera checks it, and if it turned, the two poses are combined in the rod's frame,
    each with its own side view. The paper's single-pose estimate is returned as well.

    ``careful``: lift only CAREFUL_LIFT first and, if the rod turns by more than
    CAREFUL_ABORT_DEG, put it back where it was and raise RodSlippedError (telling which
    end went down), before the rod can fall. ``detection``: the top view of the rod as it
    lies now, if the caller has looked already.
    """
    sim, robot, config = world.sim, world.robot, world.config
    if detection is None:
        detection = look_from_above(world.rig, sim.data)
    rod, rod_length = detection.grasp, detection.length
    d = np.array([np.cos(rod.yaw), np.sin(rod.yaw)])
    grasp = GraspPose(rod.x + offset * d[0], rod.y + offset * d[1], rod.z, rod.yaw)
    q_pre, T_pre = solve_top_down(robot, grasp, sim.q_des, dz=0.15)
    centre_hint = -offset * float(np.r_[d, 0.0] @ T_pre[:3, 0])  # rod centre along ee-x
    T_meas = grasp_frame(grasp)
    T_meas[:3, :3] = robot.ee_pose(q_pre)[:3, :3]
    T_meas[2, 3] = config.lift_height
    poses = [solve_ik(robot, T_meas, q_pre)]
    if config.roll_deg:
        T_roll = T_meas.copy()
        T_roll[:3, :3] = T_meas[:3, :3] @ _rot_x(np.radians(config.roll_deg))
        poses.append(solve_ik(robot, T_roll, poses[0]))

    tau_before = []
    for q in poses:
        motion.move_to(sim, q, settle=0.1)
        if config.tau_before == "measured":
            tau_before.append(sim.measure_torques(config.settle, config.window).tau)
        elif config.tau_before == "model":
            tau_before.append(robot.gravity_torques(q))
        else:
            raise ValueError(f"tau_before must be 'measured' or 'model', not {config.tau_before!r}")

    watcher = SlipWatcher(world.rig, robot, config.watch_dt, config.grip_force, rod_length,
                          centre_hint)  # fmt: skip
    if careful:
        # Lift a little, slowly, and put the rod back down at once if it turns in the jaws.
        grasp_z = grasp_frame(grasp)[2, 3]
        motion.pick(sim, robot, grasp, grip_force=config.grip_force,
                    lift_height=grasp_z + CAREFUL_LIFT, lift_time=CAREFUL_LIFT_TIME,
                    callback=watcher)  # fmt: skip
        motion.hold(sim, 0.3, callback=watcher)
        watcher(sim, force=True)
        tilt = abs(watcher.monitor.largest_tilt()) if watcher.monitor.times else 0.0
        if tilt > np.radians(CAREFUL_ABORT_DEG):
            heavy = _heavy_side(watcher, T_meas)
            # Let go where it is (its low end is on the table already): lowering the jaws
            # back to the grasp height would push that end into the table.
            motion.place(sim, robot, robot.ee_pose(sim.q_des), lower_time=0.1)
            motion.move_to(sim, Q_PARK)
            raise RodSlippedError(f"the rod turned by {np.degrees(tilt):.0f} deg", heavy)
        T_up = robot.ee_pose(sim.q_des)
        T_up[2, 3] = config.lift_height
        motion.move_linear(sim, robot, T_up, config.lift_time, watcher)
    else:
        motion.pick(sim, robot, grasp, grip_force=config.grip_force,
                    lift_height=config.lift_height, lift_time=config.lift_time,
                    callback=watcher)  # fmt: skip
    motion.move_to(sim, poses[0], duration=0.3, callback=watcher)
    motion.hold(sim, 0.5, callback=watcher)
    watcher(sim, force=True)
    after = [sim.measure_torques(config.settle, config.window)]
    try:
        side = look_from_side(world.rig, sim.data, robot, after[0].q, rod_length, centre_hint,
                          finger_q=sim.finger_q[0])  # fmt: skip
    except ObjectNotFoundError as exc:
        raise RodDroppedError(str(exc), _heavy_side(watcher, T_meas)) from exc
    truth = world.truth()  # scoring only: the rod as it was when the side camera saw it
    grasp_offset_true = world.grasp_offset_true()
    slip_seen = watcher.slipping_or_tilted()
    moved, side_rolled, dropped = False, None, False
    if len(poses) > 1:
        motion.move_to(sim, poses[1], duration=1.0)
        after.append(sim.measure_torques(config.settle, config.window))
        try:
            side_rolled = look_from_side(world.rig, sim.data, robot, after[1].q, rod_length,
                                         centre_hint, finger_q=sim.finger_q[0])  # fmt: skip
            moved = abs(side_rolled.theta - side.theta) > np.radians(ROLL_SLIP_DEG)
        except ObjectNotFoundError:
            moved = dropped = True
        except PerceptionError:
            moved = True
        motion.move_to(sim, poses[0], duration=1.0)

    n_std = config.sensor.noise_std / np.sqrt(after[0].n_samples)
    pair_std = max(n_std * (1.0 if config.tau_before == "measured" else np.sqrt(0.5)), 1e-6)

    def estimate(k: int):
        q = np.array([m.q for m in after[:k]])
        tau_a = np.array([m.tau for m in after[:k]])
        return estimate_com(robot, q, np.array(tau_before[:k]), tau_a,
                            method=config.estimator, torque_std=pair_std)  # fmt: skip

    try:
        est_line = estimate(1)
    except EmptyGripperError as exc:
        raise RodDroppedError(str(exc), _heavy_side(watcher, T_meas)) from exc
    x_line = com_along_axis(est_line, side.T_ee_obj)
    est, x_com_obj = est_line, x_line
    if len(poses) > 1 and not moved:
        est = estimate(len(poses))
        x_com_obj = com_along_axis(est, side.T_ee_obj)
    elif len(poses) > 1 and side_rolled is not None and abs(side.theta) >= ROD_FRAME_MIN_TILT:
        # The rod turned in the jaws between the poses: the CoM is fixed in the rod, so the
        # two poses still stack when written in the rod's frame, each with its own view.
        dtau = [m.tau - b for m, b in zip(after, tau_before, strict=True)]
        T_views = [side.T_ee_obj, _same_direction(side_rolled.T_ee_obj, side.T_ee_obj)]
        com_obj, cond = com_in_rod_frame(robot, [m.q for m in after], dtau, T_views)
        if cond < MAX_CONDITION:
            x_com_obj = float(com_obj[0])

    T_world_ee = robot.ee_pose(after[0].q)
    T_obj_world = invert_transform(truth.T_world_obj)

    def along_true_rod(x: float) -> float:
        p_com_world = T_world_ee @ side.T_ee_obj @ np.array([x, 0.0, 0.0, 1.0])
        return float((T_obj_world @ p_com_world)[0])

    T_ee_obj_true = invert_transform(T_world_ee) @ truth.T_world_obj
    return TrialGrasp(
        theta=side.theta,
        theta_true=float(np.arctan2(-T_ee_obj_true[2, 0], T_ee_obj_true[0, 0])),
        slip_seen=slip_seen,
        T_ee_obj=side.T_ee_obj,
        x_com_obj=x_com_obj,
        pos_esti=along_true_rod(x_com_obj),
        pos_esti_line=along_true_rod(x_line),
        rolled_slip=moved,
        dropped_at_roll=dropped,
        pos_real=truth.pos_real,
        mass_esti=est.mass,
        mass_real=truth.mass,
        grasp_offset=grasp_offset_true,
        length=world.scene.length,
        rod_length=rod_length,
        grasp_z=grasp_frame(grasp)[2, 3],
        rod_axis_z=rod.z,
        estimate=est,
        estimate_line=est_line,
        q_meas=np.array([m.q for m in after]),
        tau_before=np.array(tau_before),
        tau_after=np.array([m.tau for m in after]),
        T_world_ee=T_world_ee,
        side_view=side,
    )


def com_in_rod_frame(robot, qs, dtaus, T_ee_objs) -> tuple[np.ndarray, float]:
    """CoM in the rod's frame (3,) (m) from k static poses at which the rod sat in the jaws
    at ``T_ee_objs`` (k, 4, 4), and the condition number of the stacked problem.

    With theta_ee = (m, m c_ee) and c_ee = R c_obj + p per pose, dtau = Y theta_ee becomes
    linear in (m, m c_obj): rows (Y_0 + Y_c p, Y_c R), stacked over the poses.
    """
    rows = []
    for q, T in zip(qs, T_ee_objs, strict=True):
        Y, _ = pose_regressor(robot, q)
        rows.append(np.c_[Y[:, 0] + Y[:, 1:] @ T[:3, 3], Y[:, 1:] @ T[:3, :3]])
    A, b = np.vstack(rows), np.concatenate(dtaus)
    theta = np.linalg.lstsq(A, b, rcond=None)[0]
    singular = np.linalg.svd(A, compute_uv=False)
    return theta[1:] / theta[0], float(singular[0] / max(singular[-1], 1e-300))


def _same_direction(T: np.ndarray, T_ref: np.ndarray) -> np.ndarray:
    """``T`` turned half a turn about its z if its x points against ``T_ref``'s."""
    if T[:3, 0] @ T_ref[:3, 0] >= 0:
        return T
    T = T.copy()
    T[:3, :2] *= -1.0
    return T


def _rot_x(angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def _heavy_side_seen(trial: TrialGrasp) -> np.ndarray:
    """Direction (world, horizontal) from the jaws towards the estimated CoM along the rod."""
    x_world = trial.T_world_ee[:3, :3] @ trial.T_ee_obj[:3, 0] * np.array([1.0, 1.0, 0.0])
    side = np.sign(trial.x_com_obj - trial.side_view.grasp_offset) or 1.0
    return side * x_world / max(np.linalg.norm(x_world), 1e-9)


def trial_with_retry(world: World, attempts: int = 4) -> TrialGrasp:
    """Careful trial grasps: if the rod turns as it is lifted (or falls), put it down, look
    again and grasp it again where it now lies, towards the end the side camera saw go
    down: the CoM is on that side. The grasp point steps RETRY_SHIFT of the rod's length
    that way until the rod turns the other way, then bisects between the two last points.
    Positions are kept along one world direction, so a rod seen turned by half a turn
    (its yaw is only known modulo pi) does not confuse them."""
    u = None  # world direction (3,) along which positions s are counted
    s, below, above = 0.0, None, None  # the CoM is beyond ``below`` and short of ``above``
    for attempt in range(attempts):
        rod = look_from_above(world.rig, world.sim.data)
        d = np.array([np.cos(rod.grasp.yaw), np.sin(rod.grasp.yaw), 0.0])
        offset = s if u is None else s * float(np.sign(d @ u) or 1.0)
        offset = nearest_on_handle(rod, offset)
        try:
            trial = trial_grasp(world, offset, careful=attempt < attempts - 1, detection=rod)
            if trial.dropped_at_roll:
                raise RodDroppedError("it fell out at the rolled pose", _heavy_side_seen(trial))
            return trial
        except RodDroppedError as exc:
            if attempt == attempts - 1:
                raise
            motion.open_gripper(world.sim)
            motion.move_to(world.sim, Q_PARK)
            world.sim.hold(0.5)  # the rod comes to rest on the table
            if exc.heavy_side_world is None:
                continue
            if u is None:
                u = np.asarray(exc.heavy_side_world, dtype=float)
            if exc.heavy_side_world @ u > 0:
                below = s
            else:
                above = s
            if below is not None and above is not None:
                s = 0.5 * (below + above)
            else:
                s += (1.0 if above is None else -1.0) * RETRY_SHIFT * rod.length
    raise AssertionError("unreachable")
