"""The table's plane fitted in a depth image: a frame for a camera whose pose is not known.

The top view measures a rod in a frame whose z is the table's normal (``T_world_cam``).
A user who has not calibrated the camera's pose may take the table itself: the plane
that most of the image sees (RANSAC, then a least-squares fit to its inliers), with the
frame ``table``: z along its normal towards the camera, origin below the camera's centre,
x the camera's x laid on the plane. Lengths, widths, heights and yaw differences are then
metric; positions are in that frame.
"""

from __future__ import annotations

import numpy as np

from comgrasp_pin.camera import PinholeCamera
from comgrasp_pin.errors import ObjectNotFoundError
from comgrasp_pin.perception._points import points_in

INLIER_DISTANCE = 0.005  # a point this close to the plane is on it (m)
MIN_SHARE = 0.3  # the table must be at least this share of the valid pixels
SAMPLES = 300  # RANSAC's draws of three points
MAX_POINTS = 20_000  # points the plane is fitted to (an even subsample of the image)


def fit_table_plane(
    depth: np.ndarray, camera: PinholeCamera, seed: int = 0
) -> tuple[np.ndarray, tuple[float, float, float, float]]:
    """(T_table_cam (4, 4), the plane's inliers' extent (x_min, x_max, y_min, y_max)) (m).

    ``depth``: (H, W) float z-depth (m), 0 or inf where none. The extent, in the table
    frame, is the pick area: the part of the table in view.

    Raises:
        ObjectNotFoundError: no plane holds MIN_SHARE of the valid pixels.
    """
    points = points_in(np.eye(4), depth, camera).reshape(-1, 3)
    points = points[np.isfinite(points[:, 2])]
    if len(points) < 100:
        raise ObjectNotFoundError("the depth image has too few valid pixels to find a table")
    step = max(1, len(points) // MAX_POINTS)
    sample = points[::step]
    rng = np.random.default_rng(seed)
    best = None
    for a, b, c in rng.integers(0, len(sample), size=(SAMPLES, 3)):
        normal = np.cross(sample[b] - sample[a], sample[c] - sample[a])
        if np.linalg.norm(normal) < 1e-12:
            continue
        normal /= np.linalg.norm(normal)
        count = np.count_nonzero(np.abs((sample - sample[a]) @ normal) < INLIER_DISTANCE)
        if best is None or count > best[0]:
            best = (count, normal, sample[a])
    if best is None or best[0] < MIN_SHARE * len(sample):
        raise ObjectNotFoundError(
            f"no plane holds {100 * MIN_SHARE:.0f} % of the depth image's points: the table is "
            "not in view; give the camera's pose instead"
        )
    _, normal, origin = best
    inliers = points[np.abs((points - origin) @ normal) < INLIER_DISTANCE]
    centre = inliers.mean(axis=0)
    normal = np.linalg.svd(inliers - centre, full_matrices=False)[2][2]  # least squares
    if normal @ -centre < 0:  # towards the camera (at the origin)
        normal = -normal
    foot = -(normal @ -centre) * normal  # the camera's centre dropped onto the plane
    x = np.array([1.0, 0.0, 0.0]) - normal[0] * normal
    x /= np.linalg.norm(x)
    T_cam_table = np.eye(4)
    T_cam_table[:3, :3] = np.column_stack([x, np.cross(normal, x), normal])
    T_cam_table[:3, 3] = foot
    T_table_cam = np.linalg.inv(T_cam_table)
    on_table = inliers @ T_table_cam[:3, :3].T + T_table_cam[:3, 3]
    lo, hi = on_table[:, :2].min(axis=0), on_table[:, :2].max(axis=0)
    return T_table_cam, (float(lo[0]), float(hi[0]), float(lo[1]), float(hi[1]))
