"""The table seen from above as points: its height, its noise, a cleaned image, its edge.

A rod at the table's edge may lie over it on its plane, dip below it, or run out of the
image (``over_the_edge``, ``check_no_dip``, ``cut_end_of``).

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
from comgrasp_pin.errors import ObjectCutByBorderError, ObjectNotFoundError
from comgrasp_pin.perception._points import (
    border_pixels,
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
# A rod may reach over the table's edge: the pixels beyond the pick area that stand on the
# table's plane (not the floor below) and join the rod are the rod. One that dips below the
# plane beyond the edge (tilted down over it) is refused when at least DIP_PIXELS on its
# axis within DIP_REACH beyond an end lie between DIP_DEPTH and the threshold below the plane.
DIP_DEPTH = 0.3  # m below the table's plane: lower than this is the floor
DIP_REACH = 0.2  # m (a rod dipping at a few degrees is near the plane for centimetres first)
DIP_PIXELS = 10
DIP_END_GAP = 0.03  # m: a rod that dips over the edge reaches it (its end this near it)
DIP_BAND = 0.06  # m beyond the table's edge: a dipping rod goes down from the edge (the drop
# box's walls and their flying pixels stand 8 cm beyond it)
CUT_END_BAND = 0.03  # a rod meeting the image's border only this near one end (m) runs out
# of view there: the part seen is measured (``ObjectCutByBorderError.seen``)
_KERNEL3 = np.ones((3, 3), np.uint8)


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


def check_no_dip(view: TableView, pick_area, centroid, direction, ends, p, min_height) -> None:
    """ObjectCutByBorderError when the rod dips below the table's plane over its edge.

    That is: beyond the table's edge by less than DIP_BAND, on the rod's axis
    (``direction`` (2,) through ``centroid`` (2,), within its points' ``p`` (N, 3) spread
    across it and 1 cm) and within DIP_REACH beyond one of its ``ends`` (along the axis,
    m), DIP_PIXELS or more points lie between DIP_DEPTH and the height threshold below the
    plane (after an opening: a real camera's flying pixels lie in lines a pixel wide, a rod
    is a surface); ``min_height`` (m): the top view's height threshold. Only beyond an end
    that reaches the area's edge (within DIP_END_GAP): table between an end and the edge
    holds the rod up (what lies below it there is the table's edge seen by a noisy camera).
    """
    z = view.points[..., 2]
    dips = ~in_area(view.points, pick_area, 0.0) & in_area(view.points, pick_area, -DIP_BAND)
    dips &= np.isfinite(z)
    dips &= (z < view.table_z - min_height) & (z > view.table_z - DIP_DEPTH)
    dips = cv2.morphologyEx(dips.astype(np.uint8), cv2.MORPH_OPEN, _KERNEL3) > 0
    if not dips.any():
        return
    normal = np.array([-direction[1], direction[0]])
    half_width = np.percentile(np.abs((p[:, :2] - centroid) @ normal), 95) + 0.01
    rel = view.points[dips][:, :2] - centroid
    along, across = rel @ direction, np.abs(rel @ normal)
    lo, hi = ends
    # an end DIP_END_GAP or more inside the area has table beyond it: nothing dips from it
    reaches = [not in_area(centroid + (end + gap) * direction, pick_area, 0.0)
               for end, gap in ((lo, -DIP_END_GAP), (hi, DIP_END_GAP))]  # fmt: skip
    beyond = (reaches[0] & (along < lo) & (along > lo - DIP_REACH)) | (
        reaches[1] & (along > hi) & (along < hi + DIP_REACH)
    )
    count = int(np.count_nonzero(beyond & (across < half_width)))
    if count >= DIP_PIXELS:
        raise ObjectCutByBorderError(
            f"the object hangs down over the edge of the pick area ({count} px on its axis "
            f"beyond its end, {1e3 * min_height:.0f} to {1e3 * DIP_DEPTH:.0f} mm below the "
            "table): its part below the table cannot be measured; lay it on the table"
        )


def overhang(ends_world: np.ndarray, pick_area) -> float:
    """How far (m) the rod's axis ends ((2, 3) world) reach beyond ``pick_area``."""
    x0, x1, y0, y1 = pick_area
    x, y = ends_world[:, 0], ends_world[:, 1]
    beyond = np.concatenate([x0 - x, x - x1, y0 - y, y - y1])
    return float(max(0.0, beyond.max()))


def cut_end_of(view: TableView, mask, centroid, direction, ends, yaw) -> int:
    """Which end of the rod runs out of the image: +1 (-1) for its end towards +yaw (-yaw).

    That is: the rod's ``mask`` meets the image's border only within CUT_END_BAND of that
    end along its axis (``direction`` (2,) through ``centroid`` (2,), ``ends`` along it,
    m); ObjectCutByBorderError otherwise (both ends, or its side, run out of view: too
    little is known of it).
    """
    along = (view.points[border_pixels(mask)][:, :2] - centroid) @ direction
    lo, hi = ends
    if np.all(along > hi - CUT_END_BAND):
        side = 1
    elif np.all(along < lo + CUT_END_BAND):
        side = -1
    else:
        raise ObjectCutByBorderError("the object reaches the border of the top-down image")
    return side if direction @ np.array([np.cos(yaw), np.sin(yaw)]) > 0 else -side


def over_the_edge(view: TableView, mask, inside, standing, in_depth, min_height):
    """(the rod's ``mask`` with its parts beyond the pick area, what stands with them).

    Beyond the pick area (its EDGE_BAND and what lies over the table's edge) a pixel is the
    rod's when it joins the rod's blob and stands on the table's plane: standing in depth,
    or (a cleaned image's colour) differing from the table and no lower than the plane's
    noise; the floor lies far below. The rod may reach the image's border there
    (``cut_end_of``).
    """
    z = view.points[..., 2]
    on_plane = np.isfinite(z) & (z > view.table_z - min_height)
    beyond = ~inside & on_plane & (in_depth | standing)
    if view.cleaned:
        beyond = cv2.morphologyEx(beyond.astype(np.uint8), cv2.MORPH_OPEN, _KERNEL3) > 0
    region = (mask | beyond).astype(np.uint8)
    _, labels = cv2.connectedComponents(region, connectivity=8)
    own = np.unique(labels[mask])
    rod = mask | (np.isin(labels, own[own > 0]) & beyond)
    return rod, (inside & standing) | rod
