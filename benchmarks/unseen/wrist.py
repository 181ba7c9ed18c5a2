"""Held-rod scenes unlike the project's own, rendered with MuJoCo for the wrist (side) camera.

The project's side view was tuned on its own objects held at one measurement pose of the
workcell (sim/scene.xml): round handles, a tan table 45 cm below, two grey lights, nothing
else in view. The scenes here keep the robot (its gripper is in view, and the side view
leaves out the robot's own volume) and change everything else with ``mujoco.MjSpec``: rods of
other sections (square, hexagonal, capsule), thicknesses and colours, other tilts and a turn
out of the jaws' plane, other light, other tables, the gripper lower over the table, and
clutter behind or beside the rod (a box, a cable, a second rod). The held rod and the
clutter are fixed to the ``eelink`` body (a render, no physics); the truth is the rod's
T_ee_obj as built.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import mujoco
import numpy as np

from comgrasp_pin.motion.ik import solve_ik, top_down_frame
from comgrasp_pin.robot import RobotModel
from comgrasp_pin.simulation.cameras import CameraRig
from comgrasp_pin.simulation.objects import OBJECTS, add_object
from comgrasp_pin.simulation.sim import Simulation
from comgrasp_pin.simulation.world import SIDE_CAMERA, build_model
from comgrasp_pin.workcell import GRIPPER, Q_PARK

EE_XY, EE_YAW = (0.55, 0.0), 0.4  # the project's measurement pose: over the table's middle


@dataclass(frozen=True)
class HeldRod:
    """A rod in the jaws (ee frame, m, rad).

    Attributes:
        shape: "cylinder", "capsule", "box" (square section), "hex" (hexagonal prism, flats
            against the pads), or one of the project's objects ("obj1" ... "obj8").
        length: overall extent along its axis; radius: half its width across the jaws (the
            hexagon's across-flats half width; unused for the project's objects).
        tilt: turn of its axis about ee-y from ee-x (positive: the +x end up, towards -z_ee,
            as ``SideView.theta``); turn: about ee-z (out of the jaws' plane); roll: about
            its own axis.
        offset: where the jaws hold it, along +x_obj from its centre.
        rgba: colour (None: a project object's own).
        centre_ee: where its centre is instead, (3,) in the ee frame (a second rod in view).
    """

    shape: str = "cylinder"
    length: float = 0.3
    radius: float = 0.012
    tilt: float = 0.0
    offset: float = 0.0
    turn: float = 0.0
    roll: float = 0.0
    rgba: tuple | None = (0.55, 0.35, 0.2, 1.0)
    centre_ee: tuple | None = None

    def T_ee_obj(self) -> np.ndarray:
        """(4, 4) the rod's pose in the ee frame: centre, x along the axis."""
        R = _rot("z", self.turn) @ _rot("y", self.tilt) @ _rot("x", self.roll)
        T = np.eye(4)
        T[:3, :3] = R
        centre = self.centre_ee
        T[:3, 3] = -R @ np.array([self.offset, 0.0, 0.0]) if centre is None else centre
        return T

    @property
    def half_gap(self) -> float:
        """Half the jaws' opening on it (m): a square rolled about its axis is held by its
        edges."""
        if self.shape in OBJECTS:
            return OBJECTS[self.shape].thickness / 2
        if self.shape == "box":
            return self.radius * (abs(np.cos(self.roll)) + abs(np.sin(self.roll)))
        return self.radius


@dataclass(frozen=True)
class Thing:
    """Something in view that is not the held rod, in the ee frame (m): "box" (centre
    ``points[0]``, half sizes ``size``) or "cable" (capsules of radius ``size[0]`` through
    ``points``, (k, 3))."""

    kind: str
    points: tuple
    size: tuple = (0.04, 0.03, 0.02)
    rgba: tuple = (0.2, 0.3, 0.6, 1.0)


@dataclass(frozen=True)
class WristLook:
    """Table, light and where the gripper is: ``table_rgba``, ``texture`` (None, "checker"
    or "noise", with ``texture_rgba``), ``lights`` ((diffuse rgb, direction) per light:
    replacing the scene's two; None keeps them), ``headlight`` (ambient, diffuse) grey
    levels, ``ee_height`` above the table (m)."""

    table_rgba: tuple = (0.72, 0.60, 0.45, 1.0)
    texture: str | None = None
    texture_rgba: tuple = (0.5, 0.5, 0.5, 1.0)
    lights: tuple | None = None
    headlight: tuple = (0.25, 0.2)
    ee_height: float = 0.45


@dataclass(frozen=True)
class WristScene:
    """One scene: family, name, the held rod, the look, other things and rods in view;
    ``should_measure``: a scene the side view is meant to measure."""

    family: str
    name: str
    rod: HeldRod
    look: WristLook = field(default_factory=WristLook)
    things: tuple[Thing, ...] = ()
    others: tuple[HeldRod, ...] = ()
    should_measure: bool = False


def _rot(axis: str, angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    i, j = {"x": (1, 2), "y": (2, 0), "z": (0, 1)}[axis]
    R = np.eye(3)
    R[i, i], R[i, j], R[j, i], R[j, j] = c, -s, s, c
    return R


def _quat(R: np.ndarray) -> list[float]:
    quat = np.zeros(4)
    mujoco.mju_mat2Quat(quat, np.ascontiguousarray(R).ravel())
    return quat.tolist()


def _add_rod(spec: mujoco.MjSpec, rod: HeldRod, name: str) -> None:
    T = rod.T_ee_obj()
    if rod.shape in OBJECTS:
        body = add_object(spec, OBJECTS[rod.shape], T, name=name, parent="eelink")
        for geom in body.geoms if rod.rgba is not None else ():
            geom.rgba = list(rod.rgba)
        return
    r, half = rod.radius, 0.5 * rod.length
    body = spec.body("eelink").add_body(name=name, pos=T[:3, 3].tolist(), quat=_quat(T[:3, :3]))
    geom = body.add_geom(name=f"{name}_0", rgba=list(rod.rgba), contype=0, conaffinity=0)
    if rod.shape == "box":
        geom.type, geom.size = mujoco.mjtGeom.mjGEOM_BOX, [half, r, r]
    elif rod.shape == "hex":  # corners at 30, 90, ... deg about its axis: flats along +-y
        corner = r / np.cos(np.pi / 6)
        angles = np.pi / 6 + np.arange(6) * np.pi / 3
        vertices = [[sx * half, corner * np.sin(a), corner * np.cos(a)]
                    for sx in (-1, 1) for a in angles]  # fmt: skip
        spec.add_mesh(name=f"{name}_mesh", uservert=np.ravel(vertices).tolist())
        geom.type, geom.meshname = mujoco.mjtGeom.mjGEOM_MESH, f"{name}_mesh"
    else:
        geom.type = {"cylinder": mujoco.mjtGeom.mjGEOM_CYLINDER,
                     "capsule": mujoco.mjtGeom.mjGEOM_CAPSULE}[rod.shape]  # fmt: skip
        geom.size = [r, half - (r if rod.shape == "capsule" else 0.0), 0]
        geom.quat = _quat(_rot("y", np.pi / 2))  # the geom's z along the rod


def _add_thing(spec: mujoco.MjSpec, thing: Thing, name: str) -> None:
    ee = spec.body("eelink")
    if thing.kind == "box":
        ee.add_geom(name=name, type=mujoco.mjtGeom.mjGEOM_BOX, pos=list(thing.points[0]),
                    size=list(thing.size), rgba=list(thing.rgba), contype=0,
                    conaffinity=0)  # fmt: skip
        return
    for k, (a, b) in enumerate(zip(thing.points[:-1], thing.points[1:], strict=True)):
        ee.add_geom(name=f"{name}_{k}", type=mujoco.mjtGeom.mjGEOM_CAPSULE,
                    size=[thing.size[0], 0, 0], fromto=[*a, *b], rgba=list(thing.rgba),
                    contype=0, conaffinity=0)  # fmt: skip


def _restyle(spec: mujoco.MjSpec, look: WristLook) -> None:
    table = spec.material("table_mat")
    table.rgba = list(look.table_rgba)
    if look.texture is not None:
        tex = spec.add_texture(name="table_tex", type=mujoco.mjtTexture.mjTEXTURE_2D,
                               builtin=mujoco.mjtBuiltin.mjBUILTIN_CHECKER, width=256,
                               height=256, rgb1=list(look.table_rgba[:3]),
                               rgb2=list(look.texture_rgba[:3]))  # fmt: skip
        if look.texture == "noise":
            tex.builtin = mujoco.mjtBuiltin.mjBUILTIN_FLAT
            tex.mark, tex.random = mujoco.mjtMark.mjMARK_RANDOM, 0.3
            tex.markrgb = list(look.texture_rgba[:3])
        table.rgba = [1.0, 1.0, 1.0, 1.0]
        table.textures[mujoco.mjtTextureRole.mjTEXROLE_RGB] = "table_tex"
        table.texrepeat = [8.0, 8.0]
    if look.lights is not None:
        for light, (rgb, direction) in zip((spec.light("sun"), spec.light("fill")), look.lights):
            light.diffuse, light.dir = list(rgb), list(direction)
        for light in (spec.light("sun"), spec.light("fill"))[len(look.lights) :]:
            light.diffuse = [0.0, 0.0, 0.0]
    spec.visual.headlight.ambient = [look.headlight[0]] * 3
    spec.visual.headlight.diffuse = [look.headlight[1]] * 3


def build_model_for(scene: WristScene) -> mujoco.MjModel:
    """The workcell with the robot, restyled, the rod in the jaws and the scene's clutter."""

    def extra(spec: mujoco.MjSpec) -> None:
        _restyle(spec, scene.look)
        _add_rod(spec, scene.rod, "object")
        for k, other in enumerate(scene.others):
            _add_rod(spec, other, f"other{k}")
        for k, thing in enumerate(scene.things):
            _add_thing(spec, thing, f"thing{k}")

    return build_model(extras=[extra])


def render_side(scene: WristScene, robot: RobotModel) -> tuple[np.ndarray, CameraRig, Simulation]:
    """(clean depth (H, W) m, the rig, the simulation at the measurement pose, jaws on the
    rod) of the wrist camera; close the rig when done."""
    T_world_ee = top_down_frame(*EE_XY, scene.look.ee_height, EE_YAW)
    q = solve_ik(robot, T_world_ee, Q_PARK)
    sim = Simulation(build_model_for(scene))
    sim.reset_arm(q, finger_q=GRIPPER.open_half_gap - scene.rod.half_gap)
    mujoco.mj_forward(sim.model, sim.data)
    rig = CameraRig(sim.model)
    return rig.depth(sim.data, SIDE_CAMERA), rig, sim
