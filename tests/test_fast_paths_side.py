"""The side view's fast paths (issue 24) against the plain formulas, to the bit (the
cylinder fits: within FIT_TOLERANCE).

Only the pixels that may lie between the jaws are lifted to 3-D, and the cylinder fit takes
every residual on all the points once; the candidates, their points and the fits must be
what the whole image and the plain loop give (benchmarks/compare_runs.py checks whole runs,
benchmarks/bench_perception.py recorded episodes' frames).
"""

from __future__ import annotations

import cv2
import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from comgrasp_pin.camera import PinholeCamera
from comgrasp_pin.perception._points import median, points_at, points_in, slice_percentiles
from comgrasp_pin.perception.side_view.cylinder_fit import cylinder_residuals, fit_cylinders
from comgrasp_pin.perception.side_view.held_region import (
    REACH,
    SLAB_HALF_WIDTH,
    TABLE_MARGIN,
    gripper_volume,
    held_candidates,
    in_capsule,
    robot_volume,
    slab_pixels,
)
from comgrasp_pin.perception.side_view.rod_axis import (
    FIT_DAMPING,
    FIT_ITERATIONS,
    FIT_OUTLIER_MARGIN,
    FIT_STEPS,
    MAX_FIT_POINTS,
    MAX_Y_SHIFT,
    RADIUS_GIVE,
    _cylinder_residuals,
    fit_cylinder,
)

CAMERA = PinholeCamera.from_fovy(64, 48, 58.0)


def _pose(rotvec, shift) -> np.ndarray:
    T = np.eye(4)
    T[:3, :3] = cv2.Rodrigues(np.array(rotvec, float).reshape(3, 1))[0]
    T[:3, 3] = shift
    return T


def _depth(seed: int, lost: float) -> np.ndarray:
    """A side camera's view: a near rod across a farther background, pixels lost (0, inf)."""
    rng = np.random.default_rng(seed)
    depth = rng.uniform(0.2, 1.2, CAMERA.height)[:, None] + rng.uniform(0.0, 0.3, CAMERA.width)
    depth[20:28, 5:60] = rng.uniform(0.25, 0.4, (8, 55))
    gone = rng.random(depth.shape) < lost
    depth[gone] = np.where(rng.random(depth.shape) < 0.5, 0.0, np.inf)[gone]
    return depth


def plain_in_capsule(p, p0, p1, radius):
    """Within ``radius`` of the segment p0-p1: every point measured."""
    d = p1 - p0
    t = np.clip(np.nan_to_num((p - p0) @ d / max(d @ d, 1e-12), nan=0.0), 0.0, 1.0)
    dist = np.linalg.norm(p - p0 - t[..., None] * d, axis=-1)
    return np.nan_to_num(dist, nan=np.inf) < radius


def plain_excluded(capsules):
    """The robot's volume with every point measured against every capsule."""

    def excluded(pts):
        inside = gripper_volume(pts)
        for p0, p1, radius in capsules:
            inside |= plain_in_capsule(pts, p0, p1, radius)
        return inside

    return excluded


def plain_candidates(depth, T_ee_cam, T_world_ee, table_z, excluded):
    """The candidates as the side view took them before: the whole image lifted."""
    p = points_in(T_ee_cam, depth, CAMERA)
    candidate = np.isfinite(p[..., 0]) & (np.abs(p[..., 1]) < SLAB_HALF_WIDTH)
    candidate &= np.linalg.norm(np.nan_to_num(p, nan=1e3), axis=-1) < REACH
    if T_world_ee is not None and table_z is not None:
        z_world = np.nan_to_num(p, nan=1e3) @ T_world_ee[2, :3] + T_world_ee[2, 3]
        candidate &= z_world > table_z + TABLE_MARGIN
    idx = np.flatnonzero(candidate)
    candidate.flat[idx[excluded(p.reshape(-1, 3)[idx])]] = False
    return p, candidate


@settings(max_examples=150, deadline=None)
@given(
    rotvec=st.lists(st.floats(-3.0, 3.0), min_size=3, max_size=3),
    shift=st.lists(st.floats(-0.4, 0.4), min_size=3, max_size=3),
    lost=st.floats(0.0, 0.5),
    n=st.integers(0, 40),
    seed=st.integers(0, 2**32 - 1),
)
def test_points_at_are_the_whole_images_points_to_the_bit(rotvec, shift, lost, n, seed):
    depth = _depth(seed, lost)
    T = _pose(rotvec, shift)
    valid = np.flatnonzero(np.isfinite(depth) & (depth > 0))
    pixels = np.sort(np.random.default_rng(seed).permutation(valid)[:n])  # 0, 1, 2 rows too
    expected = points_in(T, depth, CAMERA).reshape(-1, 3)[pixels]
    assert np.array_equal(points_at(T, depth, CAMERA, pixels), expected)


@settings(max_examples=150, deadline=None)
@given(
    rotvec=st.lists(st.floats(-3.0, 3.0), min_size=3, max_size=3),
    shift=st.lists(st.floats(-0.35, 0.35), min_size=3, max_size=3),
    lost=st.floats(0.0, 0.5),
    table=st.booleans(),
    capsule=st.booleans(),
    seed=st.integers(0, 2**32 - 1),
)
def test_held_candidates_are_the_whole_images_to_the_bit(rotvec, shift, lost, table, capsule,
                                                        seed):  # fmt: skip
    depth = _depth(seed, lost)
    T_ee_cam = _pose(rotvec, shift)
    T_world_ee = _pose([0.1, 3.0, 0.2], [0.5, 0.0, 0.4]) if table else None
    capsules = [(np.array([0.0, 0.0, -0.2]), np.array([0.1, 0.05, -0.3]), 0.06)] if capsule else []
    plain, excluded = plain_excluded(capsules), robot_volume(capsules)
    p_plain, expected = plain_candidates(depth, T_ee_cam, T_world_ee, 0.02, plain)
    p, candidate = held_candidates(depth, CAMERA, T_ee_cam, T_world_ee, 0.02, excluded)
    assert np.array_equal(candidate, expected)
    assert np.array_equal(p[candidate], p_plain[candidate])
    slab = np.isfinite(p_plain[..., 1]) & (np.abs(p_plain[..., 1]) < SLAB_HALF_WIDTH)
    lifted = np.zeros(depth.size, bool)
    lifted[slab_pixels(T_ee_cam, depth, CAMERA)] = True
    assert not np.any(slab.reshape(-1) & ~lifted)  # every pixel in the slab is lifted


def plain_fit(points, direction, point, radius=None, free_y=False):
    """The cylinder fit as it was before issue 24: the inliers copied, the cost taken on
    them, every point's residual again after each step."""
    points = points[:: max(1, len(points) // MAX_FIT_POINTS)]
    y2_all = None if free_y else points[:, 1] * points[:, 1]
    angle = np.arctan2(direction[1], direction[0])
    normal = np.array([-direction[1], direction[0]])
    params = np.array([angle, point @ normal, 0.0, 0.0] if free_y else [angle, point @ normal, 0.0])
    params[2] = np.median(_cylinder_residuals(params, points, y2_all)) if radius is None else radius
    free = [0, 1] + ([] if radius is not None else [2]) + ([3] if free_y else [])
    keep = np.ones(len(points), dtype=bool)
    res = _cylinder_residuals(params, points, y2_all)
    for _ in range(FIT_ITERATIONS):
        kept = points[keep]
        y2 = None if y2_all is None else y2_all[keep]
        jac = np.empty((len(res), len(free)))
        for k, i in enumerate(free):
            step = np.zeros(len(params))
            step[i] = FIT_STEPS[i]
            jac[:, k] = (_cylinder_residuals(params + step, kept, y2) - res) / FIT_STEPS[i]
        jtj, jtr = jac.T @ jac, jac.T @ res
        cost = np.sum(res**2)
        for damping in FIT_DAMPING:
            delta = np.linalg.solve(jtj + damping * np.diag(np.diag(jtj)), jtr)
            trial = params.copy()
            trial[free] -= delta
            if np.sum(_cylinder_residuals(trial, kept, y2) ** 2) < cost:
                params = trial
                break
        res_signed = _cylinder_residuals(params, points, y2_all)
        res_all = np.abs(res_signed)
        keep = res_all < 3.0 * median(res_all[keep]) + FIT_OUTLIER_MARGIN
        res = res_signed[keep]
    return params, float(median(res_all))


def _handle(n, radius, tilt, outliers, seed):
    """A handle's visible surface (N, 3) with heads and weights off it, and a slice line."""
    rng = np.random.default_rng(seed)
    u = np.array([np.cos(tilt), 0.0, np.sin(tilt)])
    normal = np.array([-np.sin(tilt), 0.0, np.cos(tilt)])
    along, phi = rng.uniform(-0.15, 0.15, n), rng.uniform(-1.3, 1.3, n)
    pts = along[:, None] * u + radius * (np.cos(phi)[:, None] * [0.0, 1.0, 0.0]
                                         + np.sin(phi)[:, None] * normal)  # fmt: skip
    pts += rng.normal(0.0, 3e-4, pts.shape)
    far = rng.random(n) < outliers  # heads and weights off the handle
    pts[far] += rng.normal(0.0, 0.02, (np.count_nonzero(far), 3))
    direction = np.array([np.cos(tilt + 0.05), np.sin(tilt + 0.05)])
    return pts, direction, rng.normal(0.0, 0.003, 2)


def _expected(params, misfit, free_y):
    u = np.array([np.cos(params[0]), np.sin(params[0])])
    u = -u if u[0] < 0 else u
    offset = params[1] * np.array([-np.sin(params[0]), np.cos(params[0])])
    return u, offset, np.inf if free_y and abs(params[3]) > MAX_Y_SHIFT else misfit


# The batched fit sums over masked rows of a product and measures in the x-z plane: the
# last digits move, and an ill-posed fit (a free radius on a few dozen points, a third of
# them outliers) amplifies them (1.2e-9 seen); within FIT_TOLERANCE of the plain loop's, in
# m and rad: the bound on every perception output (recorded views: 1.3e-9 at most).
FIT_TOLERANCE = 1e-6


@settings(max_examples=100, deadline=None)
@given(
    n=st.integers(30, 4000),
    radius=st.floats(0.003, 0.03),
    tilt=st.floats(-1.2, 1.2),
    outliers=st.floats(0.0, 0.4),
    known=st.sampled_from(["known", "free", "free_y"]),
    seed=st.integers(0, 2**32 - 1),
)
def test_cylinder_fit_is_the_plain_loops(n, radius, tilt, outliers, known, seed):
    pts, direction, point = _handle(n, radius, tilt, outliers, seed)
    rng = np.random.default_rng(seed + 1)
    r = None if known == "free" else radius + rng.normal(0.0, 5e-4)
    free_y = known == "free_y"
    expected = _expected(*plain_fit(pts, direction, point, r, free_y), free_y)
    for got, want in zip(fit_cylinder(pts, direction, point, r, free_y), expected, strict=True):
        np.testing.assert_allclose(got, want, rtol=0.0, atol=FIT_TOLERANCE)


@settings(max_examples=60, deadline=None)
@given(
    n=st.integers(30, 4000),
    radius=st.floats(0.003, 0.03),
    tilt=st.floats(-1.2, 1.2),
    outliers=st.floats(0.0, 0.4),
    free_y=st.booleans(),
    seed=st.integers(0, 2**32 - 1),
)
def test_batched_cylinder_fits_are_each_candidates_own(n, radius, tilt, outliers, free_y, seed):
    """Several radii at once (refine_axis' candidates): each fit as the plain loop fits it
    alone, with its own inliers, damping and steps."""
    pts, direction, point = _handle(n, radius, tilt, outliers, seed)
    radii = [radius - 5e-4 + dr for dr in (0.0, *RADIUS_GIVE)]
    fits = fit_cylinders(pts, direction, point, radii, free_y)
    assert len(fits) == len(radii)
    for fit, r in zip(fits, radii, strict=True):
        expected = _expected(*plain_fit(pts, direction, point, r, free_y), free_y)
        for got, want in zip(fit, expected, strict=True):
            np.testing.assert_allclose(got, want, rtol=0.0, atol=FIT_TOLERANCE)


@settings(max_examples=200, deadline=None)
@given(
    n=st.integers(1, 300),
    angle=st.floats(-3.2, 3.2),
    offset=st.floats(-0.05, 0.05),
    radius=st.floats(0.0, 0.03),
    y_offset=st.one_of(st.none(), st.floats(-0.004, 0.004)),
    seed=st.integers(0, 2**32 - 1),
)
def test_batched_residuals_are_the_plain_formula(n, angle, offset, radius, y_offset, seed):
    pts = np.random.default_rng(seed).normal(0.0, 0.05, (n, 3))
    prm = np.array([angle, offset, radius] + ([] if y_offset is None else [y_offset]))
    y = pts[:, 1] if y_offset is not None else pts[:, 1] ** 2
    got = cylinder_residuals(np.array([prm, prm]), np.ascontiguousarray(pts[:, [0, 2]].T), y)
    np.testing.assert_allclose(got[1], _cylinder_residuals(prm, pts), rtol=0.0, atol=1e-15)
    assert np.array_equal(got[0], got[1])


def test_held_candidates_of_a_side_cameras_view_to_the_bit():
    """The camera 0.31 m beside the jaws looking across them, as on the gripper: a rod in
    the slab, a background beyond it, lost pixels; with the table and an arm capsule."""
    T_ee_cam = np.eye(4)
    T_ee_cam[:3, :3] = [[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]]
    T_ee_cam[:3, 3] = [0.0, -0.31, -0.05]
    T_world_ee = _pose([np.pi, 0.0, 0.0], [0.5, 0.0, 0.3])
    capsules = [(np.array([-0.05, 0.0, 0.0]), np.array([-0.05, 0.05, -0.2]), 0.03)]
    excluded, plain = robot_volume(capsules), plain_excluded(capsules)
    for seed in range(20):
        depth = _depth(seed, 0.05 * (seed % 4))
        p_plain, expected = plain_candidates(depth, T_ee_cam, T_world_ee, -0.2, plain)
        p, candidate = held_candidates(depth, CAMERA, T_ee_cam, T_world_ee, -0.2, excluded)
        assert np.count_nonzero(expected) > 100
        assert np.count_nonzero(plain(p_plain[np.isfinite(p_plain[..., 0])])) > 10
        assert np.array_equal(candidate, expected)
        assert np.array_equal(p[candidate], p_plain[candidate])


@settings(max_examples=100, deadline=None)
@given(
    rotvec=st.lists(st.floats(-3.0, 3.0), min_size=3, max_size=3),
    shift=st.lists(st.floats(-2.0, 2.0), min_size=3, max_size=3),
    lost=st.floats(0.0, 0.9),
    seed=st.integers(0, 2**32 - 1),
)
def test_points_in_is_depth_to_points_then_the_transform_to_the_bit(rotvec, shift, lost, seed):
    """Both views' whole-image lifting, the rays' slopes once per column and row."""
    from comgrasp_pin.camera import transform_points

    depth = _depth(seed, lost)
    T = _pose(rotvec, shift)
    valid = np.isfinite(depth) & (depth > 0)
    plain = CAMERA.depth_to_points(np.where(valid, depth, 1.0))
    plain = transform_points(T, plain.reshape(-1, 3)).reshape(plain.shape)
    plain[~valid] = np.nan
    np.testing.assert_array_equal(points_in(T, depth, CAMERA), plain)


@settings(max_examples=150, deadline=None)
@given(
    n=st.integers(0, 300),
    ends=st.lists(st.floats(-0.3, 0.3), min_size=6, max_size=6),
    radius=st.floats(0.0, 0.2),
    lost=st.floats(0.0, 0.3),
    seed=st.integers(0, 2**32 - 1),
)
def test_in_capsule_measures_only_its_box_to_the_same_answer(n, ends, radius, lost, seed):
    rng = np.random.default_rng(seed)
    p0, p1 = np.array(ends[:3]), np.array(ends[3:])
    pts = rng.uniform(-0.5, 0.5, (n, 3))
    pts[rng.random(n) < lost] = np.nan  # pixels with no depth
    assert np.array_equal(in_capsule(pts, p0, p1, radius), plain_in_capsule(pts, p0, p1, radius))
    one = pts[:1]  # a single point (an end's peek beyond the rod)
    assert np.array_equal(in_capsule(one, p0, p1, radius), plain_in_capsule(one, p0, p1, radius))


@settings(max_examples=200, deadline=None)
@given(
    k=st.integers(1, 12),
    n=st.integers(1, 300),
    keep=st.floats(0.0, 1.0),
    seed=st.integers(0, 2**32 - 1),
)
def test_row_medians_are_each_rows_median_to_the_bit(k, n, keep, seed):
    from comgrasp_pin.perception.side_view.cylinder_fit import _row_medians

    rng = np.random.default_rng(seed)
    values = np.abs(rng.normal(0.0, 1e-3, (k, n)))
    values[:, : n // 3] = values[0, 0]  # ties
    mask = rng.random((k, n)) < keep
    got = _row_medians(values, mask)
    for row, m, g in zip(values, mask, got, strict=True):
        assert (np.isnan(g) and not m.any()) or g == np.median(row[m])


@settings(max_examples=200, deadline=None)
@given(st.integers(1, 400), st.integers(1, 12), st.integers(1, 8), st.integers(0, 2**31 - 1),
       st.sampled_from([(2, 98), (10, 90), (0.1, 99.9), (50,), (0, 100)]))  # fmt: skip
def test_slice_percentiles_are_each_slices_to_the_bit(n, n_bins, min_count, seed, percentiles):
    rng = np.random.default_rng(seed)
    bins = rng.integers(-n_bins, n_bins, n)
    values = rng.normal(0.0, 0.01, n)
    values[rng.random(n) < 0.1] = 0.0  # ties
    full = [b for b in np.unique(bins) if (bins == b).sum() >= min_count]
    counts, ends = slice_percentiles(bins, values, percentiles, min_count)
    assert counts.tolist() == [(bins == b).sum() for b in full]
    assert ends.shape == (len(full), len(percentiles))
    for b, row in zip(full, ends, strict=True):
        assert row.tolist() == np.percentile(values[bins == b], percentiles).tolist()
