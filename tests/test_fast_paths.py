"""The fast paths of perception and of the simulated cameras against the plain formulas (issue 16).

Each speed change must leave every result as it was, to the bit, so that a run's rows stay
the same for the same seeds (benchmarks/compare_runs.py checks whole runs). The plain
formulas are written out here, independently of the package's code, and compared on
random inputs (hypothesis) and on the corner cases: lost pixels (0, inf), image borders,
pixels with no valid neighbour, a free y offset.
"""

from __future__ import annotations

import warnings

import cv2
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from comgrasp_pin.config import sensor_preset
from comgrasp_pin.perception._points import drop_flying, median, slice_medians
from comgrasp_pin.perception.side_view.rod_axis import _cylinder_residuals
from comgrasp_pin.simulation.depth_noise import DepthNoise


def plain_cylinder_residuals(prm: np.ndarray, pts: np.ndarray) -> np.ndarray:
    """Distance of each point from the axis (angle prm[0] in x-z, offset prm[1] along its
    normal, optional y offset prm[3]), less the radius prm[2]: the textbook formula."""
    u = np.array([np.cos(prm[0]), 0.0, np.sin(prm[0])])
    n = np.array([-np.sin(prm[0]), 0.0, np.cos(prm[0])])
    rel = pts - prm[1] * n
    if len(prm) > 3:
        rel = rel - np.array([0.0, prm[3], 0.0])
    return np.linalg.norm(rel - np.outer(rel @ u, u), axis=1) - prm[2]


def plain_drop_flying(depth: np.ndarray, tolerance: float) -> np.ndarray:
    """Flying pixels lost, with the NaN-aware reductions over a stack of the 8 neighbours."""
    valid = np.isfinite(depth) & (depth > 0)
    padded = np.pad(np.where(valid, depth, np.nan), 1, constant_values=np.nan)
    h, w = depth.shape
    stack = np.stack([padded[1 + dy : 1 + dy + h, 1 + dx : 1 + dx + w]
                      for dy in (-1, 0, 1) for dx in (-1, 0, 1) if dy or dx])  # fmt: skip
    d = np.where(valid, depth, np.nan)
    with np.errstate(invalid="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        near, far = np.nanmin(stack, axis=0), np.nanmax(stack, axis=0)
        closest = np.nanmin(np.abs(stack - d), axis=0)
    flying = (d - near > tolerance) & (far - d > tolerance) & (closest > tolerance)
    out = depth.copy()
    out[valid & flying] = 0.0
    return out


@settings(max_examples=200, deadline=None)
@given(
    n=st.integers(1, 4000),
    angle=st.floats(-3.2, 3.2),
    offset=st.floats(-0.05, 0.05),
    radius=st.floats(0.0, 0.03),
    y_offset=st.one_of(st.none(), st.floats(-0.004, 0.004)),
    seed=st.integers(0, 2**32 - 1),
)
def test_cylinder_residuals_are_the_plain_formula_to_the_bit(n, angle, offset, radius,
                                                             y_offset, seed):  # fmt: skip
    pts = np.random.default_rng(seed).normal(0.0, 0.05, (n, 3))
    prm = np.array([angle, offset, radius] + ([] if y_offset is None else [y_offset]))
    expected = plain_cylinder_residuals(prm, pts)
    assert np.array_equal(_cylinder_residuals(prm, pts), expected)
    if y_offset is None:  # the points' y squared, given once per fit
        assert np.array_equal(_cylinder_residuals(prm, pts, pts[:, 1] ** 2), expected)
    keep = np.random.default_rng(seed + 1).random(n) < 0.6  # a point's residual is its own
    assert np.array_equal(_cylinder_residuals(prm, pts)[keep], expected[keep])
    assert np.array_equal(plain_cylinder_residuals(prm, pts[keep]), expected[keep])


@settings(max_examples=200, deadline=None)
@given(
    h=st.integers(1, 40),
    w=st.integers(1, 40),
    lost=st.floats(0.0, 0.9),
    steps=st.floats(0.0, 0.5),
    tolerance=st.sampled_from([0.0, 0.002, 0.01, 0.05]),
    seed=st.integers(0, 2**32 - 1),
)
def test_drop_flying_is_the_stacked_reduction_to_the_bit(h, w, lost, steps, tolerance, seed):
    rng = np.random.default_rng(seed)
    depth = rng.uniform(0.3, 0.6, (h, w))
    depth[rng.random((h, w)) < steps] += 0.1  # edges between two surfaces
    depth[rng.random((h, w)) < 0.3 * steps] -= 0.05  # and pixels between them
    gone = rng.random((h, w)) < lost
    depth[gone] = np.where(rng.random((h, w)) < 0.5, 0.0, np.inf)[gone]
    assert np.array_equal(drop_flying(depth, tolerance), plain_drop_flying(depth, tolerance))


def test_drop_flying_loses_a_pixel_between_two_surfaces():
    depth = np.full((5, 6), 0.5)
    depth[:, 3:] = 0.6
    depth[2, 3] = 0.55  # a stereo camera's mix of the two sides
    out = drop_flying(depth, 0.01)
    assert out[2, 3] == 0.0
    assert np.count_nonzero(out == 0.0) == 1


@settings(max_examples=200, deadline=None)
@given(n=st.integers(1, 3000), width=st.integers(1, 40), seed=st.integers(0, 2**32 - 1))
def test_medians_are_numpys_to_the_bit(n, width, seed):
    rng = np.random.default_rng(seed)
    along, across = rng.normal(0.0, 0.1, n), rng.normal(0.0, 0.01, n)
    assert median(across) == np.median(across)
    bins = np.floor(along / (width * 1e-3)).astype(int)
    labels, medians = slice_medians(bins, (along, across), 5)
    expected = [b for b in np.unique(bins) if np.count_nonzero(bins == b) >= 5]
    assert labels.tolist() == expected
    assert medians.shape == (len(expected), 2)
    for row, b in zip(medians, expected, strict=True):
        assert row[0] == np.median(along[bins == b]) and row[1] == np.median(across[bins == b])


def _step_scene(rng: np.random.Generator, shape=(240, 320)) -> np.ndarray:
    """A tilted plane at 0.45-0.49 m with a nearer block on it whose edges fall at random
    sub-pixel places (m)."""
    h, w = shape
    v, u = np.mgrid[0:h, 0:w]
    depth = 0.45 + 0.04 * u / w + 0.01 * v / h
    left, top = rng.uniform(60, 90), rng.uniform(50, 80)
    block = (u > left) & (u < left + rng.uniform(100, 140)) & (v > top) & (v < top + 90)
    depth[block] = 0.35
    return depth


@pytest.mark.parametrize("stride", [2, 3])
def test_depth_noise_drawn_for_every_stride_th_pixel_alone_has_the_full_images_statistics(stride):
    """A slip watch's frame: the errors drawn for every stride-th pixel alone (the render
    holds only them) against the full image's errors taken at the same pixels, over 60
    frames of scenes whose edges fall anywhere: the same axial noise (RMS and the
    correlation of neighbours, from the Gaussian's sigma derived here), the same share of
    lost and flying pixels at the block's edges, the same random dropouts."""
    config = sensor_preset("realistic").side_depth
    stats = {"full": [], "strided": []}
    for seed in range(60):
        depth = _step_scene(np.random.default_rng(seed))
        sampled = depth[::stride, ::stride]
        whole = DepthNoise(config, seed=seed).apply(depth)[::stride, ::stride]
        alone = DepthNoise(config, seed=seed + 1000).apply(sampled, stride)
        block = sampled == 0.35
        plane = (sampled > 0.4) & (cv2.dilate(block.astype(np.uint8), np.ones((5, 5))) == 0)
        for name, out in (("full", whole), ("strided", alone)):
            ok = plane & np.isfinite(out) & (out > 0)
            dz = out - sampled
            right = ok[:, :-1] & ok[:, 1:]
            pair = np.corrcoef(dz[:, :-1][right], dz[:, 1:][right])[0, 1]
            near_edge = block ^ (cv2.erode(block.astype(np.uint8), np.ones((3, 3))) > 0)
            lost_at_edge = np.count_nonzero((out == 0) & near_edge) / np.count_nonzero(near_edge)
            dropped = np.count_nonzero(((out == 0) | np.isinf(out)) & plane) / plane.sum()
            stats[name].append((dz[ok].std(), pair, lost_at_edge, dropped))
    full, strided = np.mean(stats["full"], axis=0), np.mean(stats["strided"], axis=0)
    sigma = config.axial_std(0.47)
    assert abs(full[0] - strided[0]) < 0.03 * sigma  # RMS of the axial noise and 1 mm steps
    # Neighbours stride camera pixels apart: a Gaussian blur of sigma s correlates white noise
    # at lag d by exp(-d^2 / (4 s^2)), 0.37 at stride 2 and 0.11 at stride 3 (s = 1 px; the
    # 1 mm steps and the plane's slope take a little off).
    expected = np.exp(-(stride**2) / (4 * config.noise_corr_px**2))
    assert abs(full[1] - strided[1]) < 0.03 and abs(strided[1] - expected) < 0.06
    # The edge band is one camera pixel either side of a step: a sampled pixel next to one
    # lies in it with probability 1 / stride; half of those are lost.
    assert abs(full[2] - 0.5 / stride) < 0.05 and abs(full[2] - strided[2]) < 0.1 * full[2]
    assert abs(full[3] - strided[3]) < 0.1 * config.dropout_prob


@settings(max_examples=100, deadline=None)
@given(
    n=st.integers(1, 5000),
    rotvec=st.lists(st.floats(-3.0, 3.0), min_size=3, max_size=3),
    shift=st.lists(st.floats(-2.0, 2.0), min_size=3, max_size=3),
    seed=st.integers(0, 2**32 - 1),
)
def test_transform_points_is_the_plain_product_to_the_bit(n, rotvec, shift, seed):
    """``transform_points``, which adds the translation in place, is p @ R^T + t written
    out, to the bit: on random points and on a whole image's worth of depths."""
    import cv2

    from comgrasp_pin.camera import transform_points

    T = np.eye(4)
    T[:3, :3] = cv2.Rodrigues(np.array(rotvec, float).reshape(3, 1))[0]
    T[:3, 3] = shift
    p = np.random.default_rng(seed).uniform(-3.0, 3.0, (n, 3))
    np.testing.assert_array_equal(transform_points(T, p), p @ T[:3, :3].T + T[:3, 3])
    image = np.random.default_rng(seed).uniform(0.1, 2.0, (480 * 640, 3))  # a whole image
    np.testing.assert_array_equal(transform_points(T, image), image @ T[:3, :3].T + T[:3, 3])


def plain_differs_in_colour(rgb: np.ndarray, area: np.ndarray) -> np.ndarray:
    """The colour test as it was: CIELAB distances in floats, thresholds on the norms."""
    from comgrasp_pin.perception.top_view.table_view import COLOUR_DE, SHADOW_CHROMA

    lab = cv2.cvtColor(np.ascontiguousarray(rgb, dtype=np.uint8), cv2.COLOR_RGB2LAB).astype(float)
    table = np.median(lab[area], axis=0)
    distance = np.linalg.norm(lab - table, axis=2)
    chroma = np.linalg.norm(lab[..., 1:] - table[1:], axis=2)
    shadow = (chroma < SHADOW_CHROMA) & (lab[..., 0] < table[0])
    return (distance > COLOUR_DE) & ~shadow


@settings(max_examples=200, deadline=None)
@given(
    h=st.integers(2, 40),
    w=st.integers(2, 40),
    spread=st.integers(0, 80),
    seed=st.integers(0, 2**32 - 1),
)
def test_differs_in_colour_is_the_plain_norms_to_the_bit(h, w, spread, seed):
    """Integer distances in half units against the float norms: the same pixels, also
    those exactly at a threshold (small spreads put many there)."""
    from comgrasp_pin.perception.top_view.table_view import differs_in_colour

    rng = np.random.default_rng(seed)
    base = rng.integers(0, 256, 3)
    rgb = np.clip(base + rng.integers(-spread, spread + 1, (h, w, 3)), 0, 255).astype(np.uint8)
    area = rng.random((h, w)) < 0.7
    area.flat[0] = True
    assert np.array_equal(differs_in_colour(rgb, area), plain_differs_in_colour(rgb, area))


def plain_fill_holes(depth: np.ndarray, max_gap_px: float = 2.5) -> np.ndarray:
    """Holes filled from the nearest valid pixel, each label's depth looked up by label."""
    valid = np.isfinite(depth) & (depth > 0)
    if valid.all():
        return depth
    dist, labels = cv2.distanceTransformWithLabels(
        (~valid).astype(np.uint8), cv2.DIST_L2, 5, labelType=cv2.DIST_LABEL_PIXEL
    )
    values = np.zeros(int(labels.max()) + 1)
    values[labels[valid]] = depth[valid]
    filled = np.where(valid, depth, np.inf)
    near = ~valid & (dist <= max_gap_px)
    filled[near] = values[labels[near]]
    return filled


@settings(max_examples=200, deadline=None)
@given(
    h=st.integers(1, 60),
    w=st.integers(1, 60),
    lost=st.floats(0.0, 1.0),
    seed=st.integers(0, 2**32 - 1),
)
def test_fill_holes_is_the_label_lookup_to_the_bit(h, w, lost, seed):
    from comgrasp_pin.perception._points import fill_holes

    rng = np.random.default_rng(seed)
    depth = rng.uniform(0.2, 2.0, (h, w))
    gone = rng.random((h, w)) < lost
    depth[gone] = np.where(rng.random((h, w)) < 0.5, 0.0, np.inf)[gone]
    assert np.array_equal(fill_holes(depth), plain_fill_holes(depth))


@settings(max_examples=300, deadline=None)
@given(
    n=st.integers(0, 200),
    zeros=st.floats(0.0, 1.0),
    seed=st.integers(0, 2**32 - 1),
)
def test_noise_level_of_mostly_zero_heights_is_the_plain_mad(n, zeros, seed):
    """The shortcut for more than half exactly 0 (clean renders) gives np.median's MAD."""
    from comgrasp_pin.perception._points import noise_level

    rng = np.random.default_rng(seed)
    heights = rng.normal(0.0, 1e-3, n)
    heights[rng.random(n) < zeros] = 0.0
    heights[rng.random(n) < 0.05] = -0.0
    heights[rng.random(n) < 0.05] = np.inf
    finite = heights[np.isfinite(heights)]
    plain = float(1.4826 * np.median(np.abs(finite - np.median(finite)))) if len(finite) else 0.0
    assert noise_level(heights) == plain
