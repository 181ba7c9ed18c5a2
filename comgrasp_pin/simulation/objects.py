"""The rod objects of the experiments and how they enter the MuJoCo world.

``PAPER_OBJECTS`` (obj1-obj6) are the paper's six rods, kept as they were; ``EXTRA_OBJECTS``
(obj7, obj8) are rods on which the paper's assumption, the CoM on the rod's axis, fails: a
claw hammer whose tall head carries the CoM about 2 cm above the axis, and a thick (7 cm)
rod. Results on the extras are reported apart from the paper's six.

Object frame ``obj`` (docs/design.md section 2): origin at the rod's geometric centre (middle of
its length, on the handle's axis), x along the long axis (heavy end towards +x), z up when
the rod lies on the table. Every part rests on the table: all parts share the handle's bottom
plane z = -h, where h is the handle's half height, so a lying rod's origin is h above the
table, and the heads (boxes) keep it from rolling.

Ground truth per trial (the paper sets it in the MJCF): the body carries an explicit inertial
(``explicitinertial``): mass = sum of the parts' masses, CoM at (pos_real, 0, z_lat) in
``obj``, where z_lat is the CoM height the parts give (a head taller than the handle lifts it)
and ``pos_real`` is free (default: the parts' own CoM), inertia = the parts' rotational
inertia about their own CoM (kept when pos_real moves; a few-% effect on dynamics only).
The length is set per trial by stretching the nominal object along x (``ObjectSpec.scaled``);
the masses stay.

Contact: the object geoms use friction (0.6, 0.005, 1e-4) and condim 3 against the table
(no torsional friction needed there: the heads keep the rods still, and condim 3 is cheap);
against the pads the pads' values apply (pads have priority 1, see world.py).
"""

from __future__ import annotations

import json
from dataclasses import dataclass, replace

import mujoco
import numpy as np

from comgrasp_pin._paths import sim_path
from comgrasp_pin.errors import InvalidInputError
from comgrasp_pin.workcell import TABLE_Z

OBJECT_FRICTION = (0.6, 0.005, 1e-4)
OBJECT_CONDIM = 3


@dataclass(frozen=True)
class Part:
    """One segment of a rod, in the nominal object's ``obj`` frame.

    Attributes:
        shape: "capsule" or "cylinder" (round, along obj-x) or "box".
        x0, x1: extent along obj-x (m), x0 < x1, within [-length/2, length/2].
        half_y: half width across the rod (m): radius of a round part.
        half_z: half height (m): radius of a round part (set equal to half_y).
        mass: kg.
        rgba: colour.
    """

    shape: str
    x0: float
    x1: float
    half_y: float
    half_z: float
    mass: float
    rgba: tuple[float, float, float, float]

    @property
    def half_x(self) -> float:
        return 0.5 * (self.x1 - self.x0)

    @property
    def x_centre(self) -> float:
        return 0.5 * (self.x0 + self.x1)

    def inertia(self) -> np.ndarray:
        """(3,) principal moments about the part's centre (kg m^2), axes of ``obj``.
        Round parts are treated as solid cylinders of the same length."""
        a, b, c, m = self.half_x, self.half_y, self.half_z, self.mass
        if self.shape == "box":
            return m / 3.0 * np.array([b * b + c * c, a * a + c * c, a * a + b * b])
        r2 = b * b
        side = m * (r2 / 4.0 + (2 * a) ** 2 / 12.0)
        return np.array([m * r2 / 2.0, side, side])


@dataclass(frozen=True)
class ObjectSpec:
    """A rod object. ``parts[0]`` is the handle (the part the gripper holds).

    Attributes:
        name: "obj1" ... "obj8".
        description: what it looks like.
        length: overall length along obj-x (m).
        parts: segments; see ``Part``.
        paper: one of the paper's six rods (else an extra, reported apart).
    """

    name: str
    description: str
    length: float
    parts: tuple[Part, ...]
    paper: bool = True

    @property
    def thickness(self) -> float:
        """Width of the handle across the jaws (m): the gap the gripper closes on."""
        return 2.0 * self.parts[0].half_y

    @property
    def rest_height(self) -> float:
        """Height of the obj origin above the table when the rod lies on it (m)."""
        return self.parts[0].half_z

    @property
    def mass(self) -> float:
        return float(sum(p.mass for p in self.parts))

    def part_centres(self) -> np.ndarray:
        """(k, 3) centre of each part in ``obj`` (m): bottoms on the plane z = -h."""
        h = self.rest_height
        return np.array([[p.x_centre, 0.0, p.half_z - h] for p in self.parts])

    def com(self) -> np.ndarray:
        """(3,) CoM the parts give, in ``obj`` (m)."""
        m = np.array([p.mass for p in self.parts])
        return m @ self.part_centres() / m.sum()

    def inertia_about_com(self) -> np.ndarray:
        """(3, 3) rotational inertia about ``com()`` in ``obj`` axes (kg m^2)."""
        c = self.com()
        inertia = np.zeros((3, 3))
        for part, centre in zip(self.parts, self.part_centres(), strict=True):
            d = centre - c
            inertia += np.diag(part.inertia()) + part.mass * (d @ d * np.eye(3) - np.outer(d, d))
        return inertia

    def scaled(self, length: float) -> ObjectSpec:
        """The same object stretched along obj-x to ``length`` (m); masses are kept."""
        if not 0.05 <= length <= 1.0:
            raise InvalidInputError(f"length must be within [0.05, 1.0] m, got {length}")
        s = length / self.length
        parts = tuple(replace(p, x0=p.x0 * s, x1=p.x1 * s) for p in self.parts)
        return replace(self, length=length, parts=parts)


def _load_objects() -> dict[str, ObjectSpec]:
    """The rods, from ``sim/objects.json`` (data, not code), in the file's order."""
    data = json.loads(sim_path("objects.json").read_text())
    colours = {name: tuple(rgba) for name, rgba in data["colours"].items()}
    objects = {}
    for name, o in data["objects"].items():
        parts = tuple(
            Part(
                p["shape"],
                p["x0_m"],
                p["x1_m"],
                p["half_y_m"],
                p["half_z_m"],
                p["mass_kg"],
                colours[p["colour"]],
            )  # fmt: skip
            for p in o["parts"]
        )
        objects[name] = ObjectSpec(name, o["description"], o["length_m"], parts, o["paper"])
    return objects


OBJECTS: dict[str, ObjectSpec] = _load_objects()
PAPER_OBJECTS: tuple[str, ...] = tuple(n for n, o in OBJECTS.items() if o.paper)
"""The paper's six rods, obj1-obj6."""
EXTRA_OBJECTS: tuple[str, ...] = tuple(n for n, o in OBJECTS.items() if not o.paper)
"""Rods beyond the paper's (obj7, obj8), on which the CoM lies off the axis; reported apart."""


def get_object(name: str) -> ObjectSpec:
    """The object called ``name`` ("obj1" ... "obj8")."""
    if name not in OBJECTS:
        raise InvalidInputError(f"unknown object {name!r}; objects are {sorted(OBJECTS)}")
    return OBJECTS[name]


def pose_on_table(x: float, y: float, yaw: float, obj: ObjectSpec) -> np.ndarray:
    """(4, 4) T_world_obj of ``obj`` lying on the table at (x, y) (m), yaw about world z (rad)."""
    c, s = np.cos(yaw), np.sin(yaw)
    T = np.eye(4)
    T[:3, :3] = [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]
    T[:3, 3] = [x, y, TABLE_Z + obj.rest_height]
    return T


def add_object(
    spec: mujoco.MjSpec,
    obj: ObjectSpec,
    pose: np.ndarray | tuple[float, float, float],
    pos_real: float | None = None,
    name: str = "object",
    parent: str | None = None,
) -> mujoco.MjsBody:
    """Add ``obj`` as a free body called ``name`` to ``spec``.

    Args:
        pose: (4, 4) T_world_obj, or (x, y, yaw) lying on the table (m, m, rad).
        pos_real: true CoM along obj-x from the geometric centre (m); None keeps the parts'
            own CoM. Must lie within the rod.
        parent: attach the object rigidly (no free joint) to this body instead, with
            ``pose`` relative to it, e.g. ``"eelink"`` to render a rod held in the jaws.
    Geoms are named ``{name}_{i}`` and the body carries a site ``{name}_com`` at its CoM.
    """
    T = np.asarray(pose, dtype=float)
    if T.shape == (3,):
        T = pose_on_table(*T, obj)
    if T.shape != (4, 4):
        raise InvalidInputError(
            f"pose must be (4, 4) T_world_obj or (x, y, yaw), got shape {T.shape}"
        )
    com = obj.com()
    if pos_real is not None:
        if abs(pos_real) > 0.5 * obj.length:
            raise InvalidInputError(
                f"pos_real {pos_real} m is outside the rod (length {obj.length} m)"
            )
        com[0] = pos_real
    quat = np.zeros(4)
    mujoco.mju_mat2Quat(quat, T[:3, :3].ravel())
    holder = spec.worldbody if parent is None else spec.body(parent)
    body = holder.add_body(name=name, pos=T[:3, 3].tolist(), quat=quat.tolist())
    if parent is None:
        body.add_freejoint(name=f"{name}_free")
    body.explicitinertial = True
    body.mass = obj.mass
    body.ipos = com.tolist()
    inertia = obj.inertia_about_com()
    body.fullinertia = [
        inertia[0, 0], inertia[1, 1], inertia[2, 2], inertia[0, 1], inertia[0, 2], inertia[1, 2]
    ]  # fmt: skip
    for i, (part, centre) in enumerate(zip(obj.parts, obj.part_centres(), strict=True)):
        geom = body.add_geom(name=f"{name}_{i}", rgba=list(part.rgba), mass=0.0)
        geom.friction = list(OBJECT_FRICTION)
        geom.condim = OBJECT_CONDIM
        if part.shape == "box":
            geom.type = mujoco.mjtGeom.mjGEOM_BOX
            geom.size = [part.half_x, part.half_y, part.half_z]
            geom.pos = centre.tolist()
        else:
            r = part.half_y
            geom.type = (
                mujoco.mjtGeom.mjGEOM_CAPSULE
                if part.shape == "capsule"
                else mujoco.mjtGeom.mjGEOM_CYLINDER
            )
            cap = r if part.shape == "capsule" else 0.0
            geom.fromto = [part.x0 + cap, 0, centre[2], part.x1 - cap, 0, centre[2]]
            geom.size = [r, 0, 0]
    body.add_site(name=f"{name}_com", pos=com.tolist(), size=[0.004, 0, 0], group=3)
    return body


@dataclass(frozen=True)
class ObjectState:
    """Ground truth of an object read from the simulator.

    Attributes:
        T_world_obj: (4, 4) pose of the obj frame.
        p_world_com: (3,) CoM in the world frame (m).
        com_obj: (3,) CoM in the obj frame (m); com_obj[0] is pos_real.
        mass: kg.
    """

    T_world_obj: np.ndarray
    p_world_com: np.ndarray
    com_obj: np.ndarray
    mass: float

    @property
    def pos_real(self) -> float:
        return float(self.com_obj[0])


def object_state(model: mujoco.MjModel, data: mujoco.MjData, name: str = "object") -> ObjectState:
    """Ground-truth pose and CoM of body ``name`` (after mj_forward / mj_step)."""
    b = model.body(name).id
    T = np.eye(4)
    T[:3, :3] = data.xmat[b].reshape(3, 3)
    T[:3, 3] = data.xpos[b]
    return ObjectState(
        T, data.xipos[b].copy(), model.body_ipos[b].copy(), float(model.body_mass[b])
    )


def tilt_angle(T_ee_obj_ref: np.ndarray, T_ee_obj: np.ndarray) -> float:
    """Signed rotation (rad) of the rod's axis in the gripper since ``T_ee_obj_ref``, about
    ee-y (the jaw axis): the tilt theta. Both are (4, 4) T_ee_obj."""
    x_ref, x_now = T_ee_obj_ref[:3, 0], T_ee_obj[:3, 0]
    # angle in the ee x-z plane (rotation about y maps x to (cos, 0, -sin))
    a_ref = np.arctan2(-x_ref[2], x_ref[0])
    a_now = np.arctan2(-x_now[2], x_now[0])
    return float(np.angle(np.exp(1j * (a_now - a_ref))))
