"""The fitted table's frame is the plane under the pick area (``table_plane.fit_table_plane``).

The depth images are built here: a camera 0.8 m above a table at z = 0, looking down, and a
board on the table whose top is a plane written down in the test (the truth). The whole
view's plane is a compromise between the board and the table around it; the frame must be
the board's, where the rod lies. On a single plane seen with a noisy camera the plane is
the whole view's: fewer points would only tilt it by their noise.
"""

from __future__ import annotations

import numpy as np

from comgrasp_pin.camera import PinholeCamera
from comgrasp_pin.perception.top_view import table_plane
from comgrasp_pin.perception.top_view.table_plane import fit_table_plane

CAMERA = PinholeCamera.from_fovy(640, 480, 50.0)
HEIGHT = 0.8  # m


def _depth(surfaces) -> np.ndarray:
    """z-depth of a camera looking straight down at ``surfaces``: (height (x, y) -> m,
    where (x, y) -> bool) from the highest down; each ray takes the first it meets inside
    its region (fixed-point iterations on that surface's height, a few mm from flat)."""
    v, u = np.mgrid[0 : CAMERA.height, 0 : CAMERA.width].astype(float)
    rx, ry = (u - CAMERA.cx) / CAMERA.fx, (v - CAMERA.cy) / CAMERA.fy
    depth = np.full(rx.shape, np.inf)
    for height, where in surfaces:
        h = np.zeros_like(rx)
        for _ in range(10):
            h = height(rx * (HEIGHT - h), ry * (HEIGHT - h))
        hit = np.isinf(depth) & where(rx * (HEIGHT - h), ry * (HEIGHT - h))
        depth[hit] = HEIGHT - h[hit]
    return depth


def _tilt_mrad(T_table_cam: np.ndarray, normal_cam: np.ndarray) -> float:
    """The angle between the frame's z and a plane's normal (camera frame), mrad."""
    z_cam = T_table_cam[2, :3]  # the table frame's z in the camera frame (a row of R^T)
    return float(1e3 * np.arccos(min(1.0, abs(float(z_cam @ normal_cam)))))


def test_a_board_on_a_table_is_the_frame_not_the_whole_view():
    """A board 4 mm thick, tilted 3 mrad, fills most of the view; beyond a 3 cm gap (the
    floor, 30 cm down) the table it lies on shows along the image's edge. The whole view's
    plane lies between board and table; the frame is the board's (within 0.2 mrad)."""
    slope = 0.003

    surfaces = [
        (lambda x, y: 0.004 + slope * y, lambda x, y: (np.abs(x) < 0.45) & (np.abs(y) < 0.3)),
        (lambda x, y: np.zeros_like(x), lambda x, y: y < -0.33),  # the table
        (lambda x, y: np.full_like(x, -0.3), lambda x, y: np.ones_like(x, bool)),  # the floor
    ]  # fmt: skip
    depth = _depth(surfaces) + np.random.default_rng(1).normal(0.0, 1e-4, (480, 640))
    board_normal = np.array([0.0, -slope, -1.0]) / np.hypot(1.0, slope)  # camera y = world y
    T, area = fit_table_plane(depth, CAMERA)
    assert _tilt_mrad(T, board_normal) < 0.2, _tilt_mrad(T, board_normal)
    kept = table_plane.MIN_AREA_POINTS
    try:  # the whole view's plane, as before the fit under the area
        table_plane.MIN_AREA_POINTS = 10**12
        T_view, _ = fit_table_plane(depth, CAMERA)
    finally:
        table_plane.MIN_AREA_POINTS = kept
    assert _tilt_mrad(T_view, board_normal) > 0.5, _tilt_mrad(T_view, board_normal)


def test_a_noisy_camera_on_one_plane_keeps_the_whole_views_plane():
    """A level table seen with 3 mm of white noise: the plane under the area spreads its
    heights no less, so the frame is the whole view's (the same transform)."""
    rng = np.random.default_rng(0)
    flat = [(lambda x, y: np.zeros_like(x), lambda x, y: np.ones_like(x, bool))]
    depth = _depth(flat) + rng.normal(0.0, 0.003, (480, 640))
    T, _ = fit_table_plane(depth, CAMERA)
    kept = table_plane.MIN_AREA_POINTS
    try:
        table_plane.MIN_AREA_POINTS = 10**12
        T_view, _ = fit_table_plane(depth, CAMERA)
    finally:
        table_plane.MIN_AREA_POINTS = kept
    np.testing.assert_array_equal(T, T_view)
