"""Where the jaws let go of a hanging rod so that it lies on the put-down spot, inside the
pick area (planning.put_down.put_back_jaws_xy): pure geometry, checked against the hanging
rod built point by point in 3-D here."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from comgrasp_pin.config import RegraspConfig
from comgrasp_pin.errors import ComGraspError, UnobservableError
from comgrasp_pin.planning.put_down import put_back_jaws_xy
from comgrasp_pin.workcell import PICK_AREA, PUT_DOWN_XY


def _landing(jaws_xy, yaw, tilt, length, centre_hint):
    """(centre (2,), ends (2, 2)) where a rod held at ``jaws_xy`` with the jaws' x axis at
    ``yaw`` lies once it toppled about its low end: the rod's points built in the ee frame
    (x along the jaws, z up here), turned by ``tilt`` about ee-y (a positive tilt raises the
    +x end), the lower end found by its height, the rod laid from it towards the other end's
    side."""
    c, s = np.cos(tilt), np.sin(tilt)
    ends_ee = [np.array([centre_hint + e * 0.5 * length, 0.0]) for e in (-1.0, 1.0)]
    # a point a along the rod (from the jaws) sits at (a cos, a sin) in the ee x-z plane
    pts = [np.array([a[0] * c, a[0] * s]) for a in ends_ee]
    low, high = sorted(pts, key=lambda p: p[1])
    u = np.array([np.cos(yaw), np.sin(yaw)])
    low_xy = np.asarray(jaws_xy) + low[0] * u
    towards = np.sign(high[0] - low[0]) * u  # the rod falls over towards its upper end
    centre = low_xy + 0.5 * length * towards
    return centre, np.array([low_xy, low_xy + length * towards])


@pytest.mark.parametrize("tilt_deg", [-75.0, -30.0, 5.0, 40.0, 80.0])
@pytest.mark.parametrize("centre_hint", [-0.12, 0.0, 0.07])
@pytest.mark.parametrize("yaw_deg", [0.0, 90.0, -140.0])
def test_the_rod_lands_on_the_spot(tilt_deg, centre_hint, yaw_deg):
    yaw, tilt, length = np.radians(yaw_deg), np.radians(tilt_deg), 0.32
    x_ee = np.array([np.cos(yaw), np.sin(yaw), 0.0])
    jaws = put_back_jaws_xy(PUT_DOWN_XY, x_ee, tilt, length, centre_hint, PICK_AREA, 0.03)
    centre, _ = _landing(jaws, yaw, tilt, length, centre_hint)
    np.testing.assert_allclose(centre, PUT_DOWN_XY, atol=1e-12)


def test_a_steep_rod_is_let_go_half_its_length_from_the_spot():
    """Hanging straight down from its end, a 0.4 m rod lies 0.2 m from where it stood."""
    jaws = put_back_jaws_xy((0.55, 0.0), np.array([0.0, 1.0, 0.0]), np.radians(90.0), 0.4,
                            -0.2, PICK_AREA, 0.03)  # fmt: skip
    np.testing.assert_allclose(jaws, (0.55, -0.2), atol=1e-12)


def test_a_level_rod_is_let_go_over_its_centre():
    jaws = put_back_jaws_xy((0.55, 0.0), np.array([1.0, 0.0, 0.0]), 0.0, 0.4, 0.05,
                            PICK_AREA, 0.03)  # fmt: skip
    np.testing.assert_allclose(jaws, (0.50, 0.0), atol=1e-12)


@settings(max_examples=300, deadline=None)
@given(
    st.floats(0.30, 0.80),
    st.floats(-0.35, 0.35),
    st.floats(-np.pi, np.pi),
    st.floats(-1.5, 1.5),
    st.floats(0.1, 0.42),
    st.floats(-0.45, 0.45),
    st.floats(0.0, 0.035),
)
def test_the_landing_lies_inside_the_pick_area(x, y, yaw, tilt, length, hint_share, margin):
    """From any spot on the table, the landing rod's ends lie ``margin`` inside the area
    (where the area is longer than the rod along each axis: the table is 0.5 x 0.7 m,
    every rod here shorter than 0.5 - 2 margin; one that is not is centred, below)."""
    centre_hint = hint_share * length
    x_ee = np.array([np.cos(yaw), np.sin(yaw), 0.0])
    jaws = put_back_jaws_xy((x, y), x_ee, tilt, length, centre_hint, PICK_AREA, margin)
    _, ends = _landing(jaws, yaw, tilt, length, centre_hint)
    x0, x1, y0, y1 = PICK_AREA
    tol = 1e-9
    assert np.all(ends[:, 0] >= x0 + margin - tol) and np.all(ends[:, 0] <= x1 - margin + tol)
    assert np.all(ends[:, 1] >= y0 + margin - tol) and np.all(ends[:, 1] <= y1 - margin + tol)


def test_a_spot_inside_stays_where_it_is_and_one_at_the_edge_moves_in():
    x_ee = np.array([0.0, 1.0, 0.0])
    centre, _ = _landing(put_back_jaws_xy((0.55, 0.2), x_ee, 0.5, 0.3, 0.0, PICK_AREA, 0.03),
                         np.pi / 2, 0.5, 0.3, 0.0)  # fmt: skip
    np.testing.assert_allclose(centre, (0.55, 0.17), atol=1e-12)  # 0.35 - 0.03 - 0.15


def test_a_rod_longer_than_the_area_allows_is_centred_in_it():
    x_ee = np.array([1.0, 0.0, 0.0])
    centre, _ = _landing(put_back_jaws_xy((0.7, 0.1), x_ee, 0.0, 0.46, 0.0, PICK_AREA, 0.03),
                         0.0, 0.0, 0.46, 0.0)  # fmt: skip
    np.testing.assert_allclose(centre, (0.55, 0.1), atol=1e-12)  # 0.46 + 0.06 > 0.5 along x


def test_a_vertical_jaw_axis_is_refused():
    with pytest.raises(UnobservableError):
        put_back_jaws_xy(PUT_DOWN_XY, np.array([0.0, 0.0, 1.0]), 0.3, 0.3, 0.0, PICK_AREA, 0.03)
    assert issubclass(UnobservableError, ComGraspError)


def test_the_margin_is_in_the_config():
    assert 0.0 < RegraspConfig().put_back_margin < 0.1


def _seen(length, cut_end, yaw, x=0.6, y=0.3):
    """A RodDetection of ``length`` m seen, 1 cm slices 2 cm wide."""
    from comgrasp_pin.geometry import GraspPose
    from comgrasp_pin.perception import RodDetection

    pos = np.arange(-length / 2 + 0.005, length / 2, 0.01)
    return RodDetection(GraspPose(x, y, 0.01, yaw), length, np.c_[pos, np.full(len(pos), 0.02)],
                        0.0, 0.02, np.zeros((4, 4), bool), ((0, 0), (1, 1), 0.0),
                        np.zeros((2, 2)), 0.0, cut_end)  # fmt: skip


@pytest.mark.parametrize("cut_end", [1, -1])
def test_a_rod_seen_in_part_is_completed_towards_its_cut_end(cut_end):
    """0.30 m of a 0.40 m rod seen: the whole rod's centre lies 5 cm beyond the part seen's
    towards the end out of view; the ends seen stay where they were."""
    from comgrasp_pin.perception.top_view.grasp_points import with_known_length

    yaw = 0.3
    seen = _seen(0.30, cut_end, yaw)
    whole = with_known_length(seen, 0.40, 0.6)
    d = cut_end * np.array([np.cos(yaw), np.sin(yaw)])
    np.testing.assert_allclose([whole.grasp.x, whole.grasp.y], np.array([0.6, 0.3]) + 0.05 * d)
    # the end seen: the part's centre 0.15 m back from it, the whole's 0.20 m
    end_seen = np.array([0.6, 0.3]) - 0.15 * d
    np.testing.assert_allclose(end_seen, [whole.grasp.x, whole.grasp.y] - 0.20 * d, atol=1e-12)
    assert whole.length == 0.40 and whole.cut_end == cut_end
    np.testing.assert_allclose(whole.widths[:, 0], seen.widths[:, 0] - cut_end * 0.05)


def test_a_rod_seen_too_little_or_whole_is_not_completed():
    from comgrasp_pin.errors import ObjectCutByBorderError
    from comgrasp_pin.perception.top_view.grasp_points import nearest_graspable, with_known_length

    with pytest.raises(ObjectCutByBorderError, match="too little"):
        with_known_length(_seen(0.20, 1, 0.0), 0.40, 0.6)
    with pytest.raises(ObjectCutByBorderError, match="whole"):
        with_known_length(_seen(0.40, 0, 0.0), 0.40, 0.6)
    # a grasp goes where the pads (22 mm either side) lie on slices seen: not beyond
    whole = with_known_length(_seen(0.30, 1, 0.0), 0.40, 0.6)
    assert nearest_graspable(whole, 0.17) <= whole.widths[:, 0].max() + 0.01 - 0.022 + 1e-12
    assert nearest_graspable(whole, -0.05) == -0.05  # within the part seen: where asked


def test_a_rod_seen_again_shorter_than_first_seen_is_refused():
    from comgrasp_pin.errors import ObjectCutByBorderError
    from comgrasp_pin.perception.top_view.grasp_points import check_seen_whole

    tol = RegraspConfig().length_tolerance
    rod = _seen(0.40, 0, 0.0)
    assert check_seen_whole(rod, 0.40 + 0.9 * tol, tol) is rod
    with pytest.raises(ObjectCutByBorderError, match="out of sight"):
        check_seen_whole(_seen(0.148, 0, 0.0), 0.40, tol)  # obj1 seed 1004, hanging off
