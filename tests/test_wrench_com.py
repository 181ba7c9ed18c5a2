"""The payload from a wrist sensor's wrench change at the grasp poses (estimation.wrench_com).

Reference: the payload's weight applied at its CoM, written out in the test in the world frame
and moved to the sensor frame by hand (f = m g, tau = (c - p_sensor) x m g, then rotated),
and the joint-torque path (estimate_com) on the same payload.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from comgrasp_pin.errors import EmptyGripperError, InvalidInputError
from comgrasp_pin.estimation import estimate_com
from comgrasp_pin.estimation.regressor import stacked_regressor
from comgrasp_pin.estimation.wrench_com import (
    estimate_com_wrench,
    source_shares,
    wrench_regressor,
)
from comgrasp_pin.robot import RobotModel

ROBOT = RobotModel.ur5()
STD = np.r_[[0.02] * 3, [0.002] * 3]


def _wrench_in_sensor(q, m, c_ee, sensor="tool0"):
    """(6,) the payload's weight at its CoM, as the sensor at ``sensor`` reads it."""
    g = np.array([0.0, 0.0, -9.81])
    T_world_s, T_world_ee = ROBOT.frame_pose(q, sensor), ROBOT.ee_pose(q)
    c_world = T_world_ee[:3, :3] @ c_ee + T_world_ee[:3, 3]
    f_world = m * g
    tau_world = np.cross(c_world - T_world_s[:3, 3], f_world)
    R = T_world_s[:3, :3]
    return np.r_[R.T @ f_world, R.T @ tau_world]


def _poses(k, seed):
    return np.random.default_rng(seed).uniform(-1.5, 1.5, (k, 6))


@given(m=st.floats(0.2, 3.0), c=st.tuples(*[st.floats(-0.1, 0.1)] * 3), seed=st.integers(0, 999))
@settings(max_examples=30, deadline=None)
def test_exact_wrench_changes_give_the_payload_back(m, c, seed):
    Q = _poses(3, seed)
    W = np.array([_wrench_in_sensor(q, m, np.array(c)) for q in Q])
    est = estimate_com_wrench(ROBOT, Q, np.zeros_like(W), W, "tool0", wrench_std=STD)
    assert est.mass == pytest.approx(m, rel=1e-9)
    np.testing.assert_allclose(est.com_ee, c, atol=1e-9)


def test_one_pose_loses_the_com_along_gravity_like_the_torques():
    q = _poses(1, 4)
    W = _wrench_in_sensor(q[0], 1.0, np.array([0.05, 0.0, 0.1]))[None]
    est = estimate_com_wrench(ROBOT, q, np.zeros((1, 6)), W, "tool0", wrench_std=STD)
    g_ee = ROBOT.ee_pose(q[0])[:3, :3].T @ np.array([0.0, 0.0, -1.0])
    assert abs(abs(est.unobservable_ee @ g_ee) - 1.0) < 1e-9
    # the CoM projected across gravity is what both paths see
    Y, _ = stacked_regressor(ROBOT, q)
    dtau = Y @ np.r_[1.0, 0.05, 0.0, 0.1]
    est_t = estimate_com(ROBOT, q, np.zeros((1, 6)), dtau.reshape(1, 6), torque_std=0.01)
    np.testing.assert_allclose(est.com_ee, est_t.com_ee, atol=1e-9)


def test_the_rows_equal_the_weight_moved_to_the_sensor_for_any_sensor_frame():
    Q = _poses(2, 9)
    theta = np.r_[1.3, 1.3 * np.array([0.01, -0.02, 0.15])]
    for sensor in ("tool0", "gripper_base", "eelink"):
        Z, _ = wrench_regressor(ROBOT, Q, sensor)
        expected = np.concatenate([_wrench_in_sensor(q, 1.3, theta[1:] / 1.3, sensor) for q in Q])
        np.testing.assert_allclose(Z @ theta, expected, atol=1e-12)


def test_with_joint_torques_both_are_used_and_the_shares_say_how_much():
    Q = _poses(3, 2)
    theta = np.r_[0.9, 0.9 * np.array([0.04, 0.0, 0.05])]
    W = np.array([_wrench_in_sensor(q, theta[0], theta[1:] / theta[0]) for q in Q])
    Y, _ = stacked_regressor(ROBOT, Q)
    dtau = (Y @ theta).reshape(3, 6)
    cov_t = np.eye(18) * 0.05**2
    est = estimate_com_wrench(
        ROBOT, Q, np.zeros_like(W), W, "tool0", wrench_std=STD, torques=(0 * dtau, dtau, cov_t)
    )
    assert est.mass == pytest.approx(0.9, rel=1e-9) and est.n_poses == 3
    Z, _ = wrench_regressor(ROBOT, Q, "tool0")
    shares = source_shares({"wrench": (Z, np.diag(np.tile(STD, 3) ** 2)), "torques": (Y, cov_t)})
    for unknown in shares["wrench"]:
        assert shares["wrench"][unknown] + shares["torques"][unknown] == pytest.approx(1.0)
    assert shares["wrench"]["mass"] > 0.5  # 0.02 N against 0.05 N m on ~0.5 m levers
    # the combined interval is no wider than either alone
    alone = estimate_com_wrench(ROBOT, Q, np.zeros_like(W), W, "tool0", wrench_std=STD)
    assert np.all(np.diag(est.cov) <= np.diag(alone.cov) * (1 + 1e-9))


def test_noise_intervals_cover_the_truth():
    rng = np.random.default_rng(5)
    inside = []
    for k in range(200):
        Q = _poses(2, 100 + k)
        m, c = rng.uniform(0.5, 2.0), rng.uniform(-0.05, 0.05, 3)
        W = np.array([_wrench_in_sensor(q, m, c) for q in Q]) + rng.normal(size=(2, 6)) * STD
        est = estimate_com_wrench(ROBOT, Q, np.zeros_like(W), W, "tool0", wrench_std=STD)
        z = (np.r_[est.mass, est.com_ee] - np.r_[m, c]) / np.sqrt(np.diag(est.cov))
        inside.extend(np.abs(z) < 1.96)
    assert 0.92 < np.mean(inside) < 0.98


def test_bad_inputs_are_refused():
    Q = _poses(2, 1)
    W = np.zeros((2, 6))
    with pytest.raises(InvalidInputError, match="not a frame of the model"):
        estimate_com_wrench(ROBOT, Q, W, W + 1, "no_such_frame", wrench_std=STD)
    with pytest.raises(InvalidInputError, match="not on the same link chain"):
        estimate_com_wrench(ROBOT, Q, W, W + 1, "forearm_link", wrench_std=STD)
    with pytest.raises(InvalidInputError, match="exactly one"):
        estimate_com_wrench(ROBOT, Q, W, W + 1, "tool0")
    with pytest.raises(InvalidInputError, match=r"shape \(2, 6\)"):
        estimate_com_wrench(ROBOT, Q, W[:, :5], W[:, :5], "tool0", wrench_std=STD)
    with pytest.raises(EmptyGripperError):
        noise = np.random.default_rng(0).normal(size=(2, 6)) * STD
        estimate_com_wrench(ROBOT, Q, W, W + noise, "tool0", wrench_std=STD)
