"""One pick-and-place episode of the paper, in the simulated world.

``trial_grasp`` is the measurement of the paper's first experiment: perceive the rod from
the top camera, measure tau_before at the measurement configuration, grasp (at the
rectangle's centre plus an optional offset along the rod), lift back to the same
configuration while the side camera watches the tilt, measure tau_after, estimate the CoM
and locate it along the rod. ``run_episode`` is the second experiment: ``baseline`` carries
the rod from the geometric-centre grasp; ``regrasp`` makes the trial grasp and, when the
planner says so, puts the rod down and grasps it again at the estimated CoM before carrying
it to the drop box. Physics decides whether the rod arrives.

Ground truth (``object_state``) is read only to score the result, never to act.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from comgrasp_pin.errors import EmptyGripperError, ObjectNotFoundError, PerceptionError
from comgrasp_pin.estimator import estimate_com
from comgrasp_pin.geometry import com_along_axis, invert_transform
from comgrasp_pin.ik import (
    Q_PARK,
    GraspPose,
    IKError,
    grasp_frame,
    solve_ik,
    solve_top_down,
    top_down_frame,
)
from comgrasp_pin.perception import SideView
from comgrasp_pin.perception.top_down import PICK_AREA, nearest_graspable
from comgrasp_pin.planner import PlannerConfig, com_grasp, decide
from comgrasp_pin.robot import RobotModel
from comgrasp_pin.simulation import motion
from comgrasp_pin.simulation.cameras import CameraRig
from comgrasp_pin.simulation.objects import add_object, get_object, object_state
from comgrasp_pin.simulation.perceive import SlipWatcher, look_from_above, look_from_side
from comgrasp_pin.simulation.sim import Simulation
from comgrasp_pin.simulation.torque_sensor import TorqueSensorConfig
from comgrasp_pin.simulation.world import WorldConfig, build_model

METHODS = ("baseline", "regrasp")
SCENE_MARGIN = 0.09  # rods (heads up to 0.07 m across) lie this far inside the pick area (m)
PUT_DOWN_XY = (0.55, 0.0)  # where a rod is put down to be grasped again: mid-table (m)
CAREFUL_LIFT = 0.04  # a careful trial grasp first lifts the rod this much (m) ...
CAREFUL_ABORT_DEG = 6.0  # ... and puts it back down if it turns more than this (deg)
RETRY_SHIFT = 0.1  # a dropped rod is grasped again this fraction of its length off-centre
ROLL_SLIP_DEG = 0.5  # a tilt change above this at the rolled pose means the rod moved (deg)
DROP_BOX_INNER = (0.05, 0.58, 0.24, 0.12)  # centre x, y and half sizes (m), inside the walls


@dataclass(frozen=True)
class EpisodeConfig:
    """Settings of an episode. SI units.

    Attributes:
        grip_force: force of each finger (N); 15 N makes an off-CoM grasp tilt and a CoM
            grasp hold (see WorldConfig.pad_friction).
        lift_height: eelink height above the table at the measurement configuration (m).
        lift_time: duration of the trial grasp's lift (s); a gentle lift swings the rod less.
        roll_deg: roll about ee-x of the second measurement pose (deg); 0 measures at one
            pose only, as the paper does.
        settle, window: hold time before averaging the torques, and averaging window (s).
        sensor: the joint-torque sensor's error model (default 0.05 N m white noise).
        tau_before: "measured" (at the same configuration before grasping, as the paper)
            or "model" (RobotModel.gravity_torques).
        estimator: "lstsq" or "ipopt".
        watch_dt: period of the side camera while lifting and holding (s).
        planner: regrasp decision thresholds.
        world: the simulated world's settings.
    """

    grip_force: float = 15.0
    lift_height: float = 0.45
    lift_time: float = 1.5
    roll_deg: float = 20.0
    settle: float = 0.5
    window: float = 0.5
    sensor: TorqueSensorConfig = field(default_factory=TorqueSensorConfig)
    tau_before: str = "measured"
    estimator: str = "lstsq"
    watch_dt: float = 0.1
    planner: PlannerConfig = field(default_factory=PlannerConfig)
    world: WorldConfig = field(default_factory=WorldConfig)


@dataclass(frozen=True)
class Scene:
    """Where a rod lies and where its mass is (one trial's randomness, from a seed).

    Attributes:
        object: "obj1" ... "obj6"; length: its length (m); pos_real: true CoM along the rod
        from its geometric centre (m); x, y, yaw: its pose on the table (m, m, rad).
    """

    object: str
    length: float
    pos_real: float
    x: float
    y: float
    yaw: float

    @classmethod
    def sample(
        cls, obj: str, seed: int, pos_real: float | None = None, com_range=(0.1, 0.3)
    ) -> Scene:
        """A random pose in the pick area and, unless given, a random true CoM whose
        distance from the centre is com_range (fractions of the length), either side."""
        rng = np.random.default_rng(seed)
        spec = get_object(obj)
        if pos_real is None:
            pos_real = rng.choice([-1.0, 1.0]) * rng.uniform(*com_range) * spec.length
        x, y, yaw = random_table_pose(rng, spec.length)
        return cls(obj, spec.length, float(pos_real), x, y, yaw)


def random_table_pose(rng: np.random.Generator, length: float) -> tuple[float, float, float]:
    """(x, y, yaw) of a rod of ``length`` (m) lying wholly in the pick area, at least
    SCENE_MARGIN from its edges, its centre in the part of the table the arm reaches best."""
    x0, x1, y0, y1 = PICK_AREA
    while True:
        x, y = rng.uniform(0.47, 0.63), rng.uniform(-0.12, 0.12)
        yaw = rng.uniform(-np.pi / 2, np.pi / 2)
        half = 0.5 * length * np.abs([np.cos(yaw), np.sin(yaw)]) + SCENE_MARGIN
        if x0 < x - half[0] and x + half[0] < x1 and y0 < y - half[1] and y + half[1] < y1:
            return float(x), float(y), float(yaw)


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
        rolled_slip: the rod moved in the jaws at the rolled pose (two-pose estimate unused).
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


@dataclass(frozen=True)
class EpisodeResult:
    """Outcome of ``run_episode`` (frozen; ``row()`` flattens it for a CSV).

    Attributes:
        scene: the trial's scene. method: "baseline" or "regrasp".
        success: the rod ended inside the drop box.
        regrasped: the planner put the rod down and grasped it at the estimated CoM.
        reason: the planner's reason (or the baseline's).
        trial: the trial grasp's measurement (regrasp only).
        final_grasp_offset: where the carrying grasp held the rod, from its centre (true, m).
        timings: wall-clock seconds per phase.
    """

    scene: Scene
    method: str
    success: bool
    regrasped: bool
    reason: str
    trial: TrialGrasp | None
    final_grasp_offset: float
    timings: dict

    def row(self) -> dict:
        t = self.trial
        nan = float("nan")
        return {
            "length_m": self.scene.length,
            "pos_real_m": self.scene.pos_real,
            "pos_esti_m": t.pos_esti if t else nan,
            "theta_deg": np.degrees(t.theta) if t else nan,
            "accuracy": t.accuracy if t else nan,
            "mass_real_kg": t.mass_real if t else nan,
            "mass_esti_kg": t.mass_esti if t else nan,
            "success": int(self.success),
            "regrasped": int(self.regrasped),
            "reason": self.reason,
            "final_grasp_offset_m": self.final_grasp_offset,
            "wall_s": sum(self.timings.values()),
        }


class World:
    """The simulated world of one trial: simulation, cameras, robot model and the rod."""

    def __init__(self, scene: Scene, config: EpisodeConfig, seed: int):
        obj = get_object(scene.object).scaled(scene.length)

        def place_rod(spec):
            add_object(spec, obj, (scene.x, scene.y, scene.yaw), pos_real=scene.pos_real)

        self.scene = scene
        self.config = config
        self.robot = RobotModel.ur5()
        model = build_model(config.world, extras=[place_rod])
        self.sim = Simulation(model, config.world, config.sensor, seed=seed)
        self.rig = CameraRig(model)
        self.sim.reset_arm(Q_PARK)
        self.sim.hold(0.3)  # the rod settles on the table

    def truth(self):
        return object_state(self.sim.model, self.sim.data)

    def grasp_offset_true(self) -> float:
        """Where the jaws hold the rod now, along its true axis from its centre (m)."""
        T_obj_ee = invert_transform(self.truth().T_world_obj) @ self.sim.ee_pose()
        return float(T_obj_ee[0, 3])

    def in_drop_box(self) -> bool:
        x, y, hx, hy = DROP_BOX_INNER
        p = self.truth().p_world_com
        return bool(abs(p[0] - x) < hx and abs(p[1] - y) < hy and p[2] < 0.12)

    def close(self) -> None:
        self.rig.close()


class RodDroppedError(EmptyGripperError):
    """The rod fell out of the jaws during the trial grasp. ``heavy_side_world``: (3,) unit
    horizontal direction of the end that went down first (from the side camera's tilt
    samples), or None if no tilt was seen."""

    def __init__(self, message: str, heavy_side_world: np.ndarray | None):
        super().__init__(f"the rod was dropped in the trial grasp: {message}")
        self.heavy_side_world = heavy_side_world


def _heavy_side(watcher: SlipWatcher, T_world_ee: np.ndarray) -> np.ndarray | None:
    """Direction (world, horizontal) of the rod's end that went down, from the tilt samples:
    a positive tilt raises the ee +x end, so the heavy end lies towards -x."""
    thetas = np.array(watcher.monitor.thetas)
    if thetas.size == 0 or np.max(np.abs(thetas)) < np.radians(2.0):
        return None
    theta = thetas[np.argmax(np.abs(thetas))]
    x_world = T_world_ee[:3, 0] * np.array([1.0, 1.0, 0.0])
    return -np.sign(theta) * x_world / np.linalg.norm(x_world)


class RodSlippedError(RodDroppedError):
    """The rod turned in the jaws as a careful trial grasp began to lift it, and was put
    back down; ``heavy_side_world`` tells where its CoM lies."""

    def __init__(self, message: str, heavy_side_world: np.ndarray | None):
        EmptyGripperError.__init__(self, f"the rod slipped as it was lifted: {message}")
        self.heavy_side_world = heavy_side_world


def trial_grasp(world: World, offset: float = 0.0, careful: bool = False) -> TrialGrasp:
    """The paper's measurement: grasp ``offset`` m along the rod from the perceived centre.

    With ``config.roll_deg`` > 0 a second static pose, the measurement pose rolled about
    ee-x, is measured too: gravity then has a component along the jaw axis, which makes the
    CoM's height in the jaws observable, and the 3-D CoM is projected on the rod's axis. The
    roll lowers the gravity moment about the jaw axis, so a rod that has settled does not
    slip; the side camera checks it and the single-pose (paper's) estimate is used if it
    moved. Both estimates are returned.

    ``careful``: lift only CAREFUL_LIFT first and, if the rod turns by more than
    CAREFUL_ABORT_DEG, put it back where it was and raise RodSlippedError (telling which
    end went down), before the rod can fall.
    """
    sim, robot, config = world.sim, world.robot, world.config
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
    motion.move_to(sim, poses[0], settle=0.1)

    watcher = SlipWatcher(world.rig, robot, config.watch_dt, config.grip_force, rod_length,
                          centre_hint)  # fmt: skip
    if careful:
        # Lift a little, slowly, and put the rod back down at once if it turns in the jaws.
        grasp_z = grasp_frame(grasp)[2, 3]
        pick = motion.pick(sim, robot, grasp, grip_force=config.grip_force,
                           lift_height=grasp_z + CAREFUL_LIFT, lift_time=1.0,
                           callback=watcher)  # fmt: skip
        motion.hold(sim, 0.3, callback=watcher)
        watcher(sim, force=True)
        tilts = np.abs(watcher.monitor.thetas)
        if tilts.size and tilts.max() > np.radians(CAREFUL_ABORT_DEG):
            heavy = _heavy_side(watcher, T_meas)
            motion.place(sim, robot, pick.T_world_ee_grasp, lower_time=0.8)
            motion.move_to(sim, Q_PARK)
            sim.hold(0.5)
            raise RodSlippedError(f"the rod turned by {np.degrees(tilts.max()):.0f} deg", heavy)
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
    slip_seen = watcher.slipping_or_tilted()
    moved = False
    if len(poses) > 1:
        motion.move_to(sim, poses[1], duration=1.0)
        after.append(sim.measure_torques(config.settle, config.window))
        side_rolled = look_from_side(world.rig, sim.data, robot, after[1].q, rod_length,
                                     centre_hint, finger_q=sim.finger_q[0])  # fmt: skip
        moved = abs(side_rolled.theta - side.theta) > np.radians(ROLL_SLIP_DEG)
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

    truth = world.truth()
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
        pos_real=truth.pos_real,
        mass_esti=est.mass,
        mass_real=truth.mass,
        grasp_offset=world.grasp_offset_true(),
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


def _rot_x(angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def _trial_with_retry(world: World, attempts: int = 4) -> TrialGrasp:
    """Careful trial grasps: if the rod turns as it is lifted (or falls), put it down, look
    again and grasp it again where it now lies, shifted towards the end the side camera saw
    go down (by a further RETRY_SHIFT of its length each time): the CoM is on that side."""
    offset = 0.0
    for attempt in range(attempts):
        try:
            return trial_grasp(world, offset, careful=attempt < attempts - 1)
        except RodDroppedError as exc:
            if attempt == attempts - 1:
                raise
            motion.open_gripper(world.sim)
            motion.move_to(world.sim, Q_PARK)
            world.sim.hold(1.0)
            if exc.heavy_side_world is not None:
                rod = look_from_above(world.rig, world.sim.data)
                d = np.array([np.cos(rod.grasp.yaw), np.sin(rod.grasp.yaw), 0.0])
                step = RETRY_SHIFT * rod.length * np.sign(d @ exc.heavy_side_world)
                offset += step
    raise AssertionError("unreachable")


def _carry(world: World) -> bool:
    motion.carry_to_drop_box(world.sim, world.robot)
    motion.move_to(world.sim, Q_PARK)
    world.sim.hold(0.5)
    return world.in_drop_box()


def run_episode(
    obj: str,
    seed: int,
    method: str = "regrasp",
    pos_real: float | None = None,
    config: EpisodeConfig | None = None,
    video: Path | None = None,
    viewer: bool = False,
) -> EpisodeResult:
    """One pick-and-place of ``obj`` on the scene drawn from ``seed`` (same seed, same
    scene and same sensor noise: the result is reproducible). ``video``: write an MP4 and a
    key-frame strip (PNG) of the episode there. ``viewer``: show it in MuJoCo's interactive
    viewer (needs a display), in real time."""
    if method not in METHODS:
        raise ValueError(f"method must be one of {METHODS}, got {method!r}")
    config = config or EpisodeConfig()
    scene = Scene.sample(obj, seed, pos_real)
    world = World(scene, config, seed)
    recorder = None
    if viewer:
        world.sim.observers.append(_LiveViewer(world.sim))
    if video is not None:
        from comgrasp_pin.simulation.recorder import EpisodeRecorder

        recorder = EpisodeRecorder(world.sim)
        world.sim.observers.append(recorder)
    timings: dict[str, float] = {}
    start = time.perf_counter()
    trial, regrasped, success, final_offset = None, False, False, float("nan")
    try:
        try:
            if method == "baseline":
                _caption(recorder, "baseline: grasp at the geometric centre")
                rod = look_from_above(world.rig, world.sim.data).grasp
                motion.pick(world.sim, world.robot, rod, grip_force=config.grip_force)
                reason = "geometric-centre grasp"
            else:
                trial, regrasped, reason = _measure_and_regrasp(world, recorder)
                timings["trial"] = time.perf_counter() - start
            final_offset = world.grasp_offset_true()
            mark = time.perf_counter()
            _caption(recorder, "carrying to the drop box")
            success = _carry(world)
            timings["carry"] = time.perf_counter() - mark
        except (RodDroppedError, PerceptionError, IKError) as exc:
            # The robot lost the rod, or cannot see or reach it any more: a failed episode.
            reason = f"{type(exc).__name__}: {exc}"
        if recorder is not None:
            video.parent.mkdir(parents=True, exist_ok=True)
            recorder.write_video(video)
            recorder.write_strip(video.with_suffix(".png"))
    finally:
        if recorder is not None:
            recorder.close()
        world.close()
    timings["total"] = time.perf_counter() - start - sum(timings.values())
    return EpisodeResult(scene, method, success, regrasped, reason, trial, final_offset, timings)


def _measure_and_regrasp(world: World, recorder) -> tuple[TrialGrasp, bool, str]:
    """The regrasp method up to the carrying grasp: (trial, regrasped, reason)."""
    _caption(recorder, "trial grasp at the geometric centre, measuring")
    trial = _trial_with_retry(world)
    decision = decide(trial.theta, trial.slip_seen, trial.x_com_obj,
                      trial.side_view.grasp_offset, world.config.planner)  # fmt: skip
    if not decision.regrasp:
        return trial, False, decision.reason
    _caption(recorder, f"regrasp: {decision.reason}")
    p_pivot, low_is_plus, p_release = _put_down(world, trial)
    rod = look_from_above(world.rig, world.sim.data)
    # The low end stayed at the pivot as the rod lay down: seen from the rod's new centre,
    # it tells which way the rod's +x end points.
    centre = np.array([rod.grasp.x, rod.grasp.y])
    to_pivot = np.r_[p_pivot[:2] - centre, 0.0]
    axis_hint = to_pivot if low_is_plus else -to_pivot
    # The CoM lies (x_com - grasp_offset) along the rod from the point the jaws held, and
    # that point lies where they let go: measured from it, the side camera's estimate of
    # the rod's centre (which may be off by millimetres) drops out.
    d = np.array([np.cos(rod.grasp.yaw), np.sin(rod.grasp.yaw)])
    held_s = (p_release[:2] - centre) @ d
    sign = 1.0 if d @ axis_hint[:2] >= 0 else -1.0
    x_com_from_centre = sign * (held_s + sign * (decision.x_com_obj - decision.grasp_offset_obj))
    target = com_grasp(rod.grasp, axis_hint, x_com_from_centre,
                       lambda s: nearest_graspable(rod, s))  # fmt: skip
    motion.pick(world.sim, world.robot, target, grip_force=world.config.grip_force)
    return trial, True, decision.reason


def _put_down(world: World, trial: TrialGrasp) -> tuple[np.ndarray, bool, np.ndarray]:
    """Lay the held rod down mid-table, along the table's long side (y), and go home.

    A rod hanging tilted in the jaws is laid down as a person would: lowered until its low
    end nearly touches the table, then the jaws move down and away from that end together,
    so that the rod pivots on it and comes to lie flat where it is (lowering it straight
    down would push it through the jaws and topple it). Uses only what the side camera
    measured (axis, centre, length from the top view). Returns where the rod's low end met
    the table (3,), the pivot it lay down about, whether that end is its +x end, and where
    the jaws let go (3,)."""
    sim, robot = world.sim, world.robot
    T_now = robot.ee_pose(sim.q_des)
    yaw = np.pi / 2 if T_now[1, 0] >= 0 else -np.pi / 2  # the nearer of the two
    x_axis, centre = trial.T_ee_obj[:3, 0], trial.T_ee_obj[:3, 3]
    ends = [centre + s * 0.5 * trial.rod_length * x_axis for s in (-1.0, 1.0)]
    low = max(ends, key=lambda e: e[2])  # ee z points down
    low_is_plus = bool((low - centre) @ x_axis > 0)
    reach = float(np.hypot(low[0], low[2]))  # TCP to the low end, in the jaws' plane
    shift = low[0] - np.sign(low[0]) * reach  # TCP move along ee-x that lays the rod flat
    # Flat, the rod's centre lies -grasp_offset along ee-x from the TCP: put it mid-table.
    e_x = np.array([np.cos(yaw), np.sin(yaw)])
    xy_touch = np.asarray(PUT_DOWN_XY) + (trial.side_view.grasp_offset - shift) * e_x
    T_above = top_down_frame(*xy_touch, T_now[2, 3], yaw)
    motion.move_to(sim, solve_ik(robot, T_above, sim.q_des), settle=0.2)
    # Flat, the rod's axis lies where it is now below the TCP (its point nearest the TCP):
    # the TCP ends that far above the axis' height on the table.
    near = centre - (centre @ x_axis) * x_axis
    z_flat = max(trial.rod_axis_z + near[2] + 0.003, trial.rod_axis_z)
    T_touch = T_above.copy()
    T_touch[2, 3] = max(z_flat + low[2] + 0.01, z_flat)
    T_flat = T_above.copy()
    T_flat[:3, 3] += shift * T_above[:3, 0]
    T_flat[2, 3] = z_flat
    motion.move_linear(sim, robot, T_touch, 1.5)
    p_pivot = T_touch[:3, :3] @ low + T_touch[:3, 3]  # where the low end meets the table
    motion.place(sim, robot, T_flat, lower_time=2.0)
    motion.move_to(sim, Q_PARK)
    sim.hold(0.5)
    return p_pivot, low_is_plus, T_flat[:3, 3].copy()


class _LiveViewer:
    """A Simulation observer that mirrors the world in MuJoCo's passive viewer at 60 Hz,
    paced to real time."""

    def __init__(self, sim: Simulation):
        import mujoco.viewer

        self._handle = mujoco.viewer.launch_passive(sim.model, sim.data)
        self._next = sim.time
        self._start = (time.perf_counter(), sim.time)

    def __call__(self, sim: Simulation) -> None:
        if sim.time < self._next or not self._handle.is_running():
            return
        self._next += 1.0 / 60.0
        self._handle.sync()
        ahead = (sim.time - self._start[1]) - (time.perf_counter() - self._start[0])
        if ahead > 0:
            time.sleep(ahead)


def _caption(recorder, text: str) -> None:
    if recorder is not None:
        recorder.caption = text
