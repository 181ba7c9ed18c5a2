"""``estimate_com``'s least squares against plain least squares written out here.

The reference: the stacked regression (Pinocchio's Jacobians, eq. 5), ``np.linalg.lstsq``,
the covariance 2 sigma^2 (Y^T W Y)^-1 and the delta method; for one pose the CoM across
gravity (the unknowns (m, m c_wy, -m c_wx) in the world). IPOPT's l2 fit must land on it,
and the errors on singular or empty problems must be the documented ones.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from _payload import panda, payload_torques
from hypothesis import given, settings
from hypothesis import strategies as st

import comgrasp_pin as cg
from comgrasp_pin.estimation.regressor import stacked_regressor

ROBOTS = {"ur5": cg.RobotModel.ur5, "panda": panda}


@pytest.fixture(scope="module")
def robots() -> dict:
    return {name: make() for name, make in ROBOTS.items()}


def reference(robot, Q, dtau, sigma):
    """(mass, com_ee, cov, residuals, singular values) by plain SVD least squares."""
    k, n = Q.shape
    Y, T = stacked_regressor(robot, Q)
    if k == 1:  # world z is up in these models: the CoM across gravity, in world x and y
        R = T[0, :3, :3]
        B = np.zeros((4, 3))
        B[0, 0], B[1:, 1], B[1:, 2] = 1.0, R[1], -R[0]
    else:
        B = np.eye(4)
    Yr, b = Y @ B, dtau.ravel()
    if sigma is None:
        w = np.linalg.lstsq(Yr, b, rcond=None)[0]
        dof = len(b) - Yr.shape[1]
        noise = max(np.linalg.norm(b - Yr @ w) / math.sqrt(dof), 1e-6)
        var = np.full(len(b), noise**2)
    else:
        var = np.tile(2.0 * np.broadcast_to(sigma, (n,)) ** 2, k)
    root_w = 1.0 / np.sqrt(var)
    w = np.linalg.lstsq(Yr * root_w[:, None], b * root_w, rcond=None)[0]
    theta = B @ w
    m, c = theta[0], theta[1:] / theta[0]
    G = np.zeros((4, 4))
    G[0, 0], G[1:, 0], G[1:, 1:] = 1.0, -c / m, np.eye(3) / m
    cov_w = np.linalg.inv((Yr / var[:, None]).T @ Yr)
    cov = G @ B @ cov_w @ B.T @ G.T
    sv = np.zeros(4)
    sv[: B.shape[1]] = np.linalg.svd(Yr, compute_uv=False)
    return m, c, cov, (b - Y @ theta).reshape(k, n), sv


def wrist_poses(robot, q, k, rng):
    offsets = np.zeros((k, robot.nq))
    offsets[1:, -3:] = rng.uniform(-0.8, 0.8, size=(k - 1, 3))
    return q + offsets


def assert_same(est, ref, rel=1e-9):
    m, c, cov, residuals, sv = ref
    assert est.mass == pytest.approx(m, rel=rel)
    np.testing.assert_allclose(est.com_ee, c, rtol=0, atol=rel * max(1.0, np.abs(c).max()))
    np.testing.assert_allclose(est.cov, cov, rtol=0, atol=rel * np.abs(cov).max())
    np.testing.assert_allclose(est.residuals, residuals, rtol=0, atol=1e-10)
    np.testing.assert_allclose(est.singular_values, sv, rtol=0, atol=rel * sv[0])


@settings(max_examples=60, deadline=None)
@given(
    seed=st.integers(0, 2**32 - 1),
    robot_name=st.sampled_from(list(ROBOTS)),
    k=st.sampled_from([1, 2, 4]),
    std=st.sampled_from(["none", "scalar", "per_joint"]),
    mass=st.floats(0.05, 5.0),
    method=st.sampled_from(["lstsq", "ipopt"]),
)
def test_the_estimate_is_plain_least_squares(robots, seed, robot_name, k, std, mass, method):
    robot = robots[robot_name]
    rng = np.random.default_rng(seed)
    Q = wrist_poses(robot, robot.random_configuration(rng), k, rng)
    com = rng.uniform(-0.2, 0.2, size=3)
    tb, ta = payload_torques(robot, Q, mass, com)
    ta = ta + rng.normal(scale=0.02, size=Q.shape)
    sigma = {"none": None, "scalar": 0.02, "per_joint": rng.uniform(0.01, 0.04, robot.nq)}[std]
    ref = reference(robot, Q, ta - tb, sigma)
    try:
        est = cg.estimate_com(robot, Q, tb, ta, method=method, torque_std=sigma)
    except cg.EmptyGripperError:  # a light payload under noise: refused where it should be
        assert ref[0] <= 3.0 * math.sqrt(ref[2][0, 0])
        return
    except cg.UnobservableError:  # near a singularity
        assert ref[4][0] / ref[4][2 if k == 1 else 3] > 1e4 or ref[0] <= 3 * ref[2][0, 0] ** 0.5
        return
    assert_same(est, ref, rel=1e-9 if method == "lstsq" else 1e-7)
    assert est.condition_number == pytest.approx(ref[4][0] / ref[4][ref[4] > 0][-1], rel=1e-9)
    assert (est.unobservable_ee is None) == (k > 1)
    if k == 1:
        np.testing.assert_allclose(est.unobservable_ee, -est.T_world_ee[0, 2, :3], atol=1e-12)
    for a in (est.com_ee, est.cov, est.residuals, est.T_world_ee, est.singular_values):
        assert not a.flags.writeable
    if std == "none":  # the std of one reading: the residuals' over sqrt(2)
        dof = Q.size - (3 if k == 1 else 4)
        assert est.torque_std == pytest.approx(
            max(np.linalg.norm(ref[3]) / math.sqrt(dof), 1e-6) / math.sqrt(2), rel=1e-7
        )
    else:
        assert est.torque_std is None


def test_near_the_upright_singularity_the_estimate_is_refused_not_returned(robots):
    ur5 = robots["ur5"]
    rng = np.random.default_rng(3)
    for offset in (1e-2, 1e-4):
        q = np.array([0.0, -np.pi / 2 + offset, 0.0, -np.pi / 2, 0.0, 0.0])
        tb, ta = payload_torques(ur5, q, 0.8, np.array([0.01, 0.0, 0.05]))
        ta = ta + rng.normal(scale=0.01, size=6)
        try:
            est = cg.estimate_com(ur5, q, tb, ta, torque_std=0.01)
        except cg.UnobservableError:
            continue
        assert_same(est, reference(ur5, q[None], (ta - tb)[None], 0.01), rel=1e-7)
    q = np.array([0.0, -np.pi / 2 + 1e-7, 0.0, -np.pi / 2, 0.0, 0.0])
    tb, ta = payload_torques(ur5, q, 0.8, np.array([0.01, 0.0, 0.05]))
    with pytest.raises(cg.UnobservableError):  # 1e-7 rad away: near singular
        cg.estimate_com(ur5, q, tb, ta + rng.normal(scale=0.01, size=6), torque_std=0.01)


@pytest.mark.parametrize("rcond", [0.05, 0.2, 0.5])
def test_rcond_decides_by_the_singular_values(robots, rcond):
    """An estimate where every singular value of the regression across gravity exceeds rcond
    times the largest; UnobservableError where one does not."""
    ur5 = robots["ur5"]
    rng = np.random.default_rng(5)
    for _ in range(10):
        q = ur5.random_configuration(rng)
        tb, ta = payload_torques(ur5, q, 0.7, np.array([0.04, -0.03, 0.15]))
        sv = reference(ur5, q[None], (ta - tb)[None], 0.01)[4]
        if sv[2] > rcond * sv[0]:
            assert cg.estimate_com(ur5, q, tb, ta, rcond=rcond).mass == pytest.approx(0.7)
        else:
            with pytest.raises(cg.UnobservableError, match="rcond"):
                cg.estimate_com(ur5, q, tb, ta, rcond=rcond)


def test_empty_gripper_and_bad_readings_raise_the_documented_errors(robots):
    ur5 = robots["ur5"]
    q = ur5.random_configuration(np.random.default_rng(6))
    tb, ta = payload_torques(ur5, q, 0.7, np.array([0.04, -0.03, 0.15]))
    with pytest.raises(cg.EmptyGripperError, match="swapped"):
        cg.estimate_com(ur5, q, ta, tb, torque_std=0.01)
    with pytest.raises(cg.EmptyGripperError, match="MIN_MASS_KG|standard deviations"):
        cg.estimate_com(ur5, q, tb, tb)
    for bad, message in ((np.inf, "NaN or inf"), (np.nan, "NaN or inf"), (2e6, "beyond")):
        worse = ta.copy()
        worse[2] = bad
        with pytest.raises(cg.InvalidInputError, match=message):
            cg.estimate_com(ur5, q, tb, worse, torque_std=0.01)
    # many large but valid readings: the quick screen's sum exceeds the limit, each does not
    big = np.full(6, 9e5)
    est = cg.estimate_com(ur5, q, tb + big, ta + big, torque_std=0.01)
    assert est.mass == pytest.approx(0.7, rel=1e-6)


@pytest.mark.parametrize("g", [[0, 0, -9.80665], [0, 0, -1.62], [6.0, 0.0, -7.0]])
def test_gravity_comes_from_the_model(robots, g):
    """Noise-free torques measured under the model's gravity give the payload exactly, at
    any magnitude and direction (issue 33: 9.81 was assumed, 0.034 % off at 9.80665)."""
    import pinocchio as pin

    ur5 = cg.RobotModel.ur5()
    ur5.model.gravity = pin.Motion(np.array([*g, 0.0, 0.0, 0.0]))
    rng = np.random.default_rng(9)
    Q = wrist_poses(ur5, ur5.random_configuration(rng), 3, rng)
    mass, com = 0.8, np.array([0.02, -0.01, 0.12])
    tb, ta = payload_torques(ur5, Q, mass, com)
    for method in ("lstsq", "ipopt"):
        est = cg.estimate_com(ur5, Q, tb, ta, method=method, torque_std=1e-3)
        assert est.mass == pytest.approx(mass, rel=1e-9)
        np.testing.assert_allclose(est.com_ee, com, atol=1e-9)
        assert est.weight == pytest.approx(mass * np.linalg.norm(g), rel=1e-9)
    one = cg.estimate_com(ur5, Q[0], tb[0], ta[0])
    down_ee = ur5.ee_pose(Q[0])[:3, :3].T @ (np.array(g) / np.linalg.norm(g))
    np.testing.assert_allclose(one.unobservable_ee, down_ee, atol=1e-12)
    np.testing.assert_allclose(one.com_ee, com - (com @ down_ee) * down_ee, atol=1e-9)
