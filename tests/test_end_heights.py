"""A top view's object stands up to its ends, or is refused (``perception.top_view.end_heights``).

The depth images are built here from a pinhole camera 0.7 m above a table and an object
whose height is written down as a function of where it lies: the truth is the
construction. A rod whose last centimetres slope into the table (a tool's handle lying on
its head, a tapering handle a depth camera smooths) would be measured short where its height
crosses the threshold; it is refused. Rods with square or round ends are measured whole.
"""

from __future__ import annotations

import numpy as np
import pytest

from comgrasp_pin.camera import PinholeCamera
from comgrasp_pin.errors import UntrustedImageError
from comgrasp_pin.perception import detect_rod_top_down

CAMERA = PinholeCamera.from_fovy(640, 480, 45.0)
HEIGHT = 0.7  # m, the camera above the table
T_WORLD_CAM = np.array([[1.0, 0, 0, 0], [0, -1.0, 0, 0], [0, 0, -1.0, HEIGHT], [0, 0, 0, 1]])
AREA = (-0.25, 0.25, -0.18, 0.18)
LENGTH, WIDTH, TOP = 0.24, 0.02, 0.015  # m: a rod along x, centred at the origin


def _depth(top_of) -> np.ndarray:
    """The z-depth of a table at z = 0 with an object whose top is ``top_of(x, y)`` (m; 0
    off it, at most TOP): where each ray first meets that surface (fixed-point iterations on
    its height, from the top down)."""
    v, u = np.mgrid[0 : CAMERA.height, 0 : CAMERA.width].astype(float)
    rx, ry = (u - CAMERA.cx) / CAMERA.fx, -(v - CAMERA.cy) / CAMERA.fy  # camera y = -world y
    h = np.full_like(rx, TOP)
    for _ in range(20):
        h = top_of(rx * (HEIGHT - h), ry * (HEIGHT - h))
    return HEIGHT - h


def _rod(end_top):
    """A rod of TOP's height whose top along x is ``end_top(distance from its +x end)``."""

    def top_of(x, y):
        on = (np.abs(x) <= LENGTH / 2) & (np.abs(y) <= WIDTH / 2)
        return np.where(on, end_top(LENGTH / 2 - x), 0.0)

    return top_of


def test_square_and_round_ends_are_measured_whole():
    square = _rod(lambda d: np.full_like(d, TOP))
    r = TOP / 2  # a capsule's end: a half disc of the rod's radius, seen from above
    round_end = _rod(lambda d: np.where(d < r, r + np.sqrt(np.clip(r**2 - (r - d) ** 2, 0, None)),
                                        TOP))  # fmt: skip
    for top_of in (square, round_end):
        det = detect_rod_top_down(None, _depth(top_of), CAMERA, T_WORLD_CAM, AREA)
        assert abs(det.length - LENGTH) < 0.004, det.length
        assert abs(det.grasp.x) < 0.002


@pytest.mark.parametrize("slope_cm", [4.0, 8.0])
def test_a_rod_whose_end_slopes_into_the_table_is_refused(slope_cm):
    """The last ``slope_cm`` fall linearly from TOP to 0: the 3 mm threshold is crossed
    slope_cm / 5 short of the end; measured, the rod would be that much short."""
    s = slope_cm / 100
    sloped = _rod(lambda d: np.where(d < s, TOP * d / s, TOP))
    with pytest.raises(UntrustedImageError, match=r"slopes into the table at its \+yaw end"):
        detect_rod_top_down(None, _depth(sloped), CAMERA, T_WORLD_CAM, AREA)
