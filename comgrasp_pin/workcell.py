"""The workcell, defined once: read from ``sim/scene.xml`` (table, drop box, put-down spot,
the arm's named poses) and from ``urdf/ur5_gripper.urdf`` (the gripper's dimensions).

Plain XML reading, no MuJoCo: the robot's code knows its workcell as a real robot's would
(from a description), and ``tests/test_workcell.py`` checks these numbers against the world
MuJoCo compiles. World frame, metres.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from dataclasses import dataclass

import numpy as np

from comgrasp_pin._paths import sim_path, urdf_path


def _floats(text: str | None) -> np.ndarray:
    return np.array([float(v) for v in (text or "").split()])


def _nm(values) -> np.ndarray:
    """Rounded to the nanometre: sums of the descriptions' decimals come out as written
    (0.55 - 0.25 is 0.3, not 0.30000000000000004)."""
    return np.round(np.asarray(values, dtype=float), 9)


def _box_extent(geom: ET.Element, body_pos: np.ndarray) -> np.ndarray:
    """(x0, x1, y0, y1, z0, z1) of an axis-aligned box geom in the world."""
    centre = body_pos + _floats(geom.get("pos", "0 0 0"))
    half = _floats(geom.get("size"))
    return _nm([centre[0] - half[0], centre[0] + half[0], centre[1] - half[1],
                centre[1] + half[1], centre[2] - half[2], centre[2] + half[2]])  # fmt: skip


_SCENE = ET.parse(sim_path("scene.xml")).getroot()
_WORLD = _SCENE.find("worldbody")


def _body(name: str) -> tuple[ET.Element, np.ndarray]:
    body = _WORLD.find(f"body[@name='{name}']")
    return body, _floats(body.get("pos", "0 0 0"))


def _union(extents: list[np.ndarray]) -> np.ndarray:
    e = np.array(extents)
    return np.array([e[:, 0].min(), e[:, 1].max(), e[:, 2].min(), e[:, 3].max(),
                     e[:, 4].min(), e[:, 5].max()])  # fmt: skip


_table, _table_pos = _body("table")
_TABLE_TOP = _box_extent(_table.find("geom[@name='table_top']"), _table_pos)
TABLE_Z = float(_TABLE_TOP[5])
"""Height of the table top (m): the plane the rods lie on."""
PICK_AREA = tuple(float(v) for v in _TABLE_TOP[:4])
"""(x_min, x_max, y_min, y_max) of the table top, the pick area (m)."""

_box, _box_pos = _body("drop_box")
_BOX_GEOMS = {g.get("name"): _box_extent(g, _box_pos) for g in _box.findall("geom")}
DROP_BOX_XY = (float(_box_pos[0]), float(_box_pos[1]))
"""Centre of the drop box (m)."""
DROP_BOX_WALL_Z = float(_BOX_GEOMS["drop_wall_n"][5])
"""Top of the drop box's walls (m)."""
DROP_BOX_INNER_HALF = tuple(
    float(v) for v in _nm([_BOX_GEOMS["drop_wall_e"][0] - _box_pos[0],
                           _BOX_GEOMS["drop_wall_n"][2] - _box_pos[1]])
)  # fmt: skip
"""Half sizes (x, y) of the drop box's inside, between its walls (m)."""
_DROP_OUTER = _union([e for n, e in _BOX_GEOMS.items() if n != "drop_stand"])

_pedestal = _box_extent(_WORLD.find("geom[@name='pedestal']"), np.zeros(3))
GRAVITY_WORLD = _floats(_SCENE.find("option").get("gravity"))
"""(3,) the cell's gravity in the world frame (m/s^2): the URDF's model takes it (the arm's
``RobotModel.ur5()``), and ``planning.holding`` the jaws' load from it."""
FLOOR_Z = float(_floats(_WORLD.find("geom[@name='floor']").get("pos"))[2])
"""Height of the floor (m)."""
OBSTACLES = (
    (*PICK_AREA, TABLE_Z),
    (*(float(v) for v in _DROP_OUTER[:4]), float(_DROP_OUTER[5])),
    (*(float(v) for v in _pedestal[:4]), float(_pedestal[5])),
)
"""(x_min, x_max, y_min, y_max, top z) of what stands on the floor: table, drop box, pedestal."""

PUT_DOWN_XY = tuple(float(v) for v in _floats(_WORLD.find("site[@name='put_down']").get("pos"))[:2])
"""Where a rod is laid down to be grasped again (m)."""

_KEYS = {k.get("name"): _floats(k.get("qpos")) for k in _SCENE.find("keyframe")}
N_ARM_JOINTS = 6
Q_HOME = _KEYS["home"][:N_ARM_JOINTS]
"""Arm joints (rad) of the home pose: elbow up, wrist down above the table."""
Q_PARK = _KEYS["park"][:N_ARM_JOINTS]
"""Arm joints (rad) of the park pose, out of the top camera's view of the table."""
Q_HOME.flags.writeable = False
Q_PARK.flags.writeable = False


@dataclass(frozen=True)
class Gripper:
    """The parallel-jaw gripper's dimensions, in the ee frame (m), from the URDF.

    Attributes:
        open_half_gap: half the gap between the pad faces when open.
        finger_travel: each finger's closing stroke (its joint's upper limit); a finger at
            it means the jaws closed on nothing.
        pad_half: (3,) half sizes of a pad (along ee-x, across it, along ee-z).
        fingertip_below_ee: the pads' bottoms lie this far beyond the eelink along ee-z.
        finger_half: (3,) half sizes of a finger behind its pad; finger_centre: its centre
            relative to the pad face (finger frame), for the left finger.
        palm_half: (3,) half sizes of the palm; palm_z: (bottom, top) of the palm along ee-z.
        tool_to_ee: distance from the flange (tool0) to the eelink along ee-z.
    """

    open_half_gap: float
    finger_travel: float
    pad_half: tuple[float, float, float]
    fingertip_below_ee: float
    finger_half: tuple[float, float, float]
    finger_centre: tuple[float, float, float]
    palm_half: tuple[float, float, float]
    palm_z: tuple[float, float]
    tool_to_ee: float


def _read_gripper() -> Gripper:
    urdf = ET.parse(urdf_path()).getroot()
    link = {l.get("name"): l for l in urdf.findall("link")}
    joint = {j.get("name"): j for j in urdf.findall("joint")}

    def boxes(name: str) -> list[tuple[np.ndarray, np.ndarray]]:
        out = []
        for visual in link[name].findall("visual"):
            box = visual.find("geometry/box")
            if box is not None:
                origin = visual.find("origin")
                xyz = _floats(origin.get("xyz") if origin is not None else "0 0 0")
                out.append((xyz, 0.5 * _floats(box.get("size"))))
        return out

    finger = joint["finger_left_joint"]
    finger_xyz = _floats(finger.find("origin").get("xyz"))
    tool_to_ee = float(_floats(joint["eelink_joint"].find("origin").get("xyz"))[2])
    (pad_xyz, pad_half), (finger_box_xyz, finger_half) = boxes("finger_left")[:2]
    palm_xyz, palm_half = boxes("gripper_base")[0]
    below = _nm(finger_xyz[2] + pad_xyz[2] + pad_half[2] - tool_to_ee)
    palm_z = _nm([palm_xyz[2] - palm_half[2] - tool_to_ee, palm_xyz[2] + palm_half[2] - tool_to_ee])
    return Gripper(
        open_half_gap=float(finger_xyz[1]),
        finger_travel=float(finger.find("limit").get("upper")),
        pad_half=tuple(float(v) for v in pad_half),
        fingertip_below_ee=float(below),
        finger_half=tuple(float(v) for v in finger_half),
        finger_centre=tuple(float(v) for v in finger_box_xyz),
        palm_half=tuple(float(v) for v in palm_half),
        palm_z=(float(palm_z[0]), float(palm_z[1])),
        tool_to_ee=tool_to_ee,
    )


GRIPPER = _read_gripper()
"""The project's gripper (urdf/ur5_gripper.urdf)."""
