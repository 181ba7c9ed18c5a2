"""What may be the held rod in a side-camera frame: the points between the jaws (ee frame, m).

A pixel is a candidate when its point lies in the slab between the jaws (|y_ee| small),
within reach of the TCP, above the table when it is near, and outside the robot's own
volume (gripper and arm). Only the pixels whose depth can put them in the slab are lifted to
3-D (``slab_pixels``: a bound from each pixel's ray, with a margin far above its rounding),
and each of them exactly as ``points_in`` lifts it (``points_at``): the same candidates and
the same points to the bit, with about a sixth of the image lifted
(tests/test_fast_paths.py).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

from comgrasp_pin.camera import PinholeCamera
from comgrasp_pin.perception._points import points_at

SLAB_HALF_WIDTH = 0.08  # |y_ee| of the region the held object may occupy (m)
REACH = 0.40  # distance from the TCP beyond which nothing is the held object (m)
TABLE_MARGIN = 0.003  # points less than this above the table are the table (m)
SLAB_SLACK = 1e-6  # the slab's bound is widened by this (m) per metre of depth, and once
# The gripper's own volume in the ee frame (from the URDF): fingers and pads (with margin),
# palm, and the wrist above it.
_FINGERS = (0.016, 0.06, -0.085, 0.018)  # |x| <, |y| <, z from, z to
_PALM = (0.035, 0.075, -0.14, -0.075)
_WRIST_RADIUS, _WRIST_BELOW_Z = 0.05, -0.13

Capsules = Sequence[tuple[np.ndarray, np.ndarray, float]]


def slab_pixels(T_ee_cam: np.ndarray, depth: np.ndarray, camera: PinholeCamera) -> np.ndarray:
    """Flat indices of the valid pixels whose point may lie within SLAB_HALF_WIDTH of y_ee = 0.

    Valid: finite and > 0. Every pixel whose exact point lies in the slab, and a few more.
    The point's y_ee is depth times the ray's y_ee per metre of depth, plus the camera's;
    computed so, it differs from the exact product by rounding (1e-16 m at these depths),
    far inside the SLAB_SLACK margin.
    """
    R, t = T_ee_cam[:3, :3], T_ee_cam[:3, 3]
    x_per_z = (np.arange(camera.width) - camera.cx) / camera.fx  # (W,) ray x / z, camera frame
    y_per_z = (np.arange(camera.height) - camera.cy) / camera.fy  # (H,)
    ray_y = (R[1, 1] * y_per_z + R[1, 2])[:, None] + R[1, 0] * x_per_z  # (H, W) y_ee per m
    with np.errstate(invalid="ignore"):  # inf depth times a zero ray
        y_ee = depth * ray_y
        y_ee += t[1]
        np.abs(y_ee, out=y_ee)
        y_ee -= SLAB_SLACK * depth
        near = y_ee < SLAB_HALF_WIDTH + SLAB_SLACK
    near &= np.isfinite(depth)
    near &= depth > 0
    return np.flatnonzero(near)


def gripper_volume(p: np.ndarray) -> np.ndarray:
    """(...) bool: the points ``p`` (..., 3) inside the gripper's own volume."""
    x, y, z = p[..., 0], p[..., 1], p[..., 2]
    inside = np.zeros(x.shape, dtype=bool)
    for ax, ay, z0, z1 in (_FINGERS, _PALM):
        inside |= (np.abs(x) < ax) & (np.abs(y) < ay) & (z > z0) & (z < z1)
    inside |= (np.hypot(x, y) < _WRIST_RADIUS) & (z < _WRIST_BELOW_Z)
    return inside


def in_capsule(p: np.ndarray, p0: np.ndarray, p1: np.ndarray, radius: float) -> np.ndarray:
    """Bool mask of the points ``p`` (..., 3) within ``radius`` of the segment p0-p1.

    Only the points inside the capsule's box (widened by SLAB_SLACK) are measured; those
    outside it lie farther than ``radius`` from every point of the segment.
    """
    rows = p.reshape(-1, 3)
    lo, hi = np.minimum(p0, p1) - radius - SLAB_SLACK, np.maximum(p0, p1) + radius + SLAB_SLACK
    in_box = np.arange(len(rows))
    for axis in range(3):  # one coordinate at a time, each on the rows still in the box
        c = rows[in_box, axis] if axis else rows[:, 0]
        in_box = in_box[(c > lo[axis]) & (c < hi[axis])]
    inside = np.zeros(len(rows), dtype=bool)
    if len(in_box) == 1 and len(rows) > 1:  # one row alone would take another BLAS path
        inside[in_box] = _capsule_distance(rows[np.r_[in_box, in_box]], p0, p1)[:1] < radius
    elif len(in_box):
        inside[in_box] = _capsule_distance(rows[in_box], p0, p1) < radius
    return inside.reshape(p.shape[:-1])


def _capsule_distance(p: np.ndarray, p0: np.ndarray, p1: np.ndarray) -> np.ndarray:
    """(N,) distance of the points ``p`` (N, 3) from the segment p0-p1 (inf for NaN)."""
    d = p1 - p0
    t = np.clip(np.nan_to_num((p - p0) @ d / max(d @ d, 1e-12), nan=0.0), 0.0, 1.0)
    dist = np.linalg.norm(p - p0 - t[..., None] * d, axis=-1)
    return np.nan_to_num(dist, nan=np.inf)


def robot_volume(capsules: Capsules) -> Callable[[np.ndarray], np.ndarray]:
    """The test for the robot's own volume among points (N, 3): (N,) bool.

    The gripper, and the arm's ``capsules``, each (p0 (3,), p1 (3,), radius) in the ee frame.
    """

    def excluded(pts: np.ndarray) -> np.ndarray:
        inside = gripper_volume(pts)
        for p0, p1, radius in capsules:
            inside |= in_capsule(pts, np.asarray(p0, float), np.asarray(p1, float), radius)
        return inside

    return excluded


def held_candidates(
    depth: np.ndarray,
    camera: PinholeCamera,
    T_ee_cam: np.ndarray,
    T_world_ee: np.ndarray | None,
    table_z: float | None,
    excluded: Callable[[np.ndarray], np.ndarray],
) -> tuple[np.ndarray, np.ndarray]:
    """(points (H, W, 3), candidate (H, W) bool): the pixels that may be the held rod.

    ``points`` holds the ee-frame point of every pixel lifted (``slab_pixels``), NaN at the
    others; every candidate is lifted. With ``T_world_ee`` and ``table_z``, points within
    TABLE_MARGIN of the table plane (world z) are not candidates; nor are those
    ``excluded`` (the robot's own volume, tested only on what is left).
    """
    h, w = depth.shape
    pixels = slab_pixels(T_ee_cam, depth, camera)
    q = points_at(T_ee_cam, depth, camera, pixels)
    keep = np.isfinite(q[:, 0]) & (np.abs(q[:, 1]) < SLAB_HALF_WIDTH)
    keep &= np.linalg.norm(q, axis=-1) < REACH
    if T_world_ee is not None and table_z is not None and len(q):
        z_world = _rows_dot(q, T_world_ee[2, :3]) + T_world_ee[2, 3]
        keep &= z_world > table_z + TABLE_MARGIN
    inside = np.flatnonzero(keep)
    inside = inside[~excluded(q[inside])] if len(inside) else inside
    points = np.full((h * w, 3), np.nan)
    points[pixels] = q
    candidate = np.zeros(h * w, dtype=bool)
    candidate[pixels[inside]] = True
    return points.reshape(h, w, 3), candidate.reshape(h, w)


def _rows_dot(q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """``q @ v`` for (N, 3) rows, each row's value as in any larger product.

    One row alone would take another BLAS path.
    """
    if len(q) == 1:
        return (np.vstack([q, q]) @ v)[:1]
    return q @ v
