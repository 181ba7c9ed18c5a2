"""The pure planning functions (no simulator): retrying a trial grasp (``planning.retry``),
laying a held rod down (``planning.put_down``) and the jaws' holding moment
(``planning.holding``).

Expected values are derived by hand in this file: a 1-D model of the CoM search, rod ends and
pivots from plane geometry of a rod held in a top-down gripper, and the friction budget
2 F (mu a + mu_t) with the pad's half width a = 0.012 m read off the URDF (pad box 0.024 m
along ee-x). Frames are built here, not with the package's helpers.
"""

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from comgrasp_pin.config import RegraspConfig, TrialConfig, WorldConfig
from comgrasp_pin.planning.holding import holding_lever, holding_moment
from comgrasp_pin.planning.put_down import axis_hint_after_put_down, plan_put_down
from comgrasp_pin.planning.retry import (
    RetryState,
    after_failure,
    grasp_offset,
    heavy_side_from_estimate,
    heavy_side_from_tilt,
)

CONFIG = RegraspConfig()
SHIFT = CONFIG.retry_shift
MIN_TILT = np.radians(TrialConfig().heavy_side_min_deg)
FAST = settings(max_examples=60, deadline=None)

angles = st.floats(-np.pi, np.pi, allow_nan=False)
lengths = st.floats(0.15, 0.8)


def _unit(yaw: float) -> np.ndarray:
    return np.array([np.cos(yaw), np.sin(yaw), 0.0])


def _horizontal_unit(v: np.ndarray) -> np.ndarray:
    h = np.array([v[0], v[1], 0.0])
    return h / np.linalg.norm(h)


def _ee_frame(x: float, y: float, z: float, yaw: float, roll: float = 0.0) -> np.ndarray:
    """T_world_ee pointing down (ee z = world -z, ee x = (cos yaw, sin yaw, 0), y = z cross x),
    then rolled about its own x by ``roll``."""
    ex, ez = _unit(yaw), np.array([0.0, 0.0, -1.0])
    R = np.column_stack([ex, np.cross(ez, ex), ez])
    c, s = np.cos(roll), np.sin(roll)
    T = np.eye(4)
    T[:3, :3] = R @ np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])
    T[:3, 3] = [x, y, z]
    return T


def _held_rod(theta: float, grasp: float, depth: float = 0.0) -> np.ndarray:
    """T_ee_obj of a rod tilted by ``theta`` about ee-y (positive raises its +x end, i.e.
    moves it towards -z_ee), held ``grasp`` from its centre along +x_obj, its axis ``depth``
    from the TCP along the axis' normal in the jaws' plane (+z_obj)."""
    x = np.array([np.cos(theta), 0.0, -np.sin(theta)])
    z = np.array([np.sin(theta), 0.0, np.cos(theta)])
    T = np.eye(4)
    T[:3, :3] = np.column_stack([x, [0.0, 1.0, 0.0], z])
    T[:3, 3] = -grasp * x + depth * z
    return T


def _same_state(a: RetryState, b: RetryState) -> bool:
    if (a.direction_world is None) != (b.direction_world is None):
        return False
    if a.direction_world is not None and not np.array_equal(a.direction_world, b.direction_world):
        return False
    return (a.s, a.below, a.above) == (b.s, b.below, b.above)


# --- retry: where to grasp next ------------------------------------------------------------------


@FAST
@given(yaw=angles, length=lengths)
def test_first_failure_steps_retry_shift_lengths_towards_the_heavy_side(yaw, length):
    heavy = _unit(yaw)
    state = after_failure(RetryState(), heavy, length, SHIFT)
    assert state.s == pytest.approx(SHIFT * length)
    assert state.below == 0.0 and state.above is None
    # Seen along the heavy side, the next grasp point lies SHIFT * length that way.
    np.testing.assert_allclose(grasp_offset(state, yaw) * _unit(yaw), SHIFT * length * heavy)


@FAST
@given(
    yaw=angles,
    length=lengths,
    steps=st.integers(1, 3),
    seen_off_by=st.floats(-1.2, 1.2),
)
def test_a_failure_on_the_other_side_bisects_the_two_last_grasp_points(
    yaw, length, steps, seen_off_by
):
    """After ``steps`` failures towards the heavy side the grasps were at 0, 1, ..,
    steps * SHIFT * L; turning the other way at the last puts the next midway between the
    last two. The heavy side is seen anew each time (here up to 70 deg off the first)."""
    heavy = _unit(yaw)
    state = RetryState()
    for _ in range(steps):
        state = after_failure(state, heavy, length, SHIFT)
    assert state.s == pytest.approx(steps * SHIFT * length)
    state = after_failure(state, -_unit(yaw + seen_off_by), length, SHIFT)
    assert state.s == pytest.approx((steps - 0.5) * SHIFT * length)
    assert state.below == pytest.approx((steps - 1) * SHIFT * length)
    assert state.above == pytest.approx(steps * SHIFT * length)


@FAST
@given(direction=angles, yaw=angles, s=st.floats(-0.2, 0.2))
def test_grasp_offset_flips_sign_when_the_rod_is_seen_turned_by_pi(direction, yaw, s):
    assume(abs(np.cos(yaw - direction)) > 0.05)  # a rod seen at right angles is no rod of ours
    state = RetryState(direction_world=_unit(direction), s=s)
    a, b = grasp_offset(state, yaw), grasp_offset(state, yaw + np.pi)
    assert b == pytest.approx(-a)
    # Either way the grasp goes to the same point, s along the remembered direction.
    np.testing.assert_allclose(a * _unit(yaw), b * _unit(yaw + np.pi), atol=1e-12)
    along = a * _unit(yaw) @ _unit(direction)  # m; atol: an s of 5e-324 m underflows to 0
    np.testing.assert_allclose(along, s * abs(np.cos(yaw - direction)), atol=1e-15)


def test_grasp_offset_before_any_heavy_side_is_the_centre():
    assert grasp_offset(RetryState(), 0.3) == 0.0


def test_no_heavy_side_leaves_the_state_unchanged():
    heavy = _unit(0.4)
    states = [RetryState()]
    states.append(after_failure(states[-1], heavy, 0.3, SHIFT))
    states.append(after_failure(states[-1], -heavy, 0.3, SHIFT))
    for state in states:
        assert _same_state(after_failure(state, None, 0.3, SHIFT), state)


HOLD = 0.003  # m: a grasp this near the CoM holds ("within a few mm")


@settings(max_examples=150, deadline=None)
@given(
    com_fraction=st.floats(-0.3, 0.3),
    length=lengths,
    rod_yaw=angles,
    seen_flipped=st.lists(st.booleans(), min_size=11, max_size=11),
)
def test_search_finds_the_com_within_ten_failures(com_fraction, length, rod_yaw, seen_flipped):
    """1-D model: the CoM lies at c along the rod; a grasp at s turns the rod towards its
    +u end if c > s, else towards -u. The top view sees the rod's yaw modulo pi."""
    c, u = com_fraction * length, _unit(rod_yaw)
    state, failures = RetryState(), 0
    for flipped in seen_flipped:
        seen = rod_yaw + np.pi * flipped
        s = grasp_offset(state, seen) * (_unit(seen) @ u)  # the grasp point along u
        if abs(s - c) <= HOLD:
            break
        state = after_failure(state, u if c > s else -u, length, SHIFT)
        failures += 1
    assert abs(s - c) <= HOLD, (failures, s, c)
    assert failures <= 10


# --- retry: which end is heavy -------------------------------------------------------------------

tilts = st.floats(MIN_TILT, 1.2).flatmap(lambda t: st.sampled_from([t, -t]))


@FAST
@given(tilt=tilts, yaw=angles)
def test_heavy_side_from_tilt_points_to_the_end_that_went_down(tilt, yaw):
    T = _ee_frame(0.5, 0.0, 0.3, yaw)  # the top-down pose the trial grasp watches from
    rod = T[:3, :3] @ _held_rod(tilt, 0.0)[:3, 0]  # world direction of the rod's +x end
    assert np.sign(rod[2]) == np.sign(tilt)  # positive tilt raises the +x end
    low = rod if rod[2] < 0 else -rod
    got = heavy_side_from_tilt(tilt, T[:3, 0], MIN_TILT)
    np.testing.assert_allclose(got, _horizontal_unit(low), atol=1e-9)


@FAST
@given(tilt=tilts, yaw=angles, roll=st.floats(-0.5, 0.5))
def test_heavy_side_from_tilt_at_a_rolled_wrist_picks_the_right_end(tilt, yaw, roll):
    """Rolled about ee-x, the rod's horizontal direction is no longer ee-x; which end went
    down (all that the retry uses) is still right."""
    T = _ee_frame(0.5, 0.0, 0.3, yaw, roll)
    rod = T[:3, :3] @ _held_rod(tilt, 0.0)[:3, 0]
    low = rod if rod[2] < 0 else -rod
    assert heavy_side_from_tilt(tilt, T[:3, 0], MIN_TILT) @ _horizontal_unit(low) > 0.5


@FAST
@given(tilt=tilts, x=st.tuples(*[st.floats(-1.0, 1.0)] * 3))
def test_heavy_side_from_tilt_is_a_unit_horizontal_vector(tilt, x):
    assume(np.hypot(x[0], x[1]) > 1e-3)
    got = heavy_side_from_tilt(tilt, np.array(x), MIN_TILT)
    assert got[2] == 0.0
    assert np.linalg.norm(got) == pytest.approx(1.0)


@pytest.mark.parametrize("tilt", [None, 0.0, 0.5 * MIN_TILT, -0.99 * MIN_TILT])
def test_heavy_side_from_tilt_tells_nothing_below_min_tilt(tilt):
    assert heavy_side_from_tilt(tilt, np.array([1.0, 0.0, 0.0]), MIN_TILT) is None


@FAST
@given(
    yaw=angles,
    roll=st.floats(-0.5, 0.5),
    tilt=st.floats(-0.8, 0.8),
    x_com=st.floats(-0.2, 0.2),
    grasp=st.floats(-0.2, 0.2),
)
def test_heavy_side_from_estimate_points_from_the_jaws_to_the_com(yaw, roll, tilt, x_com, grasp):
    assume(abs(x_com - grasp) > 1e-3)
    T_world_ee, T_ee_obj = _ee_frame(0.5, 0.1, 0.3, yaw, roll), _held_rod(tilt, grasp, 0.004)

    def world(s):  # point s along the rod from its centre
        return (T_world_ee @ T_ee_obj @ np.array([s, 0.0, 0.0, 1.0]))[:3]

    got = heavy_side_from_estimate(T_world_ee, T_ee_obj, x_com, grasp)
    np.testing.assert_allclose(got, _horizontal_unit(world(x_com) - world(grasp)), atol=1e-9)


# --- put-down ------------------------------------------------------------------------------------

PUT_DOWN_XY = (0.55, 0.0)
LOWEST_TCP = 0.0 + 0.015 + 0.002  # table top + pad bottom below the TCP + fingertip clearance
"""Lowest eelink height of a grasp: table top at z = 0 (scene.xml), the pads' bottom 15 mm
beyond the TCP (URDF: pad 0.03 m tall centred at the eelink's height), kept 2 mm above the
table (``grasp_height``'s documented clearance)."""


def _lying_grasp_height(rod_axis_z: float) -> float:
    """TCP height of a grasp of a rod lying with its axis at ``rod_axis_z``: on the axis,
    but not below LOWEST_TCP (as ``motion.ik.grasp_height`` documents)."""
    return max(rod_axis_z, LOWEST_TCP)


def _e_x(T_world_ee_now: np.ndarray) -> np.ndarray:
    """The put-down frame's ee-x: world +y or -y, whichever is nearer the current ee-x."""
    return np.array([0.0, 1.0 if T_world_ee_now[1, 0] >= 0 else -1.0, 0.0])


def _plan(theta, grasp, length, rod_axis_z, yaw_now=2.0, depth=0.0):
    T_now = _ee_frame(0.45, 0.1, 0.25, yaw_now)
    T_ee_obj = _held_rod(theta, grasp, depth)
    plan = plan_put_down(T_now, T_ee_obj, length, grasp, rod_axis_z, PUT_DOWN_XY, CONFIG)
    return plan, T_now, T_ee_obj


def _at(T: np.ndarray, p_ee: np.ndarray) -> np.ndarray:
    return T[:3, :3] @ p_ee + T[:3, 3]


tilted = st.floats(0.05, 1.0).flatmap(lambda t: st.sampled_from([t, -t]))
grasps = st.floats(-0.3, 0.3)  # fraction of the rod's length


@FAST
@given(theta=st.floats(-1.0, 1.0), yaw_now=angles)
def test_put_down_frames_point_down_along_world_y(theta, yaw_now):
    assume(abs(np.sin(yaw_now)) > 1e-3)
    plan, T_now, _ = _plan(theta, 0.02, 0.3, 0.02, yaw_now)
    for T in (plan.T_above, plan.T_touch, plan.T_flat):
        R = T[:3, :3]
        np.testing.assert_allclose(R.T @ R, np.eye(3), atol=1e-12)
        assert np.linalg.det(R) == pytest.approx(1.0)
        np.testing.assert_allclose(R[:, 2], [0.0, 0.0, -1.0], atol=1e-12)
        np.testing.assert_allclose(R[:, 0], _e_x(T_now), atol=1e-12)
        np.testing.assert_array_equal(T[3], [0.0, 0.0, 0.0, 1.0])


def test_level_rod_is_lowered_straight_down_onto_the_spot():
    """Held level (axis through the TCP, held 0.04 m towards +x from the centre): no pivot,
    the TCP ends 0.04 m from the spot along the rod, its height pad_clearance above the
    lying rod's axis."""
    length, grasp, rod_axis_z = 0.3, 0.04, 0.02
    plan, T_now, T_ee_obj = _plan(0.0, grasp, length, rod_axis_z)
    e_x = _e_x(T_now)
    xy = np.array(PUT_DOWN_XY) + grasp * e_x[:2]
    z_flat = rod_axis_z + CONFIG.pad_clearance
    np.testing.assert_allclose(plan.T_above[:3, 3], [*xy, T_now[2, 3]], atol=1e-12)
    np.testing.assert_allclose(plan.T_touch[:3, 3], [*xy, z_flat + CONFIG.touch_clearance])
    np.testing.assert_allclose(plan.T_flat[:3, 3], [*xy, z_flat], atol=1e-12)
    # Both ends are equally low: the pivot is at the one the plan names.
    end = (1.0 if plan.low_is_plus else -1.0) * 0.5 * length
    np.testing.assert_allclose(plan.p_pivot[:2], np.array(PUT_DOWN_XY) + end * e_x[:2])
    np.testing.assert_allclose(plan.p_pivot, _at(plan.T_touch, T_ee_obj[:3, 3] + [end, 0, 0]))


@FAST
@given(theta=tilted, grasp_fraction=grasps, length=lengths, yaw_now=angles)
def test_tilted_rod_pivots_on_its_low_end_which_stays_put(theta, grasp_fraction, length, yaw_now):
    """The held rod's low end (the -x end for a positive tilt) at T_touch is where it lies once
    flat at T_flat, centred on the put-down spot: it pivots there without sliding."""
    assume(abs(np.sin(yaw_now)) > 1e-3)
    grasp = grasp_fraction * length
    plan, T_now, T_ee_obj = _plan(theta, grasp, length, 0.02, yaw_now)
    sigma = -1.0 if theta > 0 else 1.0  # which end is low, along the rod's +x
    assert plan.low_is_plus == (sigma > 0)
    low_held = T_ee_obj[:3, 3] + sigma * 0.5 * length * T_ee_obj[:3, 0]
    np.testing.assert_allclose(plan.p_pivot, _at(plan.T_touch, low_held), atol=1e-12)
    # Flat along ee-x with the grasp point at the TCP, the low end lies (sigma L/2 - grasp)
    # along ee-x from it, i.e. sigma L / 2 from the spot: where the pivot is.
    e_x = _e_x(T_now)
    low_flat = plan.T_flat[:3, 3] + (sigma * 0.5 * length - grasp) * e_x
    np.testing.assert_allclose(plan.p_pivot[:2], low_flat[:2], atol=1e-12)
    np.testing.assert_allclose(
        plan.p_pivot[:2], np.array(PUT_DOWN_XY) + sigma * 0.5 * length * e_x[:2], atol=1e-12
    )


@FAST
@given(theta=tilted, grasp_fraction=grasps, length=lengths)
def test_tilted_rod_lies_flat_centred_on_the_spot(theta, grasp_fraction, length):
    """T_flat: the TCP at ``grasp`` from the spot along ee-x (the rod's centre on the spot);
    T_above and T_touch are set back from it by the pivot's shift a (1 - cos theta), a being
    the distance from the grasp point to the low end: flat, the rod reaches further."""
    grasp = grasp_fraction * length
    plan, T_now, _ = _plan(theta, grasp, length, 0.02)
    e_x = _e_x(T_now)
    sigma = -1.0 if theta > 0 else 1.0
    a = 0.5 * length - sigma * grasp
    flat_xy = np.array(PUT_DOWN_XY) + grasp * e_x[:2]
    touch_xy = flat_xy + sigma * a * (1.0 - np.cos(theta)) * e_x[:2]
    np.testing.assert_allclose(plan.T_flat[:2, 3], flat_xy, atol=1e-12)
    np.testing.assert_allclose(plan.T_touch[:2, 3], touch_xy, atol=1e-12)
    np.testing.assert_allclose(plan.T_above[:3, 3], [*touch_xy, T_now[2, 3]], atol=1e-12)


@FAST
@given(theta=tilted, grasp_fraction=grasps, length=lengths, rod_axis_z=st.floats(0.002, 0.05))
def test_touch_lowers_the_low_end_to_touch_clearance_above_the_flat_height(
    theta, grasp_fraction, length, rod_axis_z
):
    """The low end hangs a |sin theta| below the TCP; at T_touch it is touch_clearance above
    z_flat, the flat TCP height max(rod_axis_z + pad_clearance, lowest grasp)."""
    grasp = grasp_fraction * length
    plan, _, _ = _plan(theta, grasp, length, rod_axis_z)
    a = 0.5 * length + (grasp if theta > 0 else -grasp)
    z_flat = max(rod_axis_z + CONFIG.pad_clearance, _lying_grasp_height(rod_axis_z))
    assert plan.T_flat[2, 3] == pytest.approx(z_flat, abs=1e-12)
    assert plan.T_touch[2, 3] == pytest.approx(
        z_flat + CONFIG.touch_clearance + a * abs(np.sin(theta)), abs=1e-12
    )
    assert plan.p_pivot[2] == pytest.approx(z_flat + CONFIG.touch_clearance, abs=1e-12)


@FAST
@given(theta=st.floats(-0.6, 0.6), depth=st.floats(-0.003, 0.008))
def test_flat_height_follows_the_axis_point_nearest_the_tcp(theta, depth):
    """A rod held with its axis ``depth`` off the TCP: the axis point nearest the TCP is
    depth * z_obj = depth (sin theta, 0, cos theta) in the ee frame (the pinch point the rod
    turns about as it pivots flat); flat, the TCP stays its ee-z (depth cos theta) above the
    lying axis, plus pad_clearance."""
    rod_axis_z = 0.03
    plan, _, _ = _plan(theta, 0.03, 0.3, rod_axis_z, depth=depth)
    expected = rod_axis_z + depth * np.cos(theta) + CONFIG.pad_clearance
    assert expected >= _lying_grasp_height(rod_axis_z)
    assert plan.T_flat[2, 3] == pytest.approx(expected, abs=1e-12)


@pytest.mark.parametrize("depth", [-0.004, -0.02])
def test_flat_height_never_below_the_lying_axis(depth):
    """Held with its axis above the TCP (nearer the palm), flat the TCP still stops on the
    lying rod's axis: a lower TCP would push the rod into the table."""
    plan, _, _ = _plan(0.2, 0.03, 0.3, 0.03, depth=depth)
    assert plan.T_flat[2, 3] == pytest.approx(0.03, abs=1e-12)


@pytest.mark.parametrize("theta", [0.0, 0.3, -0.3])
def test_flat_height_never_below_a_grasp_of_the_lying_rod(theta):
    """A thin rod (axis 4 mm above the table): the pads would jam on the table at
    rod_axis_z + pad_clearance, so the TCP stops at the lowest grasp height."""
    plan, _, _ = _plan(theta, 0.0, 0.3, 0.004)
    assert plan.T_flat[2, 3] == pytest.approx(LOWEST_TCP, abs=1e-12)


@FAST
@given(theta=st.floats(-1.0, 1.0), depth=st.floats(-0.05, 0.01))
def test_touch_is_never_below_flat(theta, depth):
    """Even a rod held above the TCP (negative depth: its low end above the TCP) is not
    lowered past the flat height on the way to the touch."""
    plan, _, _ = _plan(theta, 0.0, 0.3, 0.02, depth=depth)
    assert plan.T_touch[2, 3] >= plan.T_flat[2, 3] - 1e-12


@FAST
@given(theta=tilted, grasp_fraction=grasps, length=lengths, yaw_now=angles)
def test_axis_hint_after_put_down_is_the_flat_rods_plus_x(theta, grasp_fraction, length, yaw_now):
    """Laid flat, the rod's +x end (towards +x_ee when held) points along T_flat's ee-x, and
    its centre lies on the spot, L / 2 from the pivot."""
    assume(abs(np.sin(yaw_now)) > 1e-3)
    plan, T_now, _ = _plan(theta, grasp_fraction * length, length, 0.02, yaw_now)
    hint = axis_hint_after_put_down(plan, PUT_DOWN_XY)
    np.testing.assert_allclose(hint, 0.5 * length * plan.T_flat[:3, 0], atol=1e-12)


@FAST
@given(
    theta=tilted, length=lengths, slide=st.tuples(st.floats(-0.01, 0.01), st.floats(-0.01, 0.01))
)
def test_axis_hint_survives_a_centre_seen_a_centimetre_off(theta, length, slide):
    plan, _, _ = _plan(theta, 0.0, length, 0.02)
    seen = np.array(PUT_DOWN_XY) + np.array(slide)
    hint = axis_hint_after_put_down(plan, tuple(seen))
    assert hint[2] == 0.0
    assert _horizontal_unit(hint) @ plan.T_flat[:3, 0] > np.cos(np.radians(15.0))


# --- holding moment ------------------------------------------------------------------------------

PAD_HALF_WIDTH = 0.024 / 2  # m: the URDF's pad box is 0.024 m along ee-x (along the rod)
G = 9.81


@FAST
@given(force=st.floats(0.5, 50.0), mu=st.floats(0.1, 1.5), mu_t=st.floats(0.0, 0.01))
def test_holding_moment_is_two_f_mu_a_plus_mu_t(force, mu, mu_t):
    expected = 2.0 * force * (mu * PAD_HALF_WIDTH + mu_t)
    assert holding_moment(force, (mu, mu_t, 1e-4)) == pytest.approx(expected, rel=1e-12)


def test_holding_moment_of_the_default_pads_at_15_n():
    """WorldConfig documents about 0.023 N m per N of grip, 0.35 N m at 15 N."""
    friction = WorldConfig().pad_friction
    assert holding_moment(1.0, friction) == pytest.approx(2 * (0.8 * 0.012 + 0.002))
    assert holding_moment(15.0, friction) == pytest.approx(0.348)


def test_rolling_friction_does_not_count():
    assert holding_moment(15.0, (0.8, 0.002, 0.0)) == holding_moment(15.0, (0.8, 0.002, 0.5))


@FAST
@given(mass=st.floats(0.05, 2.0), force=st.floats(0.5, 50.0), mu=st.floats(0.1, 1.5))
def test_holding_lever_is_where_the_weight_reaches_the_moment(mass, force, mu):
    lever = holding_lever(mass, force, (mu, 0.002, 1e-4))
    assert lever == pytest.approx(2.0 * force * (mu * PAD_HALF_WIDTH + 0.002) / (mass * G))
