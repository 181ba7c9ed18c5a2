"""The families of unseen held-rod scenes (``unseen.wrist``) and how a side view is judged.

A side view is *right* when it is within the side view's contract of the held rod (tilt
within 1 deg, the axis and the grasp position along the rod within 3 mm: tests/
test_side_view_frames.py, docs/design.md), *refused* when it raises a ``PerceptionError``,
and *wrong* otherwise. Families marked ``should_measure`` are scenes the side view is meant
to measure (other rods within the jaws' range, other tilts, light, tables, clutter out of
the jaws' slab): refusing them all is no pass. The rest (clutter and a second rod within
the slab between the jaws, a rod turned out of the jaws' plane) may be refused.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from comgrasp_pin.config import sensor_preset
from comgrasp_pin.errors import PerceptionError
from comgrasp_pin.perception import observe_held_rod
from comgrasp_pin.robot import RobotModel
from comgrasp_pin.simulation.depth_noise import DepthNoise
from comgrasp_pin.simulation.eyes import arm_capsules, handle_radius, side_camera_pose
from comgrasp_pin.simulation.world import SIDE_CAMERA
from comgrasp_pin.workcell import TABLE_Z

from .wrist import HeldRod, Thing, WristLook, WristScene, render_side

TILT_BOUND_DEG = 1.0  # the side view's contract
POSITION_BOUND = 3e-3  # m: the axis and the grasp position along the rod
DEPTHS = ("clean", "realistic")  # the render as it is; with the realistic preset's errors

BROWN, GREEN, BLUE = (0.55, 0.35, 0.2, 1.0), (0.2, 0.6, 0.25, 1.0), (0.2, 0.3, 0.75, 1.0)
BLACK, WHITE, RED = (0.08, 0.08, 0.08, 1.0), (0.92, 0.92, 0.9, 1.0), (0.75, 0.15, 0.12, 1.0)
PLAIN = HeldRod("cylinder", 0.3, 0.012, np.radians(15.0), 0.03)  # a 2.4 cm brown stick


def _on_plain_axis(along: float) -> tuple:
    """(3,) the point ``along`` (m) from the TCP on PLAIN's axis, in the ee frame."""
    return tuple(np.round(along * PLAIN.T_ee_obj()[:3, 0], 6))


def _shapes() -> list[WristScene]:
    rods = {
        "cylinder_1.2cm": HeldRod("cylinder", 0.25, 0.006, np.radians(10), 0.02, rgba=RED),
        "cylinder_4.4cm": HeldRod("cylinder", 0.35, 0.022, np.radians(-20), -0.03, rgba=BLUE),
        "cylinder_6cm": HeldRod("cylinder", 0.4, 0.03, np.radians(25), 0.0, rgba=GREEN),
        "capsule_2cm": HeldRod("capsule", 0.3, 0.01, np.radians(-10), 0.04, rgba=GREEN),
        "square_2cm": HeldRod("box", 0.3, 0.01, np.radians(20), 0.02, rgba=BROWN),
        "square_3cm": HeldRod("box", 0.28, 0.015, np.radians(-15), -0.02, rgba=BLACK),
        "square_2cm_rolled_45deg": HeldRod(
            "box", 0.3, 0.01, np.radians(10), 0.0, roll=np.pi / 4, rgba=WHITE
        ),  # fmt: skip
        "hex_2.4cm": HeldRod("hex", 0.3, 0.012, np.radians(-25), 0.03, rgba=BLACK),
        "hex_3cm": HeldRod("hex", 0.35, 0.015, np.radians(30), -0.04, rgba=WHITE),
        "cylinder_0.8cm": HeldRod("cylinder", 0.25, 0.004, np.radians(-5), 0.0, rgba=BLACK),
        "cylinder_8cm": HeldRod("cylinder", 0.4, 0.04, np.radians(15), 0.03, rgba=WHITE),
        "hammer_green": HeldRod("obj2", 0.32, tilt=np.radians(20), offset=0.05, rgba=GREEN),
        "torch_white": HeldRod("obj4", 0.3, tilt=np.radians(-15), offset=0.04, rgba=WHITE),
    }
    return [WristScene("rod_shapes", name, rod, should_measure=True) for name, rod in rods.items()]


def _tilts() -> list[WristScene]:
    out = []
    for deg, off in ((-50, 0.0), (-35, 0.05), (40, -0.05), (55, 0.02), (0, 0.08)):
        rod = replace(PLAIN, tilt=np.radians(deg), offset=off)
        out.append(WristScene("tilts", f"{deg:g}deg_{1e2 * off:g}cm", rod, should_measure=True))
    for deg in (2.0, 5.0):  # turned about ee-z: the rod's axis leaves the jaws' plane
        rod = replace(PLAIN, turn=np.radians(deg))
        out.append(WristScene("turned_in_jaws", f"turned_{deg:g}deg", rod))
    return out


def _looks() -> list[WristScene]:
    out = []
    lights = {
        "dim": (((0.06, 0.06, 0.06), (0, 0, -1)),),
        "bright": (((1.0, 1.0, 1.0), (0.2, 0.1, -1)),),
        "warm": (((0.7, 0.45, 0.25), (0.1, 0.2, -1)),),
        "blue": (((0.25, 0.35, 0.7), (-0.2, 0, -1)),),
        "from_the_side": (((0.9, 0.9, 0.9), (0.0, 1.0, -0.2)),),
    }
    for name, light in lights.items():
        head = (0.03, 0.03) if name == "dim" else (0.25, 0.2)
        look = WristLook(lights=light, headlight=head)
        out.append(WristScene("light", name, PLAIN, look, should_measure=True))
    tables = {"white": WristLook(table_rgba=WHITE), "black": WristLook(table_rgba=BLACK),
              "green": WristLook(table_rgba=GREEN),
              "checker": WristLook(table_rgba=WHITE, texture="checker", texture_rgba=BLACK),
              "noise": WristLook(texture="noise", texture_rgba=(0.3, 0.2, 0.1, 1))}  # fmt: skip
    for name, look in tables.items():
        out.append(WristScene("table", name, PLAIN, look, should_measure=True))
    for height, deg in ((0.25, -30.0), (0.3, 20.0)):  # the rod's end 3-5 cm above the table
        look = WristLook(ee_height=height)
        rod = replace(PLAIN, tilt=np.radians(deg), offset=0.0)
        out.append(WristScene("table", f"low_{1e2 * height:g}cm_{deg:g}deg", rod, look,
                              should_measure=True))  # fmt: skip
    return out


def _clutter() -> list[WristScene]:
    out = []
    boxes = {
        "behind_far": ((0.0, 0.15, 0.02), True),
        "behind_in_slab": ((0.02, 0.06, 0.0), False),
        "at_the_end": ((0.2, 0.0, -0.04), False),
        "below": ((0.0, 0.0, 0.12), True),
        "below_near": ((0.05, 0.0, 0.08), False),
        "beside_in_slab": ((-0.12, 0.05, -0.1), False),
    }
    for name, (centre, measure) in boxes.items():
        box = Thing("box", (centre,), (0.04, 0.02, 0.03))
        out.append(WristScene("clutter_box", name, PLAIN, things=(box,), should_measure=measure))
    cables = {
        "behind_far": (((-0.2, 0.15, -0.05), (0.2, 0.15, 0.05)), True),
        "across_in_slab": (((-0.05, 0.05, -0.15), (0.05, 0.05, 0.15)), False),
        "along_in_slab": (((-0.15, 0.04, -0.04), (0.15, 0.04, 0.04)), False),
        "hanging_below": (((-0.02, 0.0, 0.06), (0.0, 0.01, 0.15), (0.03, 0.0, 0.25)), True),
    }
    for name, (points, measure) in cables.items():
        cable = Thing("cable", points, (0.003,), BLACK)
        out.append(WristScene("clutter_cable", name, PLAIN, things=(cable,),
                              should_measure=measure))  # fmt: skip
    seconds = {
        "parallel_far": (0.0, (0.0, 0.15, 0.0), True),
        "parallel_in_slab": (0.0, (0.02, 0.06, 0.0), False),
        "parallel_touching": (0.0, (0.0, 0.025, 0.0), False),
        "crossing_in_slab": (np.pi / 2, (0.02, 0.05, 0.0), False),
        "crossing_30deg_in_slab": (np.radians(-30), (0.0, 0.05, 0.0), False),
        "parallel_below": (0.0, (0.03, 0.0, 0.1), False),
        "parallel_below_touching": (np.radians(15), (0.0, 0.0, 0.024), False),
        "in_line_2cm_apart": (np.radians(15), _on_plain_axis(0.27), False),
        "in_line_touching": (np.radians(15), _on_plain_axis(0.247), False),  # fmt: skip
    }
    for name, (tilt, centre, measure) in seconds.items():
        other = HeldRod("cylinder", 0.25, 0.01, tilt, rgba=GREEN, centre_ee=centre)
        out.append(WristScene("second_rod", name, PLAIN, others=(other,),
                              should_measure=measure))  # fmt: skip
    return out


def families() -> list[WristScene]:
    """Every unseen held-rod scene."""
    return [*_shapes(), *_tilts(), *_looks(), *_clutter()]


def side_view_outcome(scene: WristScene, robot: RobotModel, noise_seed: int = 0) -> dict:
    """Render ``scene``; the side view's outcome in each of DEPTHS (``judge``'s dict). The
    view gets what ``eyes.look_from_side`` gives it: the rod's length (from the top view),
    the fingers' reading, the arm's capsules, the table's height."""
    depth, rig, sim = render_side(scene, robot)
    try:
        camera = rig.intrinsics(SIDE_CAMERA)
    finally:
        rig.close()
    T_world_ee, T_ee_cam = side_camera_pose(robot, sim.q)
    noise = DepthNoise(sensor_preset("realistic").side_depth, noise_seed)
    T_ee_obj = scene.rod.T_ee_obj()
    out = {}
    for label in DEPTHS:
        T_cal = np.eye(4) if label == "clean" else noise.T_cam_calibrated
        image = depth if label == "clean" else noise.apply(depth)
        try:
            found = observe_held_rod(
                None, image, camera, T_ee_cam @ T_cal, T_world_ee, TABLE_Z, scene.rod.length,
                arm_capsules(robot, sim.q), None, handle_radius(sim.finger_q[0]),
            )  # fmt: skip
        except PerceptionError as exc:
            found = exc
        # What a perfect side view with that calibration reports: the truth seen through it.
        T_seen = T_ee_cam @ T_cal @ np.linalg.inv(T_ee_cam) @ T_ee_obj
        out[label] = judge(found, T_seen, scene.rod.offset)
    return out


def judge(found, T_ee_obj: np.ndarray, offset: float) -> dict:
    """{"outcome": "right" | "refused" | "wrong", ...}: a ``SideView`` against the held rod
    (pose ``T_ee_obj``, held ``offset`` m along +x_obj from its centre; tilt, axis and grasp
    position within the contract is right), or the PerceptionError raised."""
    if isinstance(found, PerceptionError):
        return {"outcome": "refused", "error": type(found).__name__, "why": str(found)[:160]}
    R, centre = T_ee_obj[:3, :3], T_ee_obj[:3, 3]
    theta_true = np.arctan2(-R[2, 0], R[0, 0])  # the axis' tilt in the ee x-z plane
    tilt_err = (found.theta - theta_true + np.pi / 2) % np.pi - np.pi / 2
    held = centre + offset * R[:, 0]  # the axis' point the jaws hold
    seen_o, seen_x = found.T_ee_obj[:3, 3], found.T_ee_obj[:3, 0]
    d = held - seen_o
    axis_err = np.linalg.norm(d - (d @ seen_x) * seen_x)
    grasp_err = found.grasp_offset - np.sign(seen_x @ R[:, 0]) * offset
    errors = {"tilt_deg": round(abs(float(np.degrees(tilt_err))), 3),
              "axis_mm": round(1e3 * float(axis_err), 3),
              "grasp_mm": round(1e3 * float(grasp_err), 3)}  # fmt: skip
    right = (errors["tilt_deg"] <= TILT_BOUND_DEG and errors["axis_mm"] <= 1e3 * POSITION_BOUND
             and abs(errors["grasp_mm"]) <= 1e3 * POSITION_BOUND)  # fmt: skip
    return {"outcome": "right" if right else "wrong", **errors}
