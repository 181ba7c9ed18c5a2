"""Shared steps: validating images, lifting masked pixels to 3-D, robust line fits."""

from __future__ import annotations

import cv2
import numpy as np

from comgrasp_pin.camera import PinholeCamera, transform_points
from comgrasp_pin.errors import InvalidDepthError, ObjectNotFoundError


def check_images(rgb: np.ndarray | None, depth: np.ndarray, camera: PinholeCamera) -> np.ndarray:
    """``depth`` as float (H, W) metric z-depth; InvalidDepthError if unusable."""
    if not isinstance(camera, PinholeCamera):
        raise InvalidDepthError(f"camera must be a PinholeCamera, got {type(camera).__name__}")
    shape = (camera.height, camera.width)
    try:
        depth_in = np.asarray(depth)
    except (TypeError, ValueError):
        raise InvalidDepthError("the depth image is not a numeric array") from None
    if depth_in.dtype.kind in "iu":
        raise InvalidDepthError(
            f"the depth image must be float metres, got dtype {depth_in.dtype}: an integer "
            "image in a camera's depth units (a RealSense's uint16) is depth * depth_scale "
            "metres (the SDK's depth scale, e.g. 0.001 for millimetres)"
        )
    if depth_in.dtype.kind != "f":
        raise InvalidDepthError(
            f"the depth image is not a numeric array of float metres (dtype {depth_in.dtype})"
        )
    depth = depth_in.astype(float, copy=False)
    if depth.shape != shape:
        raise InvalidDepthError(f"depth image has shape {depth.shape}, the camera is {shape}")
    if rgb is not None and np.asarray(rgb).shape[:2] != shape:
        raise InvalidDepthError(f"RGB image {np.asarray(rgb).shape} does not match depth {shape}")
    if np.isnan(depth).any():
        raise InvalidDepthError("depth image contains NaN (use inf for 'no return')")
    if not np.isfinite(depth).any() or (depth[np.isfinite(depth)] <= 0).all():
        raise InvalidDepthError("depth image has no valid (finite, positive) value")
    return depth


def points_in(T_frame_cam: np.ndarray, depth: np.ndarray, camera: PinholeCamera) -> np.ndarray:
    """(H, W, 3) points of every pixel in the frame of ``T_frame_cam``; NaN where no depth.

    ``camera.depth_to_points`` followed by ``transform_points``, to the bit: each pixel's
    ray slope, (u - cx) / fx, is taken once per column (and row) instead of once per pixel.
    """
    if depth.shape != (camera.height, camera.width):
        raise InvalidDepthError(f"depth image {depth.shape} does not match the camera")
    valid = np.isfinite(depth) & (depth > 0)
    z = np.where(valid, depth, 1.0)
    in_cam = np.empty((*depth.shape, 3))
    np.multiply(pixel_slopes(camera.width, camera.cx, camera.fx), z, out=in_cam[..., 0])
    np.multiply(pixel_slopes(camera.height, camera.cy, camera.fy)[:, None], z, out=in_cam[..., 1])
    in_cam[..., 2] = z
    points = transform_points(T_frame_cam, in_cam.reshape(-1, 3)).reshape(in_cam.shape)
    points[~valid] = np.nan
    return points


def pixel_slopes(count: int, centre: float, focal: float) -> np.ndarray:
    """(count,) the rays' x / z (or y / z) of the pixel columns (or rows) 0..count-1."""
    return (np.arange(count) - centre) / focal


def points_at(
    T_frame_cam: np.ndarray, depth: np.ndarray, camera: PinholeCamera, pixels: np.ndarray
) -> np.ndarray:
    """(N, 3) points of the valid pixels ``pixels`` (N,) (flat indices) in ``T_frame_cam``'s frame.

    ``points_in(T_frame_cam, depth, camera).reshape(-1, 3)[pixels]`` to the bit (the same
    products on the same numbers), without lifting the rest of the image.
    """
    row, col = np.divmod(pixels, camera.width)
    z = depth.reshape(-1)[pixels]
    x = (col - camera.cx) / camera.fx * z
    y = (row - camera.cy) / camera.fy * z
    points = np.stack([x, y, z], axis=-1)
    if len(points) == 1:  # one row alone would take another BLAS path than an image's
        return transform_points(T_frame_cam, np.vstack([points, points]))[:1]
    return transform_points(T_frame_cam, points)


def border_pixels(blob: np.ndarray) -> np.ndarray:
    """(H, W) bool: pixels of ``blob`` on the image border."""
    edge = np.zeros_like(blob)
    edge[0], edge[-1], edge[:, 0], edge[:, -1] = blob[0], blob[-1], blob[:, 0], blob[:, -1]
    return edge


def opened_blobs(mask: np.ndarray) -> tuple[int, np.ndarray, np.ndarray]:
    """(count, labels, stats) of ``mask``'s 8-connected blobs after a 3 x 3 opening.

    As ``cv2.connectedComponentsWithStats`` gives them (label 0 the background): the
    opening removes specks and one-pixel bridges before the blobs are counted.
    """
    opened = cv2.morphologyEx(mask.astype(np.uint8), cv2.MORPH_OPEN, np.ones((3, 3), np.uint8))
    count, labels, stats, _ = cv2.connectedComponentsWithStats(opened, connectivity=8)
    return count, labels, stats


def largest_component(mask: np.ndarray, min_pixels: int, what: str) -> np.ndarray:
    """The largest connected blob of ``mask`` after a small opening, and what it cut off.

    The opening removes specks and one-pixel bridges; it can also cut a thin neck, such as
    a 1 cm stick's between its handle and its head. Opened pieces that were one blob of
    ``mask`` before the opening are one object: they are kept with the largest.
    ObjectNotFoundError if there is none. Whether it touches the image's border is the
    caller's to judge (the top view counts other objects first: ``standing.segment``).
    """
    count, labels, stats = opened_blobs(mask)
    if count <= 1 or stats[1:, cv2.CC_STAT_AREA].max() < min_pixels:
        raise ObjectNotFoundError(f"no object found in the {what} (fewer than {min_pixels} px)")
    best = 1 + int(np.argmax(stats[1:, cv2.CC_STAT_AREA]))
    _, raw_labels = cv2.connectedComponents(mask.astype(np.uint8), connectivity=8)
    seed = tuple(np.argwhere(labels == best)[0])  # a pixel of the largest opened blob
    return (raw_labels == raw_labels[seed]) & (labels > 0)


def blobs(mask: np.ndarray, min_pixels: int, what: str, min_blob: int = 20) -> np.ndarray:
    """Every connected blob of ``mask`` of at least ``min_blob`` pixels, after a small opening.

    An object split by an occluder (e.g. the near finger) thus stays whole.
    ObjectNotFoundError if fewer than ``min_pixels`` remain.
    """
    _, labels, stats = opened_blobs(mask)
    big = 1 + np.flatnonzero(stats[1:, cv2.CC_STAT_AREA] >= min_blob)
    kept = np.isin(labels, big)
    if kept.sum() < min_pixels:
        raise ObjectNotFoundError(f"no object found in the {what} (fewer than {min_pixels} px)")
    return kept


def fit_line(points: np.ndarray, iterations: int = 3) -> tuple[np.ndarray, np.ndarray]:
    """Robust 3-D line through (N, 3) points: (centroid (3,), unit direction (3,)).

    PCA, then twice: drop points farther from the line than 3 median distances, refit.
    """
    keep = np.ones(len(points), dtype=bool)
    for _ in range(iterations):
        centroid = points[keep].mean(axis=0)
        _, _, vt = np.linalg.svd(points[keep] - centroid, full_matrices=False)
        direction = vt[0]
        offsets = points - centroid
        dist = np.linalg.norm(offsets - np.outer(offsets @ direction, direction), axis=1)
        keep = dist <= 3.0 * np.median(dist[keep]) + 1e-4
    return centroid, direction


def fill_holes(depth: np.ndarray, max_gap_px: float = 2.5) -> np.ndarray:
    """``depth`` with its holes filled from the nearest valid pixel.

    Each lost pixel (0, inf) within ``max_gap_px`` of a valid one is given the depth of the
    nearest valid pixel (OpenCV's distance transform with labels): holes and dropouts inside
    surfaces close, edges stay sharp (a pixel takes one side's depth, never a mix). Larger
    empty regions stay empty. No lost pixel: ``depth`` itself.
    """
    valid = np.isfinite(depth) & (depth > 0)
    if valid.all():
        return depth
    dist, labels = cv2.distanceTransformWithLabels(
        (~valid).astype(np.uint8), cv2.DIST_L2, 5, labelType=cv2.DIST_LABEL_PIXEL
    )
    # OpenCV numbers the valid (zero) pixels 1, 2, ... in raster order, the order of a
    # boolean index: label k's depth is the k-th valid pixel's (tests/test_fast_paths.py).
    values = np.concatenate([[0.0], depth[valid]])
    filled = np.where(valid, depth, np.inf)
    near = ~valid & (dist <= max_gap_px)
    filled[near] = values[labels[near]]
    return filled


def denoise(depth: np.ndarray) -> np.ndarray:
    """A 5 x 5 median of ``depth`` (m).

    Noise falls 3-4 times, straight edges stay where they are; lost pixels (inf) stay lost.
    """
    valid = np.isfinite(depth)
    out = cv2.medianBlur(np.where(valid, depth, 0.0).astype(np.float32), 5).astype(float)
    out[~valid | (out <= 0)] = np.inf
    return out


def noise_level(heights: np.ndarray) -> float:
    """Robust standard deviation (1.4826 MAD) of ``heights`` about their median (m)."""
    heights = heights[np.isfinite(heights)]
    if len(heights) == 0:
        return 0.0
    if 2 * np.count_nonzero(heights) < len(heights):
        # More than half exactly 0 (a clean render against its median): the median is 0,
        # and so is the median of the absolute deviations.
        return 0.0
    return float(1.4826 * median(np.abs(heights - median(heights))))


_RING = np.array([[1, 1, 1], [1, 0, 1], [1, 1, 1]], np.uint8)  # a pixel's 8 neighbours


def drop_flying(depth: np.ndarray, tolerance: float) -> np.ndarray:
    """``depth`` with its flying pixels lost (set to 0).

    A flying pixel (a stereo camera's mix of the near and the far side of an edge) lies
    between its neighbours and agrees with none: some are nearer and some farther by more
    than ``tolerance`` (m), and none is within it. A pixel of a surface agrees with some
    neighbour; one at an edge whose own side was lost is not between. Lost pixels (0, inf)
    stay lost and are no one's neighbours: they count as infinitely far for the nearest
    neighbour and infinitely near for the farthest. The nearest and farthest neighbours are
    an erosion and a dilation over the 8 neighbours (minima and maxima are exact: the
    NaN-aware reductions to the bit); the closest one is looked for only at the pixels
    between their neighbours.
    """
    valid = np.isfinite(depth) & (depth > 0)
    for_min = np.where(valid, depth, np.inf)
    constant = cv2.BORDER_CONSTANT
    near = cv2.erode(for_min, _RING, borderType=constant, borderValue=np.inf)
    for_max = np.where(valid, depth, -np.inf)
    far = cv2.dilate(for_max, _RING, borderType=constant, borderValue=-np.inf)
    with np.errstate(invalid="ignore"):  # inf - inf where a lost pixel has no valid neighbour
        between = valid & (depth - near > tolerance) & (far - depth > tolerance)
    row, col = np.nonzero(between)
    padded = np.pad(for_min, 1, constant_values=np.inf)
    d = depth[row, col]
    closest = np.full(len(row), np.inf)
    for dy, dx in ((dy, dx) for dy in (-1, 0, 1) for dx in (-1, 0, 1) if dy or dx):
        np.fmin(closest, np.abs(padded[row + 1 + dy, col + 1 + dx] - d), out=closest)
    out = depth.copy()
    out[row[closest > tolerance], col[closest > tolerance]] = 0.0
    return out


def median(x: np.ndarray) -> np.floating:
    """``np.median`` of a 1-D array without NaN, to the bit, without its checks.

    The side view's fits take hundreds of medians of a few thousand values per frame.
    """
    k = len(x) // 2
    if len(x) % 2:
        return np.partition(x, k)[k]
    part = np.partition(x, [k - 1, k])
    return (part[k - 1] + part[k]) / 2.0


def slice_medians(
    bins: np.ndarray, values: tuple[np.ndarray, ...], min_count: int
) -> tuple[np.ndarray, np.ndarray]:
    """The slices with at least ``min_count`` points and the medians of ``values`` in each.

    ``bins``: each point's integer slice; ``values``: arrays like ``bins``. Returns the
    slices in increasing order (k,) and (k, len(values)) medians: ``np.median(v[bins ==
    b])``, to the bit, with one sort instead of a mask per slice.
    """
    order = np.argsort(bins, kind="stable")
    labels, starts, counts = np.unique(bins[order], return_index=True, return_counts=True)
    full = counts >= min_count
    rows = [[median(v[order[a : a + n]]) for v in values]
            for a, n in zip(starts[full], counts[full], strict=True)]  # fmt: skip
    return labels[full], np.array(rows, dtype=float).reshape(len(rows), len(values))


def slice_percentiles(
    bins: np.ndarray, values: np.ndarray, percentiles: tuple[float, ...], min_count: int
) -> tuple[np.ndarray, np.ndarray]:
    """Per slice of ``bins`` with at least ``min_count`` points, its count and percentiles.

    Returns (counts (k,), (k, len(percentiles)) percentiles of ``values``), the slices in
    increasing order: ``np.percentile(values[bins == b], percentiles)``, to the bit
    (NumPy's linear method: its index, weight and two-sided interpolation), from one sort
    of all the points instead of a mask and a partition per slice.
    """
    order = np.lexsort((values, bins))
    _, starts, counts = np.unique(bins[order], return_index=True, return_counts=True)
    starts, counts = starts[counts >= min_count], counts[counts >= min_count]
    ordered = values[order]
    last = starts + counts - 1  # (a slice of one point: its value, as NumPy's)
    out = np.empty((len(counts), len(percentiles)))
    for j, q in enumerate(np.true_divide(percentiles, 100)):
        virtual = (counts - 1) * q
        below = np.floor(virtual)
        t = virtual - below
        a = ordered[np.minimum(starts + below.astype(np.intp), last)]
        b = ordered[np.minimum(starts + below.astype(np.intp) + 1, last)]
        step = b - a
        out[:, j] = np.where(t >= 0.5, b - step * (1 - t), a + step * t)
    return counts, out
