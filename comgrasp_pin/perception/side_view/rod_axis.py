"""The axis of a held rod in the jaws' plane (ee x-z), from the side camera's points.

Slice centres give a first line that heads and weights do not pull; a cylinder fitted to
the handle's visible surface removes the offset of seeing only its near side. Ee frame, m.
"""

from __future__ import annotations

import numpy as np

from comgrasp_pin.perception._points import fit_line, slice_medians
from comgrasp_pin.perception.side_view.cylinder_fit import (  # noqa: F401 - the fit's constants
    FIT_DAMPING,
    FIT_ITERATIONS,
    FIT_OUTLIER_MARGIN,
    FIT_STEPS,
    MAX_FIT_POINTS,
    MAX_Y_SHIFT,
    fit_cylinders,
)

MAX_MISFIT = 5e-4  # a round handle's points lie this close to the fitted cylinder (m) ...
MAX_MISFIT_PER_RADIUS = 0.03  # ... or this fraction of its radius (a flat bar: 0.15-0.2)
MISFIT_NOISE = 1.5  # ... or, in a noisy image, this many times its depth noise (m)
"""Measured against the simulator's truth on realistic side views (50 grasps an object):
round handles' cylinders that misfit by 1.0-1.35 times the noise (obj4, obj5, 4-5 cm) are
within 0.2 deg of the truth; at about 2 times, other parts are among the handle's points
(obj2's head: 3 deg off). At 1.0 obj4 lost 3 of 50 grasps, obj5 2, to refused views;
at 1.5, 1 and 1, with the same accuracy below 30 deg (paired: +0.03 +- 0.05 points)."""
QUANTUM_STD = 1 / np.sqrt(12)  # a depth rounded to units of q: errors of std q/sqrt(12)
MAX_REFINE_TURN_DEG = 8.0  # a cylinder this far from the slice line locked on a wrong side
MAX_REFINE_SHIFT = 0.01  # the same, for its offset (m)
RADIUS_GIVE = np.arange(0.25, 2.01, 0.25) * 1e-3  # the handle's radius above the fingers' (m)


def centre_line(
    xz: np.ndarray, bin_width: float = 0.01
) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """The rod's axis in the ee x-z plane, from slice centres.

    The visible points are cut in slices across the rod; the median of each slice is a
    point of the centre line, and a line is fitted to those slice centres with outlier
    rejection. Heads and weights, which stand off the handle's axis over a few slices
    only, then do not pull the axis (a plain PCA of all points would).
    Returns (unit direction (2,) with positive x, the point nearest the TCP (2,), (N,) bool
    mask of the points in the slices kept: the handle, the standard error of the direction's
    angle (rad) from the kept slice centres' scatter about the line).
    """
    _, direction = fit_line(np.c_[xz, np.zeros(len(xz))])
    direction = direction[:2] / np.linalg.norm(direction[:2])
    point = xz.mean(axis=0)
    in_kept = np.ones(len(xz), dtype=bool)
    angle_std = np.inf
    for _ in range(2):
        normal = np.array([-direction[1], direction[0]])
        along, across = xz @ direction, xz @ normal
        bins = np.floor(along / bin_width).astype(int)
        labels, c = slice_medians(bins, (along, across), 5)
        if len(labels) < 3:
            break
        keep = np.ones(len(c), dtype=bool)
        for _ in range(3):
            slope, intercept = np.polyfit(c[keep, 0], c[keep, 1], 1)
            residual = np.abs(c[:, 1] - (slope * c[:, 0] + intercept))
            keep = residual <= max(3.0 * np.median(residual[keep]), 0.002)
        point = intercept * normal
        direction = (direction + slope * normal) / np.hypot(1.0, slope)
        in_kept = np.isin(bins, np.array(labels)[keep])
        angle_std = slope_std(c[keep], slope, intercept) / (1.0 + slope * slope)
    if direction[0] < 0:
        direction = -direction
    return direction, point - (point @ direction) * direction, in_kept, float(angle_std)


def slope_std(c: np.ndarray, slope: float, intercept: float) -> float:
    """Standard error of a fitted line's slope through the points ``c`` (k, 2)."""
    k = len(c)
    spread = float(np.sum((c[:, 0] - c[:, 0].mean()) ** 2))
    if k < 3 or spread <= 0.0:
        return float("inf")
    residual = c[:, 1] - (slope * c[:, 0] + intercept)
    return float(np.sqrt(np.sum(residual**2) / (k - 2) / spread))


def _cylinder_residuals(
    prm: np.ndarray, pts: np.ndarray, y2: np.ndarray | None = None
) -> np.ndarray:
    """Distance (m) of the points (N, 3) from the axis of the cylinder ``prm``, less its radius.

    ``prm``: axis angle in the x-z plane (rad), its offset along the normal (m), radius (m),
    and, when given, the axis' offset along y (m). ``y2``: the points' y squared, which the
    axis does not change without a y offset (``fit_cylinder`` computes it once per fit).
    The arithmetic of ``np.linalg.norm(rel - np.outer(rel @ u, u), axis=1)``, operation for
    operation (the same results to the bit, tests/test_fast_paths.py), on the x and z columns
    only: the axis has no y component, so the y column of that difference is the points'
    own y.
    """
    c, s = np.cos(prm[0]), np.sin(prm[0])
    u = np.array([c, 0.0, s])
    rel = pts - prm[1] * np.array([-s, 0.0, c])
    if len(prm) > 3:
        rel -= np.array([0.0, prm[3], 0.0])
        y2 = rel[:, 1] * rel[:, 1]
    elif y2 is None:
        y2 = pts[:, 1] * pts[:, 1]
    t = rel @ u
    d0 = rel[:, 0] - t * c
    d2 = rel[:, 2] - t * s
    out = d0 * d0
    out += y2
    d2 *= d2
    out += d2
    np.sqrt(out, out=out)
    out -= prm[2]
    return out


def fit_cylinder(
    points: np.ndarray,
    direction: np.ndarray,
    point: np.ndarray,
    radius: float | None = None,
    free_y: bool = False,
) -> tuple[np.ndarray, np.ndarray, float]:
    """Refine the axis (in the plane y = 0) by fitting a cylinder to the visible surface.

    The camera sees one side of the rod, so the visible points stand off the axis towards
    the camera; the slice centres inherit that offset, which changes along a tilted rod
    and biases the tilt. Fitting |(p - a) x u| = r (axis angle, its offset, radius r) by
    Gauss-Newton, with points far off the cylinder (heads, weights) left out, removes it.
    ``radius`` (m), when known (half the jaws' opening), is held fixed. ``free_y``: the axis
    may lie off y = 0 (a camera whose calibrated pose is off moves all the points; the jaws
    still hold the rod at y = 0, so only its x-z line is kept).
    Returns (direction (2,), point nearest the TCP (2,)) in the x-z plane, and the median
    distance of the points from the cylinder (m). ``cylinder_fit.fit_cylinders`` with one
    radius (it fits several at once).
    """
    return fit_cylinders(points, direction, point, [radius], free_y)[0]


def refine_axis(
    points: np.ndarray,
    direction: np.ndarray,
    point: np.ndarray,
    radius: float | None,
    noise: float = 0.0,
    quantum: float = 0.0,
) -> tuple[np.ndarray, np.ndarray]:
    """The slice line refined by a cylinder fitted to the handle, where it is round.

    ``direction`` and ``point`` are the slice line in the x-z plane, ``points`` (N, 3) the
    handle's; returned unchanged where no cylinder fits.

    The fingers' reading ``radius`` (m) is the handle's radius less the pads' give (up to
    about a millimetre under the grip); when the cylinder of that radius fits poorly, the
    radii up to ``RADIUS_GIVE`` larger are tried (a free radius is ill-posed from the points
    of one side) and the best fit is kept. The fit is trusted only near the slice line (it
    can lock on a wrong side) and where the points lie on it (a flat bar is no cylinder).
    ``quantum``: the step of a depth given in integer units (m; ROS's 16UC1 millimetres):
    its rounding, an error the image's noise does not show (a clean surface's steps),
    widens the misfit allowed in quadrature, as MISFIT_NOISE times its std.
    """
    fits = [fit_cylinder(points, direction, point, radius)]
    if radius and fits[0][2] >= MAX_MISFIT:
        fits += fit_cylinders(points, direction, point, [radius + dr for dr in RADIUS_GIVE])
    x_fit, offset_fit, misfit = min(fits, key=lambda fit: fit[2])
    limit = max(MAX_MISFIT, MAX_MISFIT_PER_RADIUS * radius) if radius else MAX_MISFIT
    limit = float(np.hypot(max(limit, MISFIT_NOISE * noise), MISFIT_NOISE * QUANTUM_STD * quantum))
    if radius and misfit >= limit:  # the camera's pose may be off: the axis off y = 0
        radii = [radius + dr for dr in (0.0, *RADIUS_GIVE)]
        x_fit, offset_fit, misfit = min(
            fit_cylinders(points, direction, point, radii, free_y=True), key=lambda fit: fit[2]
        )
    near = (
        x_fit @ direction > np.cos(np.radians(MAX_REFINE_TURN_DEG))
        and np.linalg.norm(offset_fit - point) < MAX_REFINE_SHIFT
    )
    if near and misfit < limit:
        return x_fit, offset_fit
    return direction, point
