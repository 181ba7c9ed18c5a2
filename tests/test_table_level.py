"""The table's level and what the colour adds: the same answer wherever the pick area lies.

Issue 44: a depth given in mm steps (every RealSense, every ROS depth image, the
structured-light frames of benchmarks/unseen) puts the table's heights in clusters, and
their median sat on one of them: moving the pick area by 3 cm moved the table's level by a
whole mm, which turned obj1's 1 cm handle from "two tops" into a rod. And a colour image
10 px off its depth shows the table's edge as a band of another colour at the table's
height: where the area took that edge in, the band was counted as the object. The level is
now the mean of the middle half (``table_view.table_level``); what only the colour marks
and does not stand is no object (``standing.without_marks``).
"""

import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from comgrasp_pin.errors import ObjectNotFoundError, PerceptionError
from comgrasp_pin.perception.standing import without_marks
from comgrasp_pin.perception.table_view import table_level
from comgrasp_pin.perception.top_down import PICK_AREA
from comgrasp_pin.simulation.depth_noise import DepthNoise

sys.path.append(str(Path(__file__).resolve().parents[1] / "benchmarks"))
from unseen import real_failures as rf  # noqa: E402  (benchmarks/unseen/)

STEP = 0.001  # m, a depth image's unit


@settings(max_examples=60, deadline=None)
@given(arrays(np.float64, st.integers(1, 300), elements=st.floats(-1.0, 1.0)))
def test_the_level_is_the_mean_of_the_sorted_middle_half(heights):
    n = len(heights)
    middle = np.sort(heights)[n // 4 : n - n // 4]
    assert table_level(heights.copy()) == pytest.approx(np.mean(middle), rel=0, abs=1e-15)


def test_a_clean_table_gives_its_height_to_the_bit():
    heights = np.full(1000, 0.7123456789)
    heights[:200] += np.linspace(0.001, 0.05, 200)  # what stands on it, under a quarter
    assert table_level(heights) == 0.7123456789


def test_quantised_heights_move_the_level_by_a_fraction_of_a_step():
    """Areas sliding over a table seen 0.4 mm tilted, each sharing 96 % of its pixels with
    the next: the median jumps by a whole step, the level follows the table's own mean."""
    rng = np.random.default_rng(3)
    true = np.linspace(0.0023, 0.0027, 60_000)  # along the table; half-way between steps
    heights = np.round((true + rng.normal(0.0, 0.0015, true.size)) / STEP) * STEP
    areas = [slice(k, k + 50_000) for k in range(0, 10_001, 2_000)]
    medians = [np.median(heights[a]) for a in areas]
    levels = [table_level(heights[a]) for a in areas]
    assert max(medians) - min(medians) >= 0.9 * STEP  # the failure this guards against
    np.testing.assert_allclose(levels, [np.mean(true[a]) for a in areas], rtol=0,
                               atol=0.05 * STEP)  # fmt: skip
    assert max(np.abs(np.diff(levels))) < 0.05 * STEP


def test_what_stands_on_the_table_moves_the_level_as_little_as_the_median():
    """A tenth of the pixels on a rod 3 cm high: both shift by about 0.14 noise stds
    (the quantile of 0.5 / 0.9 of a Gaussian), neither more than a quarter."""
    rng = np.random.default_rng(4)
    sigma = 0.002
    heights = rng.normal(0.0, sigma, 100_000)
    heights[:10_000] = 0.03
    assert abs(table_level(heights)) < 0.25 * sigma
    assert abs(np.median(heights)) < 0.25 * sigma


def _band_and_rod(rod_height: float):
    """(standing, inside, in_depth, height): a noisy table, a rod, and a 3000 px band of
    another colour at the table's height (the table's edge in a shifted colour image)."""
    rng = np.random.default_rng(5)
    height = rng.normal(0.0, 0.002, (240, 320))
    rod = np.zeros(height.shape, bool)
    rod[100:112, 60:240] = True
    band = np.zeros_like(rod)
    band[20:30, 10:310] = True
    height[rod] += rod_height
    in_depth = rod & (height > 0.005)
    return rod | band, np.ones_like(rod), in_depth, height, rod, band


def test_a_band_of_colour_at_the_tables_height_is_no_object():
    standing, inside, in_depth, height, rod, band = _band_and_rod(0.02)
    kept = without_marks(standing, inside, in_depth, height, 0.005)
    assert not (kept & band).any()
    np.testing.assert_array_equal(kept & rod, rod)


def test_a_low_rod_that_only_the_colour_marks_stands_by_its_median():
    """4 mm: under a pixel's threshold (5 mm), above the least a blob must stand (3 mm)."""
    standing, inside, _, height, rod, band = _band_and_rod(0.004)
    kept = without_marks(standing, inside, np.zeros_like(rod), height, 0.005)
    np.testing.assert_array_equal(kept, rod)


def test_only_marks_are_refused_as_marks():
    standing, inside, _, height, rod, band = _band_and_rod(0.0)
    with pytest.raises(ObjectNotFoundError, match="a mark or a shadow"):
        without_marks(band, inside, np.zeros_like(rod), height, 0.005)


@pytest.fixture(scope="module", params=["cylinder_10px_v_structured_light_shadow",
                                        "obj1_10mm_handle_structured_light_shadow"])  # fmt: skip
def formerly_differing(request):
    """Frames (their noise's third draw) answered differently in one of the moved areas."""
    frame = next(f for f in rf.frames(0, False) if f.parameter == request.param)
    rgb, depth, camera, T_world_cam = rf._Renders()(frame.scene)
    rgb = rf.shift_colour(rgb, *frame.shift_px)
    depth = DepthNoise(rf.STRUCTURED_LIGHT, rf.noise_seed(frame, 0, 2)).apply(depth)
    return rgb, rf.projector_shadow(depth, camera.fx), camera, T_world_cam, frame.truth


def test_one_answer_for_pick_areas_moved_by_3_cm(formerly_differing):
    rgb, depth, camera, T_world_cam, truth = formerly_differing
    x0, x1, y0, y1 = PICK_AREA
    answers = [rf._detect(rgb, depth, camera, T_world_cam, (x0 + dx, x1 + dx, y0 + dy, y1 + dy))
               for dx, dy in ((0, 0), (0.03, 0), (-0.03, 0), (0, 0.03), (0, -0.03))]  # fmt: skip
    assert not any(isinstance(a, PerceptionError) for a in answers), answers
    lengths = [a.length for a in answers]
    assert max(lengths) - min(lengths) <= 0.01, lengths
    for a in answers:
        assert rf.outcome(a, truth)["outcome"] == "right", a
