"""The top view on real cameras' frames (../shared/realdata/rgbd, never copied here).

The truth of the PrimeSense frame is its authors' own mask of the object, drawn in the depth
image (segmask_0.png): the object's extent, direction and centre are taken from those pixels
here, in the test, with NumPy alone. Its colour image is not registered with its depth.
"""

from pathlib import Path

import cv2
import numpy as np
import pytest

from comgrasp_pin.errors import AmbiguousObjectError, ColourDepthMismatchError, PerceptionError
from comgrasp_pin.perception import detect_rod_top_down
from comgrasp_pin.perception.frames.camera_input import camera_frame
from comgrasp_pin.perception.frames.rgbd_files import read_rgbd
from comgrasp_pin.perception.top_view.table_plane import fit_table_plane

RGBD = Path(__file__).resolve().parents[2] / "shared" / "realdata" / "rgbd"
FLASHLIGHT = RGBD / "overhead_primesense_flashlight"
CLUTTER = RGBD / "realsense_d435_clutter"
pytestmark = pytest.mark.skipif(
    not RGBD.is_dir(), reason=f"the real frames are not here ({RGBD}): they are never copied"
)


def _frame(folder: Path, colour: str, depth: str, info: str, scale=None):
    files = read_rgbd(folder / colour, folder / depth, folder / info, scale)
    return camera_frame(files.rgb, files.depth, files.camera, files.depth_scale)


def _truth_from_mask(depth, camera, T_frame_cam, mask):
    """(centre xy, length, yaw) of the mask's pixels lifted to the frame: the extent between
    the 1st and 99th percentiles along their principal direction."""
    v, u = np.nonzero(mask & (depth > 0))
    z = depth[v, u]
    cam = np.column_stack([(u - camera.cx) * z / camera.fx, (v - camera.cy) * z / camera.fy, z])
    p = cam @ T_frame_cam[:3, :3].T + T_frame_cam[:3, 3]
    centroid = p[:, :2].mean(axis=0)
    direction = np.linalg.svd(p[:, :2] - centroid, full_matrices=False)[2][0]
    lo, hi = np.percentile((p[:, :2] - centroid) @ direction, [1, 99])
    return centroid + 0.5 * (lo + hi) * direction, hi - lo, np.arctan2(direction[1], direction[0])


def _wrong(found, truth) -> list[str]:
    """Issue 34's wrong answer: a length 20 % off, a yaw 10 deg off, a centre 3 cm off."""
    centre, length, yaw = truth
    dyaw = abs((np.degrees(found.grasp.yaw - yaw) + 90) % 180 - 90)
    dc = np.hypot(found.grasp.x - centre[0], found.grasp.y - centre[1])
    return [what for what, bad in (("length", abs(found.length - length) > 0.2 * length),
                                   ("yaw", dyaw > 10), ("centre", dc > 0.03)) if bad]  # fmt: skip


@pytest.fixture(scope="module")
def flashlight():
    rgb, depth, camera = _frame(FLASHLIGHT, "color_0.png", "depth_0_mm.png",
                                "primesense_camera_info.yaml")  # fmt: skip
    mask = cv2.imread(str(FLASHLIGHT / "segmask_0.png"), cv2.IMREAD_GRAYSCALE) > 0
    return rgb, depth, camera, mask


def test_the_flashlight_is_measured_from_its_depth_alone_in_the_tables_frame(flashlight):
    """No camera pose: the table's plane is fitted, its clear rectangle is the pick area
    (the robot's fingers at the image's foot left out), and the depth alone measures the
    flashlight as its authors' mask has it."""
    _, depth, camera, mask = flashlight
    T_table_cam, area = fit_table_plane(depth, camera)
    found = detect_rod_top_down(None, depth, camera, T_table_cam, area)
    assert _wrong(found, _truth_from_mask(depth, camera, T_table_cam, mask)) == []
    assert 0.17 < found.length < 0.23  # about 20 cm


def test_the_flashlight_in_the_world_frame_given_its_pose(flashlight):
    """With the camera's pose (the board at z = 0.160 m) and the board as the pick area,
    short of the robot's fingers (they reach over the board up to x = 0.22 m)."""
    _, depth, camera, mask = flashlight
    T_world_cam = np.loadtxt(FLASHLIGHT / "T_world_cam.txt")
    found = detect_rod_top_down(None, depth, camera, T_world_cam, (0.25, 0.65, -0.35, 0.35))
    assert abs(found.table_z - 0.160) < 0.003
    assert _wrong(found, _truth_from_mask(depth, camera, T_world_cam, mask)) == []


def test_the_unregistered_colour_never_gives_a_wrong_answer(flashlight):
    """With its colour image (not registered with the depth) the flashlight is measured as
    from the depth alone, or refused because the two do not line up: never the part where
    they happen to overlap."""
    rgb, depth, camera, mask = flashlight
    T_table_cam, area = fit_table_plane(depth, camera)
    try:
        found = detect_rod_top_down(rgb, depth, camera, T_table_cam, area)
    except ColourDepthMismatchError as exc:
        assert "do not line up" in str(exc)
        return
    assert _wrong(found, _truth_from_mask(depth, camera, T_table_cam, mask)) == []


def test_colour_shifted_against_the_depth_never_gives_a_wrong_answer(flashlight):
    """The colour moved 12 px further against the depth, with the depth's noise raised so
    that the rod's ends are left to the colour: refused because the two do not line up, or
    measured from the depth alone as the authors' mask has it; never measured from the part
    where the colour and the depth overlap."""
    rgb, depth, camera, mask = flashlight
    T_table_cam, area = fit_table_plane(depth, camera)
    shifted = cv2.warpAffine(rgb, np.float32([[1, 0, 12], [0, 1, 0]]), rgb.shape[1::-1],
                             borderMode=cv2.BORDER_REPLICATE)  # fmt: skip
    noisy = depth + np.random.default_rng(0).normal(0.0, 0.006, depth.shape)
    try:
        found = detect_rod_top_down(shifted, noisy, camera, T_table_cam, area)
    except ColourDepthMismatchError as exc:
        assert "registered" in str(exc)
        return
    except PerceptionError:
        return  # refused for another reason: no answer, no wrong answer
    assert _wrong(found, _truth_from_mask(depth, camera, T_table_cam, mask)) == []


@pytest.mark.parametrize("with_colour", [False, True])
def test_the_cluttered_realsense_table_is_refused_for_what_lies_there(with_colour):
    """A registered D435 frame of a cluttered table: refused because what lies in the pick
    area is not one rod, not because something touches the image's border. The table's
    clear rectangle (the pick area found) holds the end of a spray bottle, its cap's edge
    cut by the rectangle; the rest of the clutter lies beyond it. The depth's noise bumps
    on the bare table (5-6 mm, under 4 noise stds) are no objects to count."""
    rgb, depth, camera = _frame(CLUTTER, "color.png", "depth.png", "camera_info_ros2.yaml",
                                0.001)  # fmt: skip
    T_table_cam, area = fit_table_plane(depth, camera)
    with pytest.raises(AmbiguousObjectError, match="not one rod|objects") as refused:
        detect_rod_top_down(rgb if with_colour else None, depth, camera, T_table_cam, area)
    assert "border" not in str(refused.value) and "image's edge" not in str(refused.value)


def _yaw_in_world(found, T_table_cam, T_world_cam) -> float:
    """A yaw measured in the table's frame as a yaw in the world (rad)."""
    axis = T_world_cam[:3, :3] @ T_table_cam[:3, :3].T @ [np.cos(found.grasp.yaw),
                                                          np.sin(found.grasp.yaw), 0.0]  # fmt: skip
    return float(np.arctan2(axis[1], axis[0]))


@pytest.mark.parametrize("with_colour", [False, True])
@pytest.mark.parametrize(
    "area",
    [(0.26, 0.56, -0.20, 0.15), (0.29, 0.59, -0.20, 0.15), (0.23, 0.53, -0.20, 0.15),
     (0.26, 0.56, -0.17, 0.18), (0.26, 0.56, -0.23, 0.12),
     (0.20, 0.55, -0.20, 0.15)],  # the last reaches the robot's fingers, 16 cm from it
)  # fmt: skip
def test_the_flashlight_gives_one_answer_with_or_without_its_pose(flashlight, area, with_colour):
    """Issue 44: the same scene in the world frame (its pose given, the pick area moved by
    3 cm either way with nothing entering or leaving it, or reaching the robot's fingers at
    the image's foot) and in the fitted table's frame: the same verdict (measured), the
    same rod within 1 cm of length and 3 deg of yaw, right against the authors' mask."""
    rgb, depth, camera, mask = flashlight
    colour = rgb if with_colour else None
    T_table_cam, table_area = fit_table_plane(depth, camera)
    in_table = detect_rod_top_down(colour, depth, camera, T_table_cam, table_area)
    T_world_cam = np.loadtxt(FLASHLIGHT / "T_world_cam.txt")
    in_world = detect_rod_top_down(colour, depth, camera, T_world_cam, area)
    assert _wrong(in_world, _truth_from_mask(depth, camera, T_world_cam, mask)) == []
    assert abs(in_world.length - in_table.length) < 0.01
    dyaw = np.degrees(_yaw_in_world(in_table, T_table_cam, T_world_cam) - in_world.grasp.yaw)
    assert abs((dyaw + 90) % 180 - 90) < 3.0


def test_the_fitted_tables_frame_is_the_boards_own(flashlight):
    """The PrimeSense's board, seen in the frame ``fit_table_plane`` gives, is level as in
    the calibrated world frame (the authors' camera pose, an independent reference): the
    plane is fitted again under the pick area, not over all the image sees (2.8 mrad off)."""
    _, depth, camera, mask = flashlight
    T_table_cam, area = fit_table_plane(depth, camera)
    T_world_cam = np.loadtxt(FLASHLIGHT / "T_world_cam.txt")
    table_z_world = T_world_cam[:3, :3] @ T_table_cam[:3, :3].T  # R_world_table
    tilt_mrad = 1e3 * np.arccos(np.clip(table_z_world[2, 2], -1.0, 1.0))
    assert tilt_mrad < 0.5, tilt_mrad
