"""The table seen from above as points: its height, the camera's noise, a cleaned image.

When the image is lost in places or noisy (a real camera), its holes are filled and its
median taken.

A clean render (no lost pixel, no noise) is used as it is, so that the ideal world's results
do not change. World frame, m.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from comgrasp_pin.camera import PinholeCamera
from comgrasp_pin.errors import ObjectNotFoundError
from comgrasp_pin.perception._points import (
    denoise,
    drop_flying,
    fill_holes,
    noise_level,
    points_in,
)

COLOUR_DE = 20.0  # a pixel this far from the table's colour (CIELAB, OpenCV's 8-bit scale:
# 2.55 per unit of L*) belongs to an object; the table's own spread in a render is about 2
SHADOW_CHROMA = 6.0  # ... unless its chroma (a*, b*) is this close to the table's and it
# is darker: the table in a shadow
CLEAN_NOISE = 3e-4  # table heights noisier than this (m, robust std) are filtered first
FLYING_MIN, FLYING_SIGMAS = 0.005, 4.0  # a pixel this far (m, noise stds) from all its
# neighbours flies


@dataclass(frozen=True)
class TableView:
    """A top-down depth image as points.

    Attributes:
        points: (H, W, 3) every pixel in the world (NaN where no depth): the image's median
            when ``cleaned``.
        table_z: height of the table plane (m), the median of the pick area.
        noise: the camera's depth noise on the table (m, robust std, before the median).
        points_noise: the same of ``points`` (after the median, when ``cleaned``).
        cleaned: whether flying pixels were dropped, holes filled and the median taken.
    """

    points: np.ndarray
    table_z: float
    noise: float
    points_noise: float
    cleaned: bool


def view_table(
    depth: np.ndarray,
    camera: PinholeCamera,
    T_world_cam: np.ndarray,
    pick_area: tuple[float, float, float, float],
    margin: float,
) -> TableView:
    """The table of ``pick_area`` in ``depth``: see ``TableView``.

    ``pick_area``: (x_min, x_max, y_min, y_max) less ``margin`` (m); ``depth``: a checked
    (H, W) z-depth (m).

    Raises ObjectNotFoundError when fewer than 100 pixels see the pick area.
    """
    points = points_in(T_world_cam, depth, camera)
    table_z, noise = _table(points, pick_area, margin)
    if noise <= CLEAN_NOISE and np.all(np.isfinite(depth) & (depth > 0)):
        return TableView(points, table_z, noise, noise, False)
    # Holes, dropouts, flying pixels or noise: drop the flying pixels, fill the holes, take
    # the median.
    tolerance = max(FLYING_MIN, FLYING_SIGMAS * noise)
    grounded = drop_flying(depth, tolerance)
    points = points_in(T_world_cam, denoise(fill_holes(grounded)), camera)
    table_z, points_noise = _table(points, pick_area, margin)
    return TableView(points, table_z, noise, points_noise, True)


def in_area(points: np.ndarray, pick_area: tuple[float, float, float, float], margin: float):
    """(H, W) bool: points within ``pick_area`` less ``margin`` (m; negative: more)."""
    x0, x1, y0, y1 = pick_area
    x, y = points[..., 0], points[..., 1]
    return (x > x0 + margin) & (x < x1 - margin) & (y > y0 + margin) & (y < y1 - margin)


def _table(points: np.ndarray, pick_area, margin: float) -> tuple[float, float]:
    """(table height, robust std of the heights about it) over the pick area (m)."""
    z = points[..., 2]
    inside = in_area(points, pick_area, margin) & np.isfinite(z)
    if inside.sum() < 100:
        raise ObjectNotFoundError("the pick area is not in view of the camera")
    table_z = float(np.median(z[inside]))  # the rod covers a small part of it
    return table_z, noise_level(z[inside] - table_z)


def differs_in_colour(rgb: np.ndarray, area: np.ndarray) -> np.ndarray:
    """(H, W) bool: pixels whose colour is not the table's, nor the table's in a shadow.

    ``rgb``: (H, W, 3) uint8 colour image registered to the depth image; ``area``: (H, W)
    bool, the pixels that see the table's pick area (its colour is their median: the rod
    covers a small part of them). A colour camera has no stereo noise, holes or flying
    pixels: where the depth cannot tell a low rod's ends from the table, the colour can.
    """
    lab = cv2.cvtColor(np.ascontiguousarray(rgb, dtype=np.uint8), cv2.COLOR_RGB2LAB)
    # In halves of OpenCV's 8-bit units every difference from the table's median colour is
    # an integer (a median of integers is one or a half), its squares' sum exact: a sum
    # compared with the squared threshold is the Euclidean distance compared with the
    # threshold, to the bit (sqrt is correctly rounded and monotonic).
    table2 = np.rint(2.0 * np.median(lab[area], axis=0)).astype(np.int32)
    diff2 = 2 * lab.astype(np.int32) - table2
    diff2 *= diff2
    chroma2 = diff2[..., 1] + diff2[..., 2]
    distance2 = chroma2 + diff2[..., 0]
    shadow = (chroma2 < 4 * SHADOW_CHROMA**2) & (2 * lab[..., 0].astype(np.int32) < table2[0])
    return (distance2 > 4 * COLOUR_DE**2) & ~shadow
