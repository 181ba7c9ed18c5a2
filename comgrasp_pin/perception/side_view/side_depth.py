"""The side camera's depth: cleaned, and the held handle's surface as a line along the rod.

``clean_side_depth`` leaves a clean frame as it is and filters a real camera's (lost pixels,
flying pixels, noise), saying which pixels it measured. ``surface_line`` fits where the
handle's visible surface lies along the jaw axis (ee y, the camera's depth) as a line along
the rod: its change between two views is the rod shifting along the jaws and turning out of
their plane (the grasp's compliance), which the axis cannot show. SI units.
"""

from __future__ import annotations

import numpy as np

from comgrasp_pin.perception._points import (
    denoise,
    drop_flying,
    fill_holes,
    noise_level,
    slice_medians,
)

CLEAN_NOISE = 3e-4  # depth noisier than this (m, robust std about its median) is filtered
FLYING_MIN, FLYING_SIGMAS = 0.005, 4.0  # flying pixels: this far from all neighbours (m, stds)
DEPTH_MARGIN = 0.003  # the handle's surface lies within its radius (+ this) of y_ee = 0 (m)
DEPTH_SLICE = 0.01  # slices along the rod for its depth line (m)


def clean_side_depth(depth: np.ndarray) -> tuple[np.ndarray, float, bool, np.ndarray]:
    """(depth, noise (m), cleaned, measured): ``depth``, 0, False, its valid pixels if clean.

    Else (pixels lost, i.e. 0, or noisier than CLEAN_NOISE against its 5 x 5 median) its
    flying pixels dropped, its holes (0 or inf) filled, the median taken, its noise, True
    and ``measured`` (H, W) bool: the pixels the camera measured (neither lost nor flying).
    A filled pixel takes its nearest valid neighbour's depth: beside a rod seen against
    nothing (inf) that grows the rod's outline by a few pixels at the depth of its edge,
    which is no measurement of its surface (``surface_line`` leaves them out).
    """
    smooth = denoise(fill_holes(depth))
    both = np.isfinite(depth) & np.isfinite(smooth)
    noise = noise_level(depth[both] - smooth[both])
    # A camera marks a lost pixel 0; inf is also what a render gives where nothing is seen.
    if np.any(depth <= 0) or noise > CLEAN_NOISE:
        grounded = drop_flying(depth, max(FLYING_MIN, FLYING_SIGMAS * noise))
        measured = np.isfinite(grounded) & (grounded > 0)
        return denoise(fill_holes(grounded)), noise, True, measured
    return depth, 0.0, False, np.isfinite(depth) & (depth > 0)


def surface_line(
    points_ee: np.ndarray, along: np.ndarray, handle: np.ndarray, radius: float
) -> tuple:
    """The handle's visible surface along the jaw axis, as a line along the rod.

    Returns ``depth_line``'s: y_ee (m) at along = 0, its slope, their std, the slices.

    ``points_ee``: (n, 3) the rod's points in the ee frame; ``along``: (n,) their positions
    along the axis (m); ``handle``: (n,) bool, the handle's pixels the camera measured
    (``clean_side_depth``: a filled hole is not the surface). Only the handle's own surface
    (within ``radius`` + DEPTH_MARGIN of the jaws' mid-plane): a head that stands within
    the axis' silhouette but far across the jaws (an axe's blade) is not it.
    """
    own = handle & (np.abs(points_ee[:, 1]) <= radius + DEPTH_MARGIN)
    return depth_line(along[own], points_ee[own, 1])


def depth_line(along: np.ndarray, y: np.ndarray) -> tuple:
    """A line through (along, y): y at along = 0, dy/d along, their std, the slices.

    Fitted to the medians of 1 cm slices along the rod (the slices: (k, 3) of index,
    median along, median y): the points of one slice are one piece of surface, not
    independent samples, so the standard errors come from how the slices scatter about the
    line (point by point they would be some 30 times too small).
    """
    bins = np.floor(along / DEPTH_SLICE).astype(int)
    labels, medians = slice_medians(bins, (along, y), 5)
    if len(labels) < 3:
        y_mid = float(np.median(y)) if len(y) else 0.0
        return y_mid, 0.0, float("inf"), float("inf"), None
    c = np.column_stack([labels, medians])
    (slope, y0), cov = np.polyfit(c[:, 1], c[:, 2], 1, cov=True)  # scaled by the residuals
    return float(y0), float(slope), float(np.sqrt(cov[1, 1])), float(np.sqrt(cov[0, 0])), c
