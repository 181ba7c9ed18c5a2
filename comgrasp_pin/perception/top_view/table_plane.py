"""The table's plane fitted in a depth image: a frame for a camera whose pose is not known.

The top view measures a rod in a frame whose z is the table's normal (``T_world_cam``).
A user who has not calibrated the camera's pose may take the table itself: the plane
that most of the image sees, or a parallel one nearer the camera that holds MIN_SHARE of it
too (RANSAC, then a least-squares fit to its inliers; a camera high above a table may see
more of the floor), fitted again to the bare table in the pick area where that is another
plane (its heights spread less about it: a board on a table), with the
frame ``table``: z along its normal towards the camera, origin below the camera's centre,
x the camera's x laid on the plane. Lengths, widths, heights and yaw differences are then
metric; positions are in that frame.

The pick area it gives is the largest rectangle of the table that the camera sees whole
(``clear_rectangle``): the table's pixels, with what lies on them, gridded on the plane. A
robot's fingers reaching into the view, the table's edge and the floor beyond it lie
outside that rectangle, while objects lying on the table lie inside it.
"""

from __future__ import annotations

import cv2
import numpy as np

from comgrasp_pin.camera import PinholeCamera
from comgrasp_pin.errors import ObjectNotFoundError
from comgrasp_pin.perception._points import noise_level, points_in

INLIER_DISTANCE = 0.005  # a point this close to the plane is on it (m), or NOISE_SIGMAS
NOISE_SIGMAS = 3.0  # ... of the depth's own noise where it is noisier (a structured light's)
NOISE_WINDOW = 15  # px: the depth's noise is measured about the mean of this window
MIN_SHARE = 0.3  # the table must be at least this share of the valid pixels
SAMPLES = 300  # RANSAC's draws of three points
SEPARATION = 0.05  # a plane this much nearer the camera than the best-held one is another
PARALLEL_DEG = 5.0  # ... surface (the table above the floor) when parallel within this
NEAR_SHARE = 0.15  # ... and holding this share of the valid pixels
MAX_POINTS = 20_000  # points the plane is fitted to (an even subsample of the image)
MIN_AREA_POINTS = 1000  # the table's points in the pick area the plane is fitted to again
CLEAR_PX = 10  # ... that far from what stands half the inlier band above it, at least,
REFIT_GAIN = 0.1  # ... where their heights' spread about it is this share less, at least
GRID = 0.005  # the table's cells when its clear rectangle is sought (m)
EDGE_MARGIN = 0.02  # the clear rectangle less this on each side (m): a board's edge may be
# bevelled or warped, and a depth camera's pixels fly at it


def fit_table_plane(
    depth: np.ndarray, camera: PinholeCamera, seed: int = 0
) -> tuple[np.ndarray, tuple[float, float, float, float]]:
    """(T_table_cam (4, 4), the pick area (x_min, x_max, y_min, y_max)) (m).

    ``depth``: (H, W) float z-depth (m), 0 or inf where none. The pick area, in the table
    frame, is the largest rectangle of the table seen whole (``clear_rectangle``).

    Raises:
        ObjectNotFoundError: no plane holds MIN_SHARE of the valid pixels.
    """
    image_points = points_in(np.eye(4), depth, camera)
    points = image_points.reshape(-1, 3)
    points = points[np.isfinite(points[:, 2])]
    if len(points) < 100:
        raise ObjectNotFoundError("the depth image has too few valid pixels to find a table")
    step = max(1, len(points) // MAX_POINTS)
    sample = points[::step]
    rng = np.random.default_rng(seed)
    band = _inlier_band(depth)
    planes = []  # (inliers, normal, a point) of each plane holding NEAR_SHARE
    for a, b, c in rng.integers(0, len(sample), size=(SAMPLES, 3)):
        normal = np.cross(sample[b] - sample[a], sample[c] - sample[a])
        if np.linalg.norm(normal) < 1e-12:
            continue
        normal /= np.linalg.norm(normal)
        count = np.count_nonzero(np.abs((sample - sample[a]) @ normal) < band)
        if count >= NEAR_SHARE * len(sample):
            planes.append((count, normal, sample[a]))
    best = _nearest_surface(planes, MIN_SHARE * len(sample))
    if best is None:
        raise ObjectNotFoundError(
            f"no plane holds {100 * MIN_SHARE:.0f} % of the depth image's points: the table is "
            "not in view; give the camera's pose instead"
        )
    _, normal, origin = best
    T_table_cam = _table_frame(points[np.abs((points - origin) @ normal) < band])
    area = clear_rectangle(image_points, T_table_cam, band)
    # The plane the rod lies on is the table under the pick area: a board laid on a table, or
    # a warped top, is not one plane with all the image sees (GQ-CNN's PrimeSense frames: the
    # board 2.8 mrad off the plane of the whole view). Fitted again to the bare table there,
    # where its heights spread less about that plane (a noisy camera's do not: the fewer
    # points would only tilt the plane by their noise).
    bare = _bare_table(image_points, T_table_cam, area, band)
    if len(bare) >= MIN_AREA_POINTS:
        T_refit = _table_frame(bare)
        spread = [noise_level(bare @ T[2, :3] + T[2, 3]) for T in (T_table_cam, T_refit)]
        if spread[1] < (1.0 - REFIT_GAIN) * spread[0]:
            T_table_cam = T_refit
            area = clear_rectangle(image_points, T_table_cam, band)
    return T_table_cam, area


def _bare_table(image_points: np.ndarray, T_table_cam: np.ndarray, area, band: float):
    """(N, 3) the camera's points of the bare table in ``area`` (table frame, m).

    Within ``band`` of the plane, and CLEAR_PX or more from any pixel half that high above
    it: a rod's low handle, which the band would take in, does not tilt the plane.
    """
    x, y, z = np.moveaxis(image_points @ T_table_cam[:3, :3].T + T_table_cam[:3, 3], -1, 0)
    with np.errstate(invalid="ignore"):  # NaN where no depth
        raised = (z >= 0.5 * band).astype(np.uint8)
        kernel = np.ones((2 * CLEAR_PX + 1, 2 * CLEAR_PX + 1), np.uint8)
        near = cv2.dilate(raised, kernel) > 0
        bare = (np.abs(z) < band) & ~near
        bare &= (x > area[0]) & (x < area[1]) & (y > area[2]) & (y < area[3])
    return image_points[bare]


def _table_frame(on_plane: np.ndarray) -> np.ndarray:
    """T_table_cam of the least-squares plane of the points ``on_plane`` (N, 3) (camera, m).

    z along its normal towards the camera, origin below the camera's centre, x the camera's
    x laid on the plane.
    """
    centre = on_plane.mean(axis=0)
    normal = np.linalg.svd(on_plane - centre, full_matrices=False)[2][2]
    if normal @ -centre < 0:  # towards the camera (at the origin)
        normal = -normal
    foot = -(normal @ -centre) * normal  # the camera's centre dropped onto the plane
    x = np.array([1.0, 0.0, 0.0]) - normal[0] * normal
    x /= np.linalg.norm(x)
    T_cam_table = np.eye(4)
    T_cam_table[:3, :3] = np.column_stack([x, np.cross(normal, x), normal])
    T_cam_table[:3, 3] = foot
    return np.linalg.inv(T_cam_table)


def _nearest_surface(planes: list, least: float) -> tuple | None:
    """The table among ``planes`` ((inliers, normal, point)); None if none holds ``least``.

    The best-held of those parallel to the best-held one and nearer the camera by
    SEPARATION at least (a table above the floor that a camera high above it sees more of),
    else the best-held one.
    """
    first = max(planes, key=lambda p: p[0], default=None)
    if first is None or first[0] < least:
        return None

    def distance(p) -> float:  # of the camera's centre (the origin) from the plane
        return abs(float(p[1] @ p[2]))

    nearer = [p for p in planes if abs(float(p[1] @ first[1])) > np.cos(np.radians(PARALLEL_DEG))
              and distance(p) < distance(first) - SEPARATION]  # fmt: skip
    return max(nearer, key=lambda p: p[0]) if nearer else first


def _inlier_band(depth: np.ndarray) -> float:
    """How close to the plane a point is on it (m).

    INLIER_DISTANCE, or NOISE_SIGMAS of the depth's noise where that is larger: its robust
    std about the mean of the NOISE_WINDOW around each pixel (a structured-light camera's
    noise comes in patches a few pixels wide, which a smaller window follows).
    """
    valid = np.isfinite(depth) & (depth > 0)
    d = np.where(valid, depth, 0.0).astype(np.float32)
    window = (NOISE_WINDOW, NOISE_WINDOW)
    count = cv2.blur(valid.astype(np.float32), window)
    mean = cv2.blur(d, window) / np.maximum(count, 1e-6)
    return max(INLIER_DISTANCE, NOISE_SIGMAS * noise_level((d - mean)[valid & (count > 0.5)]))


def clear_rectangle(points_cam: np.ndarray, T_table_cam: np.ndarray,
                    band: float = INLIER_DISTANCE):  # fmt: skip
    """The largest axis-aligned rectangle (x_min, x_max, y_min, y_max) of the table seen whole.

    ``points_cam``: (H, W, 3) every pixel's point in the camera (NaN where no depth). The
    table's pixels (within ``band`` of its plane z = 0, m), their largest connected
    region with the holes in it filled (what lies on the table), are laid on the plane in
    GRID cells; the rectangle is the largest that holds only such cells, less EDGE_MARGIN
    (m, table frame).
    """
    points = points_cam @ T_table_cam[:3, :3].T + T_table_cam[:3, 3]
    z = points[..., 2]
    on = (np.abs(np.nan_to_num(z, nan=np.inf)) < band).astype(np.uint8)
    count, labels, stats, _ = cv2.connectedComponentsWithStats(on, connectivity=8)
    table = labels == 1 + int(np.argmax(stats[1:, cv2.CC_STAT_AREA]))
    outline, _ = cv2.findContours(table.astype(np.uint8), cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
    filled = cv2.drawContours(np.zeros_like(on), outline, -1, 1, cv2.FILLED) > 0
    filled &= np.isfinite(z)
    # a pixel that sees an object on the table stands on the plane where its ray meets it
    ray = points_cam[filled] / points_cam[filled][:, 2:]
    origin = T_table_cam[:3, 3]
    direction = ray @ T_table_cam[:3, :3].T
    xy = origin[:2] + (-origin[2] / direction[:, 2])[:, None] * direction[:, :2]
    lo = xy.min(axis=0)
    cells = np.floor((xy - lo) / GRID).astype(int)
    grid = np.zeros(cells.max(axis=0) + 1, np.uint8)
    grid[cells[:, 0], cells[:, 1]] = 1
    grid = cv2.morphologyEx(grid, cv2.MORPH_CLOSE, np.ones((3, 3), np.uint8))  # gaps between rays
    (i0, i1), (j0, j1) = _largest_rectangle(grid > 0)
    x0, x1 = lo[0] + i0 * GRID + EDGE_MARGIN, lo[0] + i1 * GRID - EDGE_MARGIN
    y0, y1 = lo[1] + j0 * GRID + EDGE_MARGIN, lo[1] + j1 * GRID - EDGE_MARGIN
    if x1 <= x0 or y1 <= y0:
        raise ObjectNotFoundError("the table in view is too small to pick from")
    return float(x0), float(x1), float(y0), float(y1)


def _largest_rectangle(grid: np.ndarray) -> tuple[tuple[int, int], tuple[int, int]]:
    """((row_start, row_end), (col_start, col_end)) of the largest all-True rectangle.

    The classic histogram method: per row, the run of True above each column, and the
    largest rectangle under that histogram by a stack.
    """
    runs = np.zeros(grid.shape[1] + 1, int)
    best, where = 0, ((0, 0), (0, 0))
    for i, row in enumerate(grid):
        runs[:-1] = np.where(row, runs[:-1] + 1, 0)
        stack: list[int] = []
        for j, height in enumerate(runs):
            while stack and runs[stack[-1]] >= height:
                top = runs[stack.pop()]
                left = stack[-1] + 1 if stack else 0
                if top * (j - left) > best:
                    best, where = top * (j - left), ((i + 1 - top, i + 1), (left, j))
            stack.append(j)
    return where
