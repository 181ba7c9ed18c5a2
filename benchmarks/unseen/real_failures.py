"""Frames made in MuJoCo that reproduce the real cameras' failure modes (issue 34, item 4).

Four modes, each a few frames of the top camera (``unseen.scenes``: built from scratch,
rendered with the package's own ``CameraRig``):

- ``colour_shift``: the colour image shifted against the depth by 5, 10, 20, 30 px, along
  the image's u and v (an affine shift of the RGB only, the border repeated), as on a
  colour/depth pair that is not registered;
- ``thin_handle``: a tool whose handle is under 1 cm high (a thin cylinder with a box head
  at one end, a mallet; the bare thin rod; the project's obj1, whose handle is 1 cm), on
  registered frames and with the colour shifted by 10 px (the real mallet);
- ``structured_light``: the depth of a structured-light camera (PrimeSense class: focal
  580 px, baseline 7.5 cm, 1/8 px disparity, patchy noise, holes at depth edges, dropouts,
  1 mm steps) made with the package's ``DepthNoise`` and a configuration of its own, and
  the projector's shadow (no depth beside each step, on the projector's side) added here;
- ``table``: textured and coloured tables (a wood grain, a board the rod's own colour, a
  white, a black and a red board, a coarse checker), through ``Look``.

A frame's outcome follows issue 34: *wrong* when a measurement comes back more than 20 % off
in length, 10 deg off in yaw or 3 cm off in centre from the tool as built; *refused* on a
``PerceptionError``; *right* otherwise. ``precise`` says whether it also meets the
family's own tight bounds (``families.judge``: 3 mm, 1 deg, 8 mm). Each frame is also run
without its colour image (``depth_alone``): the top view measures the depth first and
looks at the colour only where a real camera's (cleaned) depth fails, so a colour shift or
a table's colour matter on structured-light depth only; the clean renders are controls.
"""

from __future__ import annotations

import zlib
from dataclasses import dataclass, replace

import cv2
import numpy as np

from comgrasp_pin.config import DepthNoiseConfig
from comgrasp_pin.errors import ObjectNotFoundError, PerceptionError
from comgrasp_pin.perception import detect_rod_top_down
from comgrasp_pin.perception.top_view.table_plane import fit_table_plane
from comgrasp_pin.simulation.depth_noise import DepthNoise

from .families import BLACK, BROWN, GREEN, _at, judge
from .moved_areas import moved_areas
from .scenes import Clutter, Look, Rod, UnseenScene, render_top

WRONG_LENGTH = 0.20  # relative
WRONG_YAW_DEG = 10.0
WRONG_CENTRE = 0.03  # m
SHIFTS_PX = (5, 10, 20, 30)
# The depth each colour-shift, thin-handle and table frame is run with: the render as it is
# (the top view then measures from the depth alone and never looks at the colour), and a
# structured-light camera's (its depth cleaned: the colour is used where the depth fails)
DEPTHS = ("clean", "structured_light_shadow")

# A structured-light camera (PrimeSense / Kinect v1 class) as DepthNoise's parameters
STRUCTURED_LIGHT = DepthNoiseConfig(
    focal_px=580.0,
    baseline=0.075,
    subpixel=0.125,
    noise_corr_px=3.0,
    edge_jump=0.005,
    edge_band_px=2,
    edge_hole_prob=0.7,
    flying_prob=0.2,
    dropout_prob=0.02,
    quantum=0.001,
    scale_std=0.003,
)
PROJECTOR_BASELINE = 0.075  # m, projector to camera along +u


@dataclass(frozen=True)
class Frame:
    """One frame: its mode, its parameter, the scene rendered, the truth judged against
    (``truth``: scene-like, its rods the tools as built), and what is done to the render."""

    mode: str
    parameter: str
    scene: UnseenScene
    truth: UnseenScene
    shift_px: tuple[int, int] = (0, 0)  # (du, dv) of the colour image
    depth: str = "clean"  # "clean", "structured_light", "structured_light_shadow"


def shift_colour(rgb: np.ndarray, du: int, dv: int) -> np.ndarray:
    """``rgb`` moved by (du, dv) px against the depth (the border repeated)."""
    M = np.array([[1.0, 0.0, du], [0.0, 1.0, dv]])
    h, w = rgb.shape[:2]
    return cv2.warpAffine(rgb, M, (w, h), flags=cv2.INTER_NEAREST,
                          borderMode=cv2.BORDER_REPLICATE)  # fmt: skip


def projector_shadow(depth: np.ndarray, fx: float, jump: float = 0.005) -> np.ndarray:
    """A copy of ``depth`` with the projector's shadow lost (0): beside every step toward
    the far side along +u, as many pixels as the disparity between the two sides."""
    out = depth.copy()
    z = np.where(np.isfinite(depth) & (depth > 0), depth, np.inf)
    lost = np.zeros(depth.shape, bool)
    for s in range(1, 16):
        near = np.full_like(z, np.inf)
        near[:, s:] = z[:, :-s]
        step = near < z - jump
        width = fx * PROJECTOR_BASELINE * (1.0 / np.where(step, near, 1.0) - 1.0 / z)
        lost |= step & (width >= s)
    out[lost] = 0.0
    return out


def _mallet(x: float, y: float, yaw: float, radius: float, handle: float = 0.24,
            head=(0.02, 0.045, 0.02), rgba=BROWN) -> tuple[UnseenScene, Rod]:  # fmt: skip
    """A handle of ``radius`` (m) with a box head (half sizes ``head``) at its +axis end:
    (the scene's rods and clutter as a scene, the tool as built as a rod)."""
    rod = Rod("cylinder", x, y, yaw, handle, radius, rgba)
    centre = _at(rod, 0.5 * handle + head[0])
    box = Clutter("box", (centre,), head, yaw, rgba=(0.45, 0.3, 0.18, 1.0))
    tool_centre = _at(rod, head[0])
    tool = Rod("cylinder", *tool_centre, yaw, handle + 2 * head[0], radius, rgba)
    return UnseenScene("thin_handle", "", (rod,), clutter=(box,)), tool


def frames(seed: int = 0, quick: bool = False) -> list[Frame]:
    """Every frame of the family (poses drawn from ``seed``); ``quick``: fewer."""
    rng = np.random.default_rng(seed)

    def pose():
        return rng.uniform(0.5, 0.6), rng.uniform(-0.06, 0.06), rng.uniform(-np.pi / 2, np.pi / 2)

    hammer = Rod("obj2", *pose(), length=0.32, rgba=None)
    cylinder = Rod("cylinder", *pose(), length=0.28, radius=0.012, rgba=BROWN)
    torch = Rod("obj4", *pose(), length=0.30, rgba=None)
    out: list[Frame] = []

    def plain(rod: Rod, family: str, look: Look | None = None) -> UnseenScene:
        return UnseenScene(family, rod.shape, (rod,), look or Look(), (), True)

    for rod in (hammer, cylinder):
        scene = plain(rod, "colour_shift")
        for depth in DEPTHS:
            for s in (0, *SHIFTS_PX):  # 0: the registered frame, for comparison
                for axis, shift in (("u", (s, 0)), ("v", (0, s))):
                    if (s == 0 or quick and rod is cylinder) and axis == "v":
                        continue
                    name = f"{rod.shape}_{s}px_{axis}_{depth}"
                    out.append(Frame("colour_shift", name, scene, scene, shift, depth))

    thin = []
    for radius in (0.0045, 0.0035):
        scene, tool = _mallet(*pose(), radius)
        name = f"mallet_{2e3 * radius:g}mm_high"
        thin.append((name, replace(scene, name=name), replace(scene, rods=(tool,))))
    bare = Rod("cylinder", *pose(), 0.25, 0.004, BROWN)
    thin.append(("rod_8mm_high", plain(bare, "thin_handle"), plain(bare, "thin_handle")))
    obj1 = Rod("obj1", *pose(), length=0.4, rgba=None)
    thin.append(("obj1_10mm_handle", plain(obj1, "thin_handle"), plain(obj1, "thin_handle")))
    for name, scene, truth in thin:
        for depth in DEPTHS:
            out.append(Frame("thin_handle", f"{name}_{depth}", scene, truth, (0, 0), depth))
            out.append(Frame("thin_handle", f"{name}_shift10px_{depth}", scene, truth, (10, 0),
                             depth))  # fmt: skip

    for rod in (hammer, cylinder, torch):
        scene = plain(rod, "structured_light")
        for depth in ("structured_light", "structured_light_shadow"):
            out.append(Frame("structured_light", f"{rod.shape}_{depth}", scene, scene,
                             depth=depth))  # fmt: skip
    scene, tool = _mallet(*pose(), 0.0045)
    out.append(Frame("structured_light", "mallet_9mm_structured_light_shadow", scene,
                     replace(scene, rods=(tool,)), depth="structured_light_shadow"))  # fmt: skip

    looks = {
        "wood_grain": Look((0.55, 0.38, 0.22, 1), "noise", (0.35, 0.22, 0.12, 1)),
        "rod_coloured_board": Look(BROWN),
        "white_board": Look((0.92, 0.92, 0.9, 1)),
        "black_board": Look(BLACK),
        "red_board": Look((0.6, 0.15, 0.12, 1)),
        "coarse_checker": Look(texture="checker", texture_rgba=(0.3, 0.3, 0.3, 1)),
        "green_fine_checker": Look(GREEN, "fine_checker", (0.5, 0.5, 0.45, 1)),
    }
    for k, (name, look) in enumerate(looks.items()):
        if quick and k >= 5:
            break
        for rod in (hammer, cylinder):
            scene = plain(rod, "table", look)
            for depth in DEPTHS:
                out.append(Frame("table", f"{name}_{rod.shape}_{depth}", scene, scene, (0, 0),
                                 depth))  # fmt: skip
    return out


def outcome(found, truth: UnseenScene) -> dict:
    """Issue 34's outcome of ``found`` (a ``RodDetection`` or a ``PerceptionError``) against
    the first rod of ``truth``, with the errors and the family's tight verdict."""
    if isinstance(found, PerceptionError):
        return {"outcome": "refused", "error": type(found).__name__, "why": str(found)[:200]}
    rod = truth.rods[0]
    yaw = (found.grasp.yaw - rod.yaw + np.pi / 2) % np.pi - np.pi / 2
    errors = {
        "centre_mm": round(1e3 * float(np.hypot(found.grasp.x - rod.x, found.grasp.y - rod.y)), 2),
        "yaw_deg": round(abs(float(np.degrees(yaw))), 2),
        "length_mm": round(1e3 * float(found.length - rod.length), 2),
        "length_true_mm": round(1e3 * rod.length, 1),
    }
    wrong = (
        abs(found.length - rod.length) > WRONG_LENGTH * rod.length
        or errors["yaw_deg"] > WRONG_YAW_DEG
        or errors["centre_mm"] > 1e3 * WRONG_CENTRE
    )
    precise = judge(found, replace(truth, rods=(rod,)))["outcome"] == "right"
    return {"outcome": "wrong" if wrong else "right", "precise": precise, **errors}


class _Renders:
    """Renders cached by scene (a scene is rendered once for all its frames)."""

    def __init__(self):
        self._cache: dict = {}

    def __call__(self, scene: UnseenScene):
        key = repr(scene)
        if key not in self._cache:
            self._cache[key] = render_top(scene)
        return self._cache[key]


def noise_seed(frame: Frame, seed: int = 0, draw: int = 0) -> int:
    """The seed of ``frame``'s depth noise: one per scene (its shifts and colours are
    compared on the same depth), the run's ``seed`` and the ``draw`` moving it."""
    return seed * 1000 + zlib.crc32(repr(frame.scene).encode()) % 1000 + 7919 * draw


def run_frame(frame: Frame, renders, noise_seed: int = 0) -> dict:
    """Render (or reuse) ``frame``'s scene, apply its shift and depth, run the top view:
    the outcome with the colour image, and (``depth_alone``) without it."""
    rgb, depth, camera, T_world_cam = renders(frame.scene)
    if frame.shift_px != (0, 0):
        rgb = shift_colour(rgb, *frame.shift_px)
    if frame.depth.startswith("structured_light"):
        depth = DepthNoise(STRUCTURED_LIGHT, noise_seed).apply(depth)
        if frame.depth.endswith("shadow"):
            depth = projector_shadow(depth, camera.fx)
    judged, same, same_moved = {}, {}, {}
    try:
        in_table = fit_table_plane(depth, camera)
    except PerceptionError:
        in_table = None
    areas = moved_areas(frame.scene)
    for label, colour in (("", rgb), ("depth_alone", None)):
        found = _detect(colour, depth, camera, T_world_cam, None)
        judged[label] = outcome(found, frame.truth)
        # issue 44: the same answer in the fitted table's frame (no camera pose)
        other = _detect(colour, depth, camera, *in_table) if in_table else ObjectNotFoundError()
        same[label or "with_colour"] = same_answer(other, found, in_table[0], T_world_cam) \
            if in_table else isinstance(found, PerceptionError)  # fmt: skip
        # ... and with the pick area moved by 3 cm where no object enters or leaves
        same_moved[label or "with_colour"] = all(
            same_answer(_detect(colour, depth, camera, T_world_cam, a), found, T_world_cam,
                        T_world_cam) for a in areas)  # fmt: skip
    return {**judged[""], "depth_alone": judged["depth_alone"], "same_in_table_frame": same,
            "moved_areas": len(areas), "same_for_moved_areas": same_moved}  # fmt: skip


def _detect(colour, depth, camera, T, area):
    try:
        if area is None:
            return detect_rod_top_down(colour, depth, camera, T)
        return detect_rod_top_down(colour, depth, camera, T, area)
    except PerceptionError as exc:
        return exc


def world_yaw(found, T_frame_cam, T_world_cam) -> float:
    """The detection's yaw (in the frame of ``T_frame_cam``) as a yaw in the world (rad)."""
    axis = np.array([np.cos(found.grasp.yaw), np.sin(found.grasp.yaw), 0.0])
    v = T_world_cam[:3, :3] @ T_frame_cam[:3, :3].T @ axis
    return float(np.arctan2(v[1], v[0]))


def same_answer(in_table, in_world, T_table_cam, T_world_cam) -> bool:
    """The same answer both ways: both refused, or both measured within 1 cm and 3 deg."""
    if isinstance(in_table, PerceptionError) or isinstance(in_world, PerceptionError):
        return isinstance(in_table, PerceptionError) and isinstance(in_world, PerceptionError)
    dyaw = np.degrees(world_yaw(in_table, T_table_cam, T_world_cam) - in_world.grasp.yaw)
    return bool(abs(in_table.length - in_world.length) <= 0.01
                and abs((dyaw + 90) % 180 - 90) <= 3.0)  # fmt: skip
