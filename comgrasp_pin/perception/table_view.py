"""The table seen from above as points: its height, the camera's noise, a cleaned image.

When the image is lost in places or noisy (a real camera), its holes are filled and its
median taken.

A clean render (no lost pixel, no noise) is used as it is, so that the ideal world's results
do not change. World frame, m.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from comgrasp_pin.camera import PinholeCamera
from comgrasp_pin.errors import ObjectNotFoundError
from comgrasp_pin.perception._points import (
    denoise,
    fill_holes,
    noise_level,
    points_in,
    trusted_pixels,
)

CLEAN_NOISE = 3e-4  # table heights noisier than this (m, robust std) are filtered first
TRUST_SIGMAS, TRUST_MARGIN = 3.0, 0.002  # a pixel this far off the median is not measured


@dataclass(frozen=True)
class TableView:
    """A top-down depth image as points.

    Attributes:
        points: (H, W, 3) every pixel in the world (NaN where no depth): the image's median
            when ``cleaned`` (for segmenting and heights).
        geometry: (H, W, 3) the points to measure the rod on: the camera's own pixels that
            agree with the median (NaN for lost and flying pixels) when ``cleaned``, else
            ``points``.
        table_z: height of the table plane (m), the median of the pick area.
        noise: the camera's depth noise on the table (m, robust std, before the median).
        points_noise: the same of ``points`` (after the median, when ``cleaned``).
        cleaned: whether holes were filled and the median taken.
    """

    points: np.ndarray
    geometry: np.ndarray
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
        return TableView(points, points, table_z, noise, noise, False)
    # Holes, dropouts or noise: segment on the median of the filled image (it rounds
    # corners), measure on the camera's pixels that agree with it (a flying pixel's wrong
    # depth moves its point along its oblique ray).
    smooth = denoise(fill_holes(depth))
    trusted = trusted_pixels(depth, smooth, TRUST_SIGMAS * noise + TRUST_MARGIN)
    geometry = np.where(trusted[..., None], points, np.nan)
    points = points_in(T_world_cam, smooth, camera)
    table_z, points_noise = _table(points, pick_area, margin)
    return TableView(points, geometry, table_z, noise, points_noise, True)


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
