"""The same frame with its pick area moved by 3 cm, where no object enters or leaves (issue 44).

An area is moved by +-3 cm in x and in y; it is kept where every object of the scene (rods
and clutter, as built) lies on the same side of each of its four edges as of the default
area's (inside, outside or across it, its edge band included): the same objects in the
area, so the top view must give the same answer (both refused, or both measured within 1 cm
of length and 3 deg of yaw). The table's own edge may come into a moved area: it is no
object. World frame, m.
"""

from __future__ import annotations

import numpy as np

from comgrasp_pin.perception.top_view.standing import EDGE_BAND
from comgrasp_pin.perception.top_view.top_down import PICK_AREA

from .scenes import UnseenScene

MOVES = ((0.03, 0.0), (-0.03, 0.0), (0.0, 0.03), (0.0, -0.03))


def _corners(x: float, y: float, yaw: float, half_x: float, half_y: float) -> np.ndarray:
    """(4, 2) corners of a rectangle of half sizes ``half_x`` (along ``yaw``), ``half_y``."""
    u, n = np.array([np.cos(yaw), np.sin(yaw)]), np.array([-np.sin(yaw), np.cos(yaw)])
    return np.array([[x, y] + a * half_x * u + b * half_y * n
                     for a in (-1, 1) for b in (-1, 1)])  # fmt: skip


def footprints(scene: UnseenScene) -> list[np.ndarray]:
    """Each object's outline on the table as (k, 2) points (m, world)."""
    out = [_corners(r.x, r.y, r.yaw, r.length / 2, r.radius) for r in scene.rods]
    for item in scene.clutter:
        if item.kind == "box":
            (x, y), (hx, hy) = item.points[0], item.size[:2]
            out.append(_corners(x, y, item.yaw, hx, hy))
        else:  # a cable: its points grown by its radius
            pts, r = np.asarray(item.points, float), item.size[0]
            out.append(np.vstack([pts + d for d in ((r, r), (r, -r), (-r, r), (-r, -r))]))
    return out


def _sides(points: np.ndarray, area: tuple) -> tuple:
    """Per edge of ``area`` (less EDGE_BAND): whether ``points`` lie inside, outside, or across."""
    x0, x1, y0, y1 = area
    inside = (points[:, 0] > x0 + EDGE_BAND, points[:, 0] < x1 - EDGE_BAND,
              points[:, 1] > y0 + EDGE_BAND, points[:, 1] < y1 - EDGE_BAND)  # fmt: skip
    return tuple("in" if s.all() else "out" if not s.any() else "across" for s in inside)


def moved_areas(scene: UnseenScene, area: tuple = PICK_AREA) -> list[tuple]:
    """The areas ``area`` moved by MOVES that hold the same objects as ``area``."""
    shapes = footprints(scene)
    kept = [_sides(p, area) for p in shapes]
    x0, x1, y0, y1 = area
    out = []
    for dx, dy in MOVES:
        moved = (x0 + dx, x1 + dx, y0 + dy, y1 + dy)
        if [_sides(p, moved) for p in shapes] == kept:
            out.append(moved)
    return out
