"""The world of one trial: where the rod lies, and the simulated world built for it.

``Scene`` is a trial's randomness (drawn from a seed), ``World`` the simulation, cameras and
robot model built for it with an ``EpisodeConfig``; ``save_world_xml`` writes a scene's world
as one MJCF file (``comgrasp scene``). Ground truth (``World.truth``) is read
only to score results, never to act.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from comgrasp_pin import validate
from comgrasp_pin.config import EpisodeConfig, SensorConfig
from comgrasp_pin.geometry import invert_transform
from comgrasp_pin.robot import RobotModel
from comgrasp_pin.simulation.cameras import CameraRig
from comgrasp_pin.simulation.depth_noise import DepthNoise
from comgrasp_pin.simulation.objects import ObjectState, add_object, get_object, object_state
from comgrasp_pin.simulation.sim import Simulation
from comgrasp_pin.simulation.world import SIDE_CAMERA, TOP_CAMERA, build_model, build_spec
from comgrasp_pin.workcell import PICK_AREA, Q_PARK

SCENE_MARGIN = 0.09  # rods (heads up to 0.07 m across) lie this far inside the pick area (m)


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
        distance from the centre is com_range (fractions of the length), either side.

        Raises:
            InvalidInputError: an unknown object, a seed that is not an integer >= 0, a
                ``pos_real`` that is not finite or lies outside the rod.
        """
        spec = get_object(obj)
        rng = np.random.default_rng(validate.integer(seed, "seed", low=0))
        if pos_real is not None:
            half = 0.5 * spec.length
            pos_real = validate.number(pos_real, "pos_real", low=-half, high=half)
        else:
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


def misstate_gripper(spec, mass_error: float, com_error: float) -> None:
    """Make the simulated gripper ``mass_error`` (relative) heavier than the robot's model
    says and move its CoM ``com_error`` (m) along (1, 1, 1) / sqrt(3) of its frame: the
    model error of ``SensorConfig`` (the robot's ``RobotModel`` keeps the URDF's values)."""
    body = spec.body("gripper_base")
    body.mass = body.mass * (1.0 + mass_error)
    body.ipos = np.asarray(body.ipos) + com_error * np.ones(3) / np.sqrt(3.0)


def depth_noises(sensors: SensorConfig, seed: int) -> dict[str, DepthNoise]:
    """Each camera's depth errors of ``sensors`` (none in the ideal preset), seeded from
    the episode's ``seed``."""
    noises = {}
    for k, (camera, config) in enumerate(
        ((TOP_CAMERA, sensors.top_depth), (SIDE_CAMERA, sensors.side_depth))
    ):
        if config.enabled:
            noises[camera] = DepthNoise(config, (int(seed), 21 + k))
    return noises


class World:
    """The simulated world of one trial: simulation, cameras, robot model and the rod."""

    def __init__(self, scene: Scene, config: EpisodeConfig, seed: int):
        obj = get_object(scene.object).scaled(scene.length)

        def place_rod(spec):
            add_object(spec, obj, (scene.x, scene.y, scene.yaw), pos_real=scene.pos_real)

        self.scene = scene
        self.config = config
        self.robot = RobotModel.ur5()
        sensors = config.sensors
        extras = [place_rod]
        if sensors.gripper_mass_error or sensors.gripper_com_error:
            extras.append(lambda spec: misstate_gripper(spec, sensors.gripper_mass_error,
                                                        sensors.gripper_com_error))  # fmt: skip
        model = build_model(config.world, extras=extras)
        self.sim = Simulation(model, config.world, sensors.torque, seed, sensors.wrench)
        self.rig = CameraRig(model, noise=depth_noises(sensors, seed))
        self.sim.reset_arm(Q_PARK)
        self.sim.hold(config.world.settle_time)  # the rod settles on the table

    def truth(self) -> ObjectState:
        """The rod's true state now (scoring only)."""
        return object_state(self.sim.model, self.sim.data)

    def grasp_offset_true(self) -> float:
        """Where the jaws hold the rod now, along its true axis from its centre (m)."""
        T_obj_ee = invert_transform(self.truth().T_world_obj) @ self.sim.ee_pose()
        return float(T_obj_ee[0, 3])

    def close(self) -> None:
        self.rig.close()


def save_world_xml(path: Path, obj: str = "obj2", seed: int = 0) -> Path:
    """Write the assembled world (scene, robot, ``obj`` where the scene of ``seed`` puts it)
    as one MJCF file at ``path``, for MuJoCo's own viewer; meshes are referenced where
    example-robot-data installed them. Returns ``path``."""
    scene = Scene.sample(obj, seed)
    rod = get_object(obj).scaled(scene.length)
    spec = build_spec(extras=[lambda s: add_object(s, rod, (scene.x, scene.y, scene.yaw),
                                                   pos_real=scene.pos_real)])  # fmt: skip
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message="Attaching a spec with an empty prefix")
        spec.compile()
        xml = spec.to_xml()
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(xml)
    return path
