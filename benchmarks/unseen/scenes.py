"""Table scenes unlike the project's own, rendered with MuJoCo for the top-down camera.

Perception was tuned on one workcell (sim/scene.xml): a tan table, a camera 1.25 m straight
above it, two grey directional lights, the paper's rods alone. The scenes here are built
from scratch with ``mujoco.MjSpec`` (the workcell is not touched): another table colour or
texture, the camera moved, higher or lower and tilted, other light, other rods (square,
hexagonal, thicker, thinner, other colours) and clutter (a box, a cable, a second rod).
Rods are static geoms lying on the table; the truth of each is its centre, yaw and length
(world frame, m, rad), as built. No robot: nothing else is in view of the top camera.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import mujoco
import numpy as np

from comgrasp_pin.camera import PinholeCamera
from comgrasp_pin.simulation.cameras import CameraRig
from comgrasp_pin.simulation.objects import OBJECTS, add_object

CAMERA = "top_down"
TABLE_CENTRE = (0.55, 0.0)  # the project's table (m, world): top at z = 0, 0.5 m x 0.7 m
TABLE_HALF = (0.25, 0.35)


@dataclass(frozen=True)
class Rod:
    """A rod lying on the table (world frame, m, rad).

    Attributes:
        shape: "cylinder", "capsule", "box" (square section), "hex" (hexagonal prism), or
            the name of one of the project's objects ("obj1" ... "obj8": its parts, its
            length; ``radius`` unused).
        x, y: centre on the table; yaw: direction of its axis about world z.
        length: extent along the axis (overall, caps included).
        radius: half its width across the axis (the hexagon's across-flats half width).
        rgba: colour (None: the project object's own).
        z: height of its bottom above the table (a rod lying across another).
    """

    shape: str
    x: float
    y: float
    yaw: float
    length: float = 0.3
    radius: float = 0.01
    rgba: tuple | None = (0.55, 0.35, 0.2, 1.0)
    z: float = 0.0

    @property
    def half_height(self) -> float:
        """Half the rod's height (m): where its axis lies above its bottom."""
        return OBJECTS[self.shape].rest_height if self.shape in OBJECTS else self.radius


@dataclass(frozen=True)
class Clutter:
    """Something on the table that is not a rod to measure: "box" (half sizes ``size``) or
    "cable" (a chain of thin capsules through ``points``, (k, 2) m, of radius ``size[0]``)."""

    kind: str
    points: tuple = ()
    size: tuple = (0.04, 0.03, 0.02)
    yaw: float = 0.0
    rgba: tuple = (0.2, 0.3, 0.6, 1.0)


@dataclass(frozen=True)
class Look:
    """How the table looks to the top camera.

    Attributes:
        table_rgba: the table's colour; texture: None, "checker", "fine_checker" or "noise"
            (a texture of ``table_rgba`` and ``texture_rgba``).
        camera_height: the camera's height above the table (m); camera_tilt_deg: its turn
            about ``tilt_axis`` (world "x" or "y"), still aimed at ``aim`` (x, y) on the table.
        lights: (kind, position, direction, diffuse rgb) with kind "directional" or "spot";
            headlight: the headlight's (ambient, diffuse) grey levels.
    """

    table_rgba: tuple = (0.72, 0.60, 0.45, 1.0)
    texture: str | None = None
    texture_rgba: tuple = (0.5, 0.5, 0.5, 1.0)
    camera_height: float = 1.25
    camera_tilt_deg: float = 0.0
    tilt_axis: str = "x"
    aim: tuple = TABLE_CENTRE
    lights: tuple = (
        ("directional", (0.4, -0.3, 3.0), (-0.1, 0.1, -1.0), (0.45, 0.45, 0.45)),
        ("directional", (1.5, 1.0, 2.0), (-0.5, -0.3, -1.0), (0.15, 0.15, 0.15)),
    )
    headlight: tuple = (0.25, 0.2)


@dataclass(frozen=True)
class UnseenScene:
    """One scene: its family, a name, the look, the rods (the first is the one to measure)
    and the clutter; ``should_measure``: a scene perception is expected to measure."""

    family: str
    name: str
    rods: tuple[Rod, ...]
    look: Look = field(default_factory=Look)
    clutter: tuple[Clutter, ...] = ()
    should_measure: bool = False


def camera_pose(look: Look) -> tuple[np.ndarray, np.ndarray]:
    """(position (3,), R_world_mjcam (3, 3)) of the top camera (MuJoCo's camera frame)."""
    a = np.radians(look.camera_tilt_deg)
    c, s = np.cos(a), np.sin(a)
    if look.tilt_axis == "x":
        R = np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])
    else:
        R = np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])
    aim = np.array([*look.aim, 0.0])
    return aim + look.camera_height / R[2, 2] * R[:, 2], R


def _quat(R: np.ndarray) -> list[float]:
    quat = np.zeros(4)
    mujoco.mju_mat2Quat(quat, np.ascontiguousarray(R).ravel())
    return quat.tolist()


def _yaw_matrix(yaw: float) -> np.ndarray:
    c, s = np.cos(yaw), np.sin(yaw)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _add_table(spec: mujoco.MjSpec, look: Look) -> None:
    table = spec.add_material(name="table_mat", rgba=list(look.table_rgba))
    if look.texture is not None:
        builtin = {"checker": mujoco.mjtBuiltin.mjBUILTIN_CHECKER,
                   "fine_checker": mujoco.mjtBuiltin.mjBUILTIN_CHECKER,
                   "noise": mujoco.mjtBuiltin.mjBUILTIN_FLAT}[look.texture]  # fmt: skip
        tex = spec.add_texture(name="table_tex", type=mujoco.mjtTexture.mjTEXTURE_2D,
                               builtin=builtin, width=256, height=256,
                               rgb1=list(look.table_rgba[:3]),
                               rgb2=list(look.texture_rgba[:3]))  # fmt: skip
        if look.texture == "noise":
            tex.mark = mujoco.mjtMark.mjMARK_RANDOM
            tex.random = 0.3
            tex.markrgb = list(look.texture_rgba[:3])
        table.rgba = [1.0, 1.0, 1.0, 1.0]
        table.textures[mujoco.mjtTextureRole.mjTEXROLE_RGB] = "table_tex"
        table.texrepeat = [8.0, 8.0] if look.texture == "checker" else [30.0, 30.0]
    floor = spec.add_material(name="floor_mat", rgba=[0.4, 0.42, 0.45, 1.0])
    world = spec.worldbody
    world.add_geom(name="floor", type=mujoco.mjtGeom.mjGEOM_PLANE, pos=[0, 0, -0.75],
                   size=[3, 3, 0.05], material=floor.name)  # fmt: skip
    world.add_geom(name="table_top", type=mujoco.mjtGeom.mjGEOM_BOX, pos=[*TABLE_CENTRE, -0.1],
                   size=[*TABLE_HALF, 0.1], material=table.name)  # fmt: skip


def _add_rod(spec: mujoco.MjSpec, rod: Rod, name: str) -> None:
    if rod.shape in OBJECTS:
        body = add_object(spec, OBJECTS[rod.shape], (rod.x, rod.y, rod.yaw), name=name)
        body.pos = [rod.x, rod.y, rod.z + OBJECTS[rod.shape].rest_height]
        if rod.rgba is not None:
            for geom in body.geoms:
                geom.rgba = list(rod.rgba)
        return
    r, half = rod.radius, 0.5 * rod.length
    # The geom's frame: x along the rod (box, hex) or z along it (cylinder, capsule).
    R = _yaw_matrix(rod.yaw)
    geom = spec.worldbody.add_geom(name=name, rgba=list(rod.rgba),
                                   pos=[rod.x, rod.y, rod.z + r])  # fmt: skip
    if rod.shape == "box":
        geom.type, geom.size = mujoco.mjtGeom.mjGEOM_BOX, [half, r, r]
    elif rod.shape == "hex":  # corners at 0, 60, ... deg about its axis: a flat face down
        corner = r / np.cos(np.pi / 6)
        angles = np.arange(6) * np.pi / 3
        vertices = [[sx * half, corner * np.cos(a), corner * np.sin(a)]
                    for sx in (-1, 1) for a in angles]  # fmt: skip
        spec.add_mesh(name=f"{name}_mesh", uservert=np.ravel(vertices).tolist())
        geom.type, geom.meshname = mujoco.mjtGeom.mjGEOM_MESH, f"{name}_mesh"
    else:
        round_ = {"cylinder": mujoco.mjtGeom.mjGEOM_CYLINDER,
                  "capsule": mujoco.mjtGeom.mjGEOM_CAPSULE}[rod.shape]  # fmt: skip
        geom.type = round_
        geom.size = [r, half - (r if rod.shape == "capsule" else 0.0), 0]
        R = R @ np.array([[0, 0, 1.0], [0, 1.0, 0], [-1.0, 0, 0]])  # geom z along the rod
    geom.quat = _quat(R)


def _add_clutter(spec: mujoco.MjSpec, item: Clutter, name: str) -> None:
    world = spec.worldbody
    if item.kind == "box":
        x, y = item.points[0]
        world.add_geom(name=name, type=mujoco.mjtGeom.mjGEOM_BOX, rgba=list(item.rgba),
                       pos=[x, y, item.size[2]], size=list(item.size),
                       quat=_quat(_yaw_matrix(item.yaw)))  # fmt: skip
        return
    r = item.size[0]
    for k, (a, b) in enumerate(zip(item.points[:-1], item.points[1:], strict=True)):
        world.add_geom(name=f"{name}_{k}", type=mujoco.mjtGeom.mjGEOM_CAPSULE,
                       rgba=list(item.rgba), size=[r, 0, 0],
                       fromto=[a[0], a[1], r, b[0], b[1], r])  # fmt: skip


def build_model(scene: UnseenScene) -> mujoco.MjModel:
    """The scene's MuJoCo model: table, floor, lights, the top camera, rods and clutter."""
    spec = mujoco.MjSpec()
    spec.visual.global_.offwidth, spec.visual.global_.offheight = 1280, 960
    spec.visual.quality.shadowsize = 4096
    spec.visual.map.znear, spec.visual.map.zfar = 0.01, 20.0
    ambient, diffuse = scene.look.headlight
    spec.visual.headlight.ambient = [ambient] * 3
    spec.visual.headlight.diffuse = [diffuse] * 3
    spec.visual.headlight.specular = [0.0] * 3
    _add_table(spec, scene.look)
    for k, (kind, pos, direction, rgb) in enumerate(scene.look.lights):
        light = spec.worldbody.add_light(name=f"light{k}", pos=list(pos), dir=list(direction),
                                         diffuse=list(rgb), castshadow=k == 0)  # fmt: skip
        light.specular = [0.05] * 3
        if kind == "directional":
            light.type = mujoco.mjtLightType.mjLIGHT_DIRECTIONAL
        else:
            light.type = mujoco.mjtLightType.mjLIGHT_SPOT
            light.cutoff, light.exponent = 25.0, 10.0
    pos, R = camera_pose(scene.look)
    spec.worldbody.add_camera(name=CAMERA, pos=pos.tolist(), quat=_quat(R), fovy=40.0)
    for k, rod in enumerate(scene.rods):
        _add_rod(spec, rod, f"rod{k}")
    for k, item in enumerate(scene.clutter):
        _add_clutter(spec, item, f"clutter{k}")
    return spec.compile()


def render_top(scene: UnseenScene) -> tuple[np.ndarray, np.ndarray, PinholeCamera, np.ndarray]:
    """(rgb (H, W, 3) uint8, clean depth (H, W) m, intrinsics, T_world_cam) of the top camera."""
    model = build_model(scene)
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    rig = CameraRig(model)
    try:
        return (rig.rgb(data, CAMERA), rig.depth(data, CAMERA), rig.intrinsics(CAMERA),
                rig.T_world_cam(data, CAMERA))  # fmt: skip
    finally:
        if model.nmesh or model.ntex:  # not for reuse: a renderer keeps the assets it was
            for renderer in rig._renderers.values():  # made with, and these differ from
                renderer.close()  # scene to scene in content, not in their counts
        else:
            rig.close()
