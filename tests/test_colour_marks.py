"""What only the colour marks and does not stand is no object: one answer wherever the area lies.

Issue 44: a colour image 10 px off its depth (benchmarks/unseen's colour-shift frames) shows
the table's edge as a band of another colour at the table's height. Where a pick area moved
by 3 cm took that edge in, the band was the largest blob: counted as a second object, or
taken for the object. Now the blobs that the colour alone marks and whose median does not
stand above the noise of such a median are dropped first (``standing.without_marks``).
"""

import sys
from pathlib import Path

import numpy as np
import pytest

from comgrasp_pin.errors import ObjectNotFoundError, PerceptionError
from comgrasp_pin.perception.top_view.standing import without_marks
from comgrasp_pin.perception.top_view.top_down import PICK_AREA
from comgrasp_pin.simulation.depth_noise import DepthNoise

sys.path.append(str(Path(__file__).resolve().parents[1] / "benchmarks"))
from unseen import real_failures as rf  # noqa: E402  (benchmarks/unseen/)


def _band_and_rod(rod_height: float):
    """(standing, inside, in_depth, height, rod, band): a noisy table (2 mm), a rod
    ``rod_height`` high, and a 3000 px band of another colour at the table's height (the
    table's edge in a shifted colour image); all (H, W), heights in m."""
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


@pytest.fixture(scope="module")
def formerly_differing():
    """The frame (its noise's third draw) answered differently in one of the moved areas."""
    name = "cylinder_10px_v_structured_light_shadow"
    frame = next(f for f in rf.frames(0, False) if f.parameter == name)
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
