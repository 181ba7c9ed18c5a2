"""Cylinders fitted to a held handle's visible surface, several radii at once (ee frame, m).

``rod_axis.refine_axis`` tries the fingers' radius and up to 17 others; each is the same
damped Gauss-Newton (Levenberg-Marquardt) fit of the axis on the same points. Here they run
as one: every array carries a leading axis of fits, each fit keeps its own inliers (a mask),
damping and accepted steps, so each follows the steps it would alone. The sums are taken
over the masked rows of a product instead of over the inliers' copy, which moves the last
digits only (tests/test_fast_paths_side.py holds it to the plain per-fit loop).

In the x-z plane the distance of a point from an axis (angle a, offset o along its normal
n = (-sin a, cos a)) is |p . n - o|; with the point's y (less the axis' y offset) it is
the distance from the axis in 3-D: a residual is sqrt((p . n - o)^2 + y^2) - r.
"""

from __future__ import annotations

import numpy as np

from comgrasp_pin.perception._points import median

MAX_FIT_POINTS = 3000
FIT_ITERATIONS = 8  # Levenberg-Marquardt steps of the cylinder fit, each refitting the inliers
FIT_STEPS = (1e-6, 1e-7, 1e-7, 1e-7)  # finite-difference steps: angle (rad), offset, radius,
# y offset (m)
MAX_Y_SHIFT = 0.003  # a camera's calibration error may move the handle's axis this far in y (m)
FIT_DAMPING = (1e-6, 1e-3, 1e-1, 1.0)  # damping tried in turn until the cost falls
FIT_OUTLIER_MARGIN = 0.002  # inliers: within 3 median residuals plus this (m)


def cylinder_residuals(params: np.ndarray, xz: np.ndarray, y: np.ndarray) -> np.ndarray:
    """(..., N) signed distances (m) of the points from the cylinders ``params`` (..., P).

    ``params``: axis angle in the x-z plane (rad), its offset along the normal (m), radius
    (m) and, when P = 4, the axis' offset along y (m). ``xz``: (2, N) the points' x and z
    rows; ``y``: (N,) their y, or with P = 3 their y squared (the axis has no y offset).
    """
    angle = params[..., 0, None]
    across = np.cos(angle) * xz[1]
    across -= np.sin(angle) * xz[0]
    across -= params[..., 1, None]
    across *= across
    if params.shape[-1] > 3:
        off_y = y - params[..., 3, None]
        across += off_y * off_y
    else:
        across += y
    np.sqrt(across, out=across)
    across -= params[..., 2, None]
    return across


def fit_cylinders(
    points: np.ndarray,
    direction: np.ndarray,
    point: np.ndarray,
    radii: list[float | None],
    free_y: bool = False,
) -> list[tuple[np.ndarray, np.ndarray, float]]:
    """One cylinder fit per radius in ``radii`` (m; None: a free radius, alone).

    All on the same points (N, 3), from the line ``direction`` (2,), ``point`` (2,) in the
    x-z plane.
    Each fit is ``rod_axis.fit_cylinder``'s: ``free_y`` lets the axis lie off y = 0.
    Returns per radius (direction (2,), the axis' point nearest the TCP (2,), the median
    distance of all the points from the cylinder (m); inf when the axis moved more than
    MAX_Y_SHIFT in y).
    """
    # Three parameters need no more than a few thousand points (a full-resolution view
    # of a thick handle has tens of thousands): every k-th point, spread along the rod.
    points = points[:: max(1, len(points) // MAX_FIT_POINTS)]
    xz = np.ascontiguousarray(points[:, [0, 2]].T)
    y = points[:, 1] if free_y else points[:, 1] * points[:, 1]
    free_radius = radii[0] is None
    angle = np.arctan2(direction[1], direction[0])
    offset = point @ np.array([-direction[1], direction[0]])
    params = np.zeros((len(radii), 4 if free_y else 3))
    params[:, 0], params[:, 1] = angle, offset
    if free_radius:
        params[:, 2] = median(cylinder_residuals(params[0], xz, y))
    else:
        params[:, 2] = radii
    free = [0, 1] + ([2] if free_radius else []) + ([3] if free_y else [])
    params, misfits = _levenberg_marquardt(params, free, xz, y)
    out = []
    for (a, o, *rest), misfit in zip(params, misfits, strict=True):
        u, n = np.array([np.cos(a), np.sin(a)]), np.array([-np.sin(a), np.cos(a)])
        if free_y and abs(rest[1]) > MAX_Y_SHIFT:
            misfit = np.inf  # more than a calibration error: no fit
        out.append((-u if u[0] < 0 else u, o * n, float(misfit)))
    return out


def _levenberg_marquardt(
    params: np.ndarray, free: list[int], xz: np.ndarray, y: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """FIT_ITERATIONS damped steps of each fit ``params`` (K, P) in its ``free`` parameters.

    Each step refits the fit's inliers. Returns the parameters (K, P) and each fit's median
    distance of all the points from its cylinder (K,) (m).
    """
    k_fits, n_free = len(params), len(free)
    h = np.take(FIT_STEPS, free)  # (F,) finite-difference steps
    steps = np.zeros((n_free, params.shape[1]))
    steps[np.arange(n_free), free] = h
    on_diagonal = (slice(None), np.arange(n_free), np.arange(n_free))
    keep = np.ones((k_fits, xz.shape[1]), dtype=bool)
    res_signed = cylinder_residuals(params, xz, y)
    for _ in range(FIT_ITERATIONS):
        res = res_signed * keep  # (K, N): the inliers' residuals, 0 elsewhere
        jac = cylinder_residuals(params[:, None, :] + steps, xz, y)  # (K, F, N)
        jac -= res_signed[:, None, :]  # the Jacobian times each parameter's step h
        jtr = (jac @ res[:, :, None])[..., 0] / h  # (K, F): res is 0 off the inliers
        jtj = (jac * keep[:, None, :]) @ jac.transpose(0, 2, 1)  # (K, F, F)
        jtj /= h[:, None] * h
        cost = np.einsum("kn,kn->k", res, res)
        diag = jtj[on_diagonal]
        todo = np.arange(k_fits)  # the fits whose cost has not fallen yet
        for damping in FIT_DAMPING:
            damped = jtj[todo]
            damped[on_diagonal] += damping * diag[todo]
            delta = np.linalg.solve(damped, jtr[todo][:, :, None])[..., 0]
            trial = params[todo]
            trial[:, free] -= delta
            trial_signed = cylinder_residuals(trial, xz, y)
            kept_trial = trial_signed * keep[todo]
            better = np.einsum("kn,kn->k", kept_trial, kept_trial) < cost[todo]
            params[todo[better]], res_signed[todo[better]] = trial[better], trial_signed[better]
            todo = todo[~better]
            if not len(todo):
                break
        res_all = np.abs(res_signed)
        keep = res_all < 3.0 * _row_medians(res_all, keep)[:, None] + FIT_OUTLIER_MARGIN
    return params, _row_medians(res_all, np.ones_like(keep))


def _row_medians(values: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """(K,) the median of each row of ``values`` (K, N) over its ``mask``ed entries.

    ``np.median(values[k][mask[k]])``, the same numbers, each from a partition of its row
    (faster than one sort of all the rows for every K the fits take); NaN if none.
    """
    rows = zip(values, mask, strict=True)
    return np.array([median(v[m]) if m.any() else np.nan for v, m in rows])
