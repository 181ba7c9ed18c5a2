"""The world of one trial: where the rod lies, the settings, and the simulated world.

``Scene`` is a trial's randomness (drawn from a seed), ``EpisodeConfig`` the settings of
the robot's behaviour, ``World`` the simulation, cameras and robot model built for them.
Ground truth (``World.truth``) is read only to score results, never to act.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from comgrasp_pin.geometry import invert_transform
from comgrasp_pin.motion.ik import Q_PARK
from comgrasp_pin.perception.top_down import PICK_AREA
from comgrasp_pin.planning.regrasp import PlannerConfig
from comgrasp_pin.robot import RobotModel
from comgrasp_pin.simulation.cameras import CameraRig
from comgrasp_pin.simulation.objects import add_object, get_object, object_state
from comgrasp_pin.simulation.sim import Simulation
from comgrasp_pin.simulation.torque_sensor import TorqueSensorConfig
from comgrasp_pin.simulation.world import WorldConfig, build_model

SCENE_MARGIN = 0.09  # rods (heads up to 0.07 m across) lie this far inside the pick area (m)
DROP_BOX_INNER = (0.05, 0.58, 0.24, 0.12)  # centre x, y and half sizes (m), inside the walls


@dataclass(frozen=True)
class EpisodeConfig:
    """Settings of an episode. SI units.

    Attributes:
        grip_force: force of each finger (N); 15 N makes an off-CoM grasp tilt and a CoM
            grasp hold (see WorldConfig.pad_friction).
        lift_height: eelink height above the table at the measurement configuration (m).
        lift_time: duration of the trial grasp's lift (s); a gentle lift swings the rod less
            (0.41 m in 2.5 s peaks at 0.38 m/s^2, below the careful lift's test).
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
    lift_time: float = 2.5
    roll_deg: float = 20.0
    settle: float = 0.5
    window: float = 1.0
    sensor: TorqueSensorConfig = field(default_factory=TorqueSensorConfig)
    tau_before: str = "measured"
    estimator: str = "lstsq"
    watch_dt: float = 0.2
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

    def where_is_the_rod(self) -> str:
        """Where the rod's CoM is, in words (for the record of a failed episode)."""
        x, y, z = self.truth().p_world_com
        if self.in_drop_box():
            return "in the drop box"
        if z < -0.05:
            return "on the floor"
        x0, x1, y0, y1 = PICK_AREA
        if z < 0.08 and x0 <= x <= x1 and y0 <= y <= y1:
            return "on the table"
        return f"at ({x:.2f}, {y:.2f}, {z:.2f}) m"

    def close(self) -> None:
        self.rig.close()
