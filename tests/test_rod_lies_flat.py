"""A rod put down propped on its head says so, not "two rods side by side".

After a slip, pick-and-place lays the rod down; its head may come to rest turned on its
side and prop one end up (obj1's weight on its edge: the handle's top rising 10 to 26 mm;
obj7's hammer head on its side: 25 to 87 mm, in the paper-size run's put-downs). The top
view refuses such a rod (its slices seem off the axis), and said "not one rod (rods side by
side, crossing or at an angle?)". ``rod_shape.check_one_rod`` now names a rod whose tops
rise steadily along it as not lying flat; two rods keep their words. The clouds are made
here, on a 1.5 mm grid (about a pixel on the table), their heights known by construction.
"""

import numpy as np
import pytest

from comgrasp_pin.errors import AmbiguousObjectError
from comgrasp_pin.perception.top_view.rod_flat import propped_ends
from comgrasp_pin.perception.top_view.rod_shape import SLICE, check_one_rod

GRID = 0.0015  # m
NOISE = 0.0005  # m


def _rod(along: tuple, across: tuple, top: tuple, round_top: bool = False) -> np.ndarray:
    """(N, 3) points of a rod's top along x (m), across y (m), its top's height rising
    linearly from ``top[0]`` to ``top[1]`` (m) along it; a cylinder's across it where
    ``round_top``."""
    a = np.arange(along[0], along[1] + 1e-9, GRID)
    c = np.arange(across[0], across[1] + 1e-9, GRID)
    x, y = np.meshgrid(a, c)
    z = top[0] + (top[1] - top[0]) * (x - along[0]) / (along[1] - along[0])
    if round_top:
        r, mid = 0.5 * (across[1] - across[0]), 0.5 * (across[0] + across[1])
        z = z - r + np.sqrt(np.maximum(r**2 - (y - mid) ** 2, 0.0))
    return np.c_[x.ravel(), y.ravel(), z.ravel()]


def _turned(degrees: float) -> np.ndarray:
    return np.array([np.cos(np.radians(degrees)), np.sin(np.radians(degrees))])


def test_a_rod_propped_on_its_head_is_refused_as_not_lying_flat():
    """A 36 cm handle whose top rises from 10 to 26 mm, its 4 cm head turned 8 mm off the
    handle's line at the high end; the axis given 2.2 deg off the handle (the principal
    axis of obj1's blob in the run)."""
    handle = _rod((-0.20, 0.16), (-0.005, 0.005), (0.010, 0.026))
    head = _rod((0.16, 0.20), (-0.012, 0.028), (0.040, 0.040))
    p = np.r_[handle, head]
    with pytest.raises(AmbiguousObjectError, match="does not lie flat") as refused:
        check_one_rod(p, p[:, :2].mean(axis=0), _turned(2.2), 0.0, NOISE)
    low, high = (int(w) for w in str(refused.value).split("from ")[1].split(" mm")[0].split(" to "))
    # the handle's line at the first and last slices' middles (5 mm in from the rod's
    # ends, the head's included): 10 + 16 * 0.005 / 0.36 and 10 + 16 * 0.395 / 0.36 mm
    assert abs(low - 10.2) <= 1 and abs(high - 27.6) <= 1
    assert "two rods" not in str(refused.value) and "side by side" not in str(refused.value)


@pytest.mark.parametrize("kind", ["vee", "beside"])
def test_two_rods_keep_their_words(kind):
    """A V of two round 1 cm rods 10 deg apart, and two touching side by side: not one rod,
    whose tops do not rise."""
    one = _rod((0.0, 0.30), (-0.005, 0.005), (0.010, 0.010), round_top=True)
    if kind == "vee":
        c, s = np.cos(np.radians(5)), np.sin(np.radians(5))
        turn = [np.c_[one[:, :2] @ np.array([[c, k * s], [-k * s, c]]), one[:, 2]] for k in (1, -1)]
        p = np.r_[turn[0], turn[1]]
    else:
        p = np.r_[one, one + [0.0, 0.0105, 0.0]]
    centroid = p[:, :2].mean(axis=0)
    direction = np.linalg.svd(p[:, :2] - centroid, full_matrices=False)[2][0]
    with pytest.raises(AmbiguousObjectError, match="not one rod"):
        check_one_rod(p, centroid, direction, 0.0, NOISE)


def test_a_flat_rod_with_a_tall_head_is_one_rod():
    handle = _rod((-0.20, 0.16), (-0.005, 0.005), (0.010, 0.010))
    head = _rod((0.16, 0.20), (-0.020, 0.020), (0.040, 0.040))
    p = np.r_[handle, head]
    centroid = p[:, :2].mean(axis=0)
    check_one_rod(p, centroid, _turned(0.0), 0.0, NOISE)


def test_a_tapered_body_lying_flat_is_not_propped():
    """A round body thickening from 16 to 32 mm along it (a toy shark, a bottle) lies flat:
    its top rises as steadily as a propped handle's, but with its width."""
    along = np.arange(-0.15, 0.15 + 1e-9, GRID)
    points = []
    for x in along:
        r = 0.5 * (0.016 + 0.016 * (x + 0.15) / 0.30)
        for y in np.arange(-r, r + 1e-9, GRID):
            points.append((x, y, r + np.sqrt(max(r**2 - y**2, 0.0))))
    p = np.array(points)
    assert propped_ends(p, np.zeros(2), np.array([1.0, 0.0]), 0.0, NOISE, None, SLICE) is None
    handle = _rod((-0.15, 0.15), (-0.005, 0.005), (0.016, 0.032))
    ends = propped_ends(handle, np.zeros(2), np.array([1.0, 0.0]), 0.0, NOISE, None, SLICE)
    assert ends is not None and abs(ends[1] - ends[0] - 0.016 * 0.29 / 0.30) < 0.001


def _mallet() -> np.ndarray:
    """A mallet's points as a noisy depth measures them: a 5 cm wide head 2 cm high, 4 cm
    along, and the 6 cm of its handle (7 mm high) the depth shows, 2 cm wide and then, where
    the depth loses its sides, 1 cm (as on the real PrimeSense mallet)."""
    head = _rod((0.0, 0.04), (-0.025, 0.025), (0.020, 0.020))
    handle = _rod((0.04, 0.07), (-0.01, 0.01), (0.007, 0.007))
    end = _rod((0.07, 0.10), (-0.005, 0.005), (0.007, 0.007))
    p = np.r_[head, handle, end]
    p[:, 2] += np.random.default_rng(1).normal(0.0, NOISE, len(p))
    return p


def test_a_tools_head_and_handle_pass_only_where_its_rest_is_looked_for():
    """The median profile of a wide head's and a narrow handle's slices has a valley in the
    middle (the handle's slices there, the head's alone at the sides). Without ``heads`` it
    is refused as two rods side by side (a smooth depth: no check looks for the rest of the
    tool); with ``heads`` (a cleaned depth, where the thin-part checks do), its slices'
    heights, 7 against 20 mm, are no two rods alike all along: it passes."""
    p = _mallet()
    centroid, direction = p[:, :2].mean(axis=0), _turned(0.0)
    with pytest.raises(AmbiguousObjectError, match="two tops all along"):
        check_one_rod(p, centroid, direction, 0.0, NOISE)
    check_one_rod(p, centroid, direction, 0.0, NOISE, heads=True)


def test_two_rods_touching_all_along_are_refused_with_heads():
    """Two round rods 1.2 cm thick and 20 cm long touching side by side: alike all along,
    refused with ``heads`` too."""
    p = np.r_[_rod((0.0, 0.2), (-0.012, 0.0), (0.012, 0.012), round_top=True),
              _rod((0.0, 0.2), (0.0, 0.012), (0.012, 0.012), round_top=True)]  # fmt: skip
    p[:, 2] += np.random.default_rng(2).normal(0.0, NOISE, len(p))
    with pytest.raises(AmbiguousObjectError, match="not one rod"):
        check_one_rod(p, p[:, :2].mean(axis=0), _turned(0.0), 0.0, NOISE, heads=True)
