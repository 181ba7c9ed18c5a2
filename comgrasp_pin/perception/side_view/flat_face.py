"""A flat bar held in the jaws, seen edge-on by the side camera: its axis from its face.

The jaws close on a flat bar's two narrow sides, and the side camera, looking along the jaw
axis, sees the near one: a strip (the bar's thickness high) in the plane of the near pad,
parallel to the jaws' plane, and perhaps the bar's top or bottom face obliquely. No cylinder
fits that (``rod_axis.refine_axis`` misfits it by 15-20 % of the half-width), and the slice
centres of all the points are pulled towards the oblique face (2-4 mm). The strip's mid-line
is the bar's axis in the jaws' plane: the face's points are those near its plane (a robust
level of their ee-y), and each is put where its camera ray meets that plane, so that the
depth noise (1-1.5 mm on the wrist camera) moves them no more (the pixel's position does
not carry it). Ee frame, m.
"""

from __future__ import annotations

import numpy as np

from comgrasp_pin.perception._points import median, slice_medians, slice_percentiles
from comgrasp_pin.perception.side_view.rod_axis import slope_std

FLAT_WIDTH_SHARE = 0.6  # a handle seen less wide than this share of the jaws' gap is flat
FACE_BAND = 0.0015  # the face's points lie within this of its plane (m) ...
FACE_BAND_SIGMAS = 2.5  # ... or this many depth-noise stds
MIN_FACE_SHARE = 0.2  # at least this share of the handle's points are on the face
WIDTH_PERCENTILES = (5.0, 95.0)  # the handle's width across its axis, robust to strays
EDGE_PERCENTILES = (2.0, 98.0)  # a slice's edges: nearly its extremes, robust to a stray
SLICE = 0.01  # slices along the strip (m)
MIN_SLICE_POINTS = 10
WHOLE_WIDTH, WHOLE_COUNT = 0.8, 0.3  # a slice narrower or sparser than this share of the
# median slice's is partial


def looks_flat(xz_across: np.ndarray, radius: float | None) -> bool:
    """Whether a handle is a flat bar seen edge-on.

    Its points' spread across the slice line in the jaws' plane (``xz_across`` (N,), m) is
    well below the jaws' gap 2 ``radius`` (m): a round handle is as wide as the gap, obj3's
    1 cm edge in a 3 cm gap a third.
    """
    if not radius or len(xz_across) < 2:
        return False
    lo, hi = np.percentile(xz_across, WIDTH_PERCENTILES)
    return bool(hi - lo < FLAT_WIDTH_SHARE * 2.0 * radius)


def face_points(
    points: np.ndarray, camera_ee: np.ndarray, noise: float
) -> tuple[np.ndarray, float] | None:
    """The visible face's points put on its plane: ((M, 2) x-z, the plane's ee-y), or None.

    ``points`` (N, 3): the handle's; ``camera_ee`` (3,) the camera's optical centre; ``noise``
    (m) the image's depth noise (0 for a clean one). The face is the level of ee-y that most
    points share (the median, then the median of the points within the band of it); each
    face point moves along its ray from the camera onto y = that level. None when fewer
    than MIN_FACE_SHARE of the points lie on it (no face).
    """
    y = points[:, 1]
    band = max(FACE_BAND, FACE_BAND_SIGMAS * noise)
    level = float(median(y))
    for _ in range(2):
        on = np.abs(y - level) <= band
        if not on.any():
            return None
        level = float(median(y[on]))
    on = np.abs(y - level) <= band
    if on.sum() < MIN_FACE_SHARE * len(points):
        return None
    return on_plane(points[on], camera_ee, level), level


def on_plane(points: np.ndarray, camera_ee: np.ndarray, level: float) -> np.ndarray:
    """(M, 2) x-z where the camera's rays through ``points`` (N, 3) meet the plane y = level.

    ``level``: ee-y (m). The pixels' positions without their depth (rays along the plane
    are left out): the depth noise of a point on that plane moves it along its ray only.
    """
    rays = points - camera_ee
    rays = rays[np.abs(rays[:, 1]) > 1e-3]
    along_ray = (level - camera_ee[1]) / rays[:, 1]  # the ray's parameter at y = level
    return (camera_ee + rays * along_ray[:, None])[:, [0, 2]]


def strip_line(
    xz: np.ndarray, direction: np.ndarray
) -> tuple[np.ndarray, np.ndarray, float] | None:
    """The mid-line of a strip of points ``xz`` (M, 2) on the face's plane, in the x-z plane.

    Cut in SLICE slices along ``direction`` (2,); each slice's mid-point lies half-way
    between its two edges (EDGE_PERCENTILES across the line: the face's points, on their
    plane, carry no depth noise, and the oblique face's strip along one edge, unlike a
    median, does not pull it); a line through the mid-points, those farther than 3 median
    residuals (at least 0.5 mm) left out, twice. Returns (unit direction (2,), positive x;
    its point nearest the TCP (2,); the standard error of its angle (rad)), or None with
    fewer than 3 slices.
    """
    point = np.zeros(2)
    angle_std = np.inf
    for _ in range(2):
        normal = np.array([-direction[1], direction[0]])
        along, across = xz @ direction, xz @ normal
        bins = np.floor(along / SLICE).astype(int)
        counts, ends = slice_percentiles(bins, across, EDGE_PERCENTILES, MIN_SLICE_POINTS)
        lo, hi = ends.T
        mid_along = slice_medians(bins, (along,), MIN_SLICE_POINTS)[1][:, 0]
        whole = np.column_stack([mid_along, 0.5 * (lo + hi), hi - lo, counts])
        if len(whole) < 3:  # (no median of too few slices: an empty one warns)
            return None
        # A slice that sees the strip only in part (cut by an occluder, the image's border
        # or a hole: narrower, or far fewer points) has its mid-point off the mid-line.
        whole = whole[(whole[:, 2] >= WHOLE_WIDTH * np.median(whole[:, 2]))
                      & (whole[:, 3] >= WHOLE_COUNT * np.median(whole[:, 3]))]  # fmt: skip
        if len(whole) < 3:
            return None
        c = whole[:, :2]
        keep = np.ones(len(c), dtype=bool)
        for _ in range(3):
            slope, intercept = np.polyfit(c[keep, 0], c[keep, 1], 1)
            residual = np.abs(c[:, 1] - (slope * c[:, 0] + intercept))
            keep = residual <= max(3.0 * float(np.median(residual[keep])), 5e-4)
        point = intercept * normal
        direction = (direction + slope * normal) / np.hypot(1.0, slope)
        angle_std = slope_std(c[keep], slope, intercept) / (1.0 + slope * slope)
    if direction[0] < 0:
        direction = -direction
    return direction, point - (point @ direction) * direction, float(angle_std)
