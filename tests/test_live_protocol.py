"""live.protocol and live.session's Recording: the live measurement's rules, without a robot."""

import numpy as np
import pytest

from comgrasp_pin.config import LiveConfig
from comgrasp_pin.errors import InvalidInputError
from comgrasp_pin.live.protocol import (
    EMPTY,
    LOADED,
    check_dynamics_factor,
    check_poses_fit,
    load_read_back,
    load_to_send,
    motion_waypoints,
    stops,
    visit_order,
    windows_text,
)
from comgrasp_pin.live.session import Recording
from comgrasp_pin.robot_io import JointLog
from comgrasp_pin.robot_io.at_rest import parse_windows


def test_each_pose_is_reached_from_both_sides_and_recorded_twice():
    Q = np.array([[0.0, 1.0], [0.5, -0.5]])
    plan = stops(Q, 0.04)
    assert len(plan) == 8
    recorded = [s for s in plan if s.record]
    assert [(s.pose, s.side) for s in recorded] == [(0, 1), (0, -1), (1, 1), (1, -1)]
    for s in recorded:
        np.testing.assert_array_equal(s.q, Q[s.pose])
    # the stop before each recording is the pose moved by the approach, on the recorded side
    for before, at in zip(plan[::2], plan[1::2]):
        np.testing.assert_allclose(before.q - at.q, at.side * 0.04)


def test_poses_are_visited_along_the_shortest_path():
    # on a line: from 0 the shortest path visits 0.1, 0.5, 1.0 in that order, whatever the
    # order given; a path's length is the sum of its moves' largest joint excursions
    Q = np.array([[1.0, 0.0], [0.1, 0.05], [0.5, -0.2]])
    assert visit_order(np.zeros(2), Q) == [1, 2, 0]
    assert visit_order(np.array([1.2, 0.0]), Q) == [0, 2, 1]
    # beyond 7 poses the nearest next: still the line's order
    line = np.linspace(0, 1, 9)[::-1, None] * np.ones((1, 2))
    assert visit_order(np.zeros(2), line) == list(range(8, -1, -1))
    # the stops follow the order given
    plan = stops(Q, 0.04, [1, 2, 0])
    assert [s.pose for s in plan if s.record] == [1, 1, 2, 2, 0, 0]


def test_a_motion_too_fast_for_the_dynamics_factor_is_played_slower():
    # q = A sin(w t): peak velocity A w, acceleration A w^2, jerk A w^3; the slow-down is
    # the largest of v/v_max, sqrt(a/a_max), cbrt(j/j_max) (derived by hand), at least 1
    c = LiveConfig()
    t = np.linspace(0, 2 * np.pi, 2001)
    A, w = 0.3, 2.0
    q = np.column_stack([A * np.sin(w * t), np.zeros_like(t)])
    qd = np.column_stack([A * w * np.cos(w * t), np.zeros_like(t)])
    qdd = np.column_stack([-A * w**2 * np.sin(w * t), np.zeros_like(t)])
    share = c.motion_limit_share * 0.2
    for v_max, a_max, j_max, expected in [
        (10.0, 1.0, 100.0, np.sqrt(A * w**2 / (share * 1.0))),  # acceleration-bound
        (1.0, 100.0, 100.0, A * w / (share * 1.0)),  # velocity-bound
        (100.0, 100.0, 1.0, np.cbrt(A * w**3 / (share * 1.0))),  # jerk-bound
        (1e3, 1e3, 1e4, 1.0),  # within: as planned
    ]:
        limits = (np.full(2, v_max), np.full(2, a_max), np.full(2, j_max))
        wp = motion_waypoints(t, q, qd, qdd, limits, 0.2, c)
        assert wp.slow_down == pytest.approx(expected, rel=2e-3)
        assert wp.duration_s == pytest.approx(t[-1] * wp.slow_down)
        np.testing.assert_allclose(np.diff(wp.t), c.waypoint_period_s, rtol=0.05)
        # the waypoints lie on the planned path at the slowed time (to linear interpolation
        # error), velocities divided
        s = wp.t[:-1] / wp.slow_down
        np.testing.assert_allclose(wp.q[:-1, 0], A * np.sin(w * s), atol=1e-5)
        np.testing.assert_allclose(wp.qd[:-1, 0], A * w * np.cos(w * s) / wp.slow_down, atol=1e-5)
        np.testing.assert_array_equal(wp.qd[-1], 0.0)
        np.testing.assert_array_equal(wp.start, q[0])


def test_dynamics_factor_is_capped():
    c = LiveConfig()
    assert check_dynamics_factor(0.1, c) == 0.1
    assert check_dynamics_factor(c.max_dynamics_factor, c) == c.max_dynamics_factor
    for bad in (0.0, -0.1, c.max_dynamics_factor + 0.01, 1.0, float("nan")):
        with pytest.raises(InvalidInputError, match="dynamics-factor"):
            check_dynamics_factor(bad, c)


def test_poses_whose_approach_leaves_the_limits_are_refused():
    lo, hi = np.array([-1.0, -1.0]), np.array([1.0, 1.0])
    check_poses_fit(np.array([[0.9, 0.0]]), lo, hi, 0.05)
    with pytest.raises(InvalidInputError, match="pose 0: joint 1"):
        check_poses_fit(np.array([[0.97, 0.0]]), lo, hi, 0.05)


def test_windows_text_round_trips_through_the_estimate_parser():
    spans = [[(1.0, 1.5), (2.5, 3.0)], [(5.25, 5.75), (6.0, 6.5)]]
    text = windows_text(spans)
    assert text == "1.0000:1.5000+2.5000:3.0000,5.2500:5.7500+6.0000:6.5000"
    assert parse_windows(text, joined=True) == [(1.0, 1.5, 2.5, 3.0), (5.25, 5.75, 6.0, 6.5)]


class _Estimate:
    def __init__(self, verdict, reasons=()):
        self.verdict, self.reasons = verdict, tuple(reasons)


def test_only_an_identified_load_is_sent():
    assert load_to_send(_Estimate("identified"), object()) == (True, "identified")
    send, why = load_to_send(_Estimate("nothing held", ["no payload seen: ... holds 0"]), None)
    assert not send and "nothing held" in why and "holds 0" in why and "Nothing was sent" in why
    send, why = load_to_send(_Estimate("unreliable", ["a reason"]), None)
    assert not send and "a reason" in why
    assert not load_to_send(_Estimate("identified"), None)[0]  # no payload made: nothing sent


def test_load_read_back_compares_each_field():
    sent = {"mass": 1.0, "F_x_Cload": [0.01, 0.02, 0.03], "load_inertia": list(range(9))}
    inertia_3x3 = np.arange(9.0).reshape(3, 3, order="F")
    assert load_read_back(sent, 1.0, [0.01, 0.02, 0.03], inertia_3x3, 1e-4) == []
    assert load_read_back(sent, 1.0, [0.01, 0.02, 0.03], np.arange(9.0), 1e-4) == []
    wrong = load_read_back(sent, 0.0, [0.0, 0.0, 0.0], np.zeros(9), 1e-4)
    assert len(wrong) == 3 and wrong[0].startswith("m_load 0")


def _recording(empty, loaded):
    log = JointLog(np.arange(3.0), ("a",), np.zeros((3, 1)), np.zeros((3, 1)), "live")
    return Recording(log, None, {EMPTY: empty, LOADED: loaded}, False, "stopped")


def test_only_poses_recorded_from_both_sides_in_both_runs_are_paired():
    both = [(0.0, 1.0), (2.0, 3.0)]
    rec = _recording([both, both, both], [both, [(8.0, 9.0)], []])
    assert rec.n_pairs == 1
    assert rec.before == rec.after == "0.0000:1.0000+2.0000:3.0000"
