"""Quintic trajectories: boundary conditions, finite-difference derivatives, limits."""

import numpy as np
import pytest

from comgrasp_pin.errors import ComGraspError
from comgrasp_pin.motion.trajectory import Quintic, min_duration


def test_rest_to_rest_and_derivatives_match_finite_differences():
    rng = np.random.default_rng(0)
    q0, q1 = rng.uniform(-2, 2, 6), rng.uniform(-2, 2, 6)
    traj = Quintic(q0, q1, 1.7)
    for t, q_ref in ((0.0, q0), (1.7, q1)):
        q, qd, qdd = traj.sample(t)
        np.testing.assert_allclose(q, q_ref, atol=1e-12)
        np.testing.assert_allclose(qd, 0.0, atol=1e-12)
        np.testing.assert_allclose(qdd, 0.0, atol=1e-12)
    t, h = np.linspace(0.05, 1.65, 17), 1e-6
    q, qd, qdd = traj.sample(t)
    assert q.shape == (17, 6)
    np.testing.assert_allclose(
        qd, (traj.sample(t + h)[0] - traj.sample(t - h)[0]) / (2 * h), atol=1e-6
    )
    np.testing.assert_allclose(
        qdd, (traj.sample(t + h)[1] - traj.sample(t - h)[1]) / (2 * h), atol=1e-5
    )


def test_min_duration_respects_limits_and_is_tight():
    rng = np.random.default_rng(1)
    for _ in range(20):
        q0, q1 = rng.uniform(-3, 3, 6), rng.uniform(-3, 3, 6)
        v_max, a_max = rng.uniform(0.3, 2.0), rng.uniform(0.5, 4.0)
        traj = Quintic.fastest(q0, q1, v_max, a_max)
        _, qd, qdd = traj.sample(traj.times(1e-3))
        peak_v, peak_a = np.abs(qd).max(), np.abs(qdd).max()
        assert peak_v <= v_max * (1 + 1e-9) and peak_a <= a_max * (1 + 1e-6)
        assert peak_v > 0.999 * v_max or peak_a > 0.999 * a_max  # one limit is reached


def test_bad_input():
    with pytest.raises(ComGraspError):
        Quintic(np.zeros(6), np.zeros(5), 1.0)
    with pytest.raises(ComGraspError):
        Quintic(np.zeros(6), np.ones(6), 0.0)
    assert min_duration(np.zeros(6), np.zeros(6), 1.0, 2.0) == pytest.approx(0.1)
