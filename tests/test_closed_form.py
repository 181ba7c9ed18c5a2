"""The estimator's fast closed form (normal equations) against plain least squares (issue 24).

The reference is written out here: the stacked regression, ``np.linalg.lstsq`` and ``svd``,
the covariance 2 sigma^2 (Y^T W Y)^-1 and the delta method. The fast path must give the same
estimate to ~1e-12 relative wherever it answers, hand ill-conditioned pose sets to the SVD
path, and raise the same error classes as before on near-singular or unobservable poses.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from _payload import panda, payload_torques
from hypothesis import given, settings
from hypothesis import strategies as st

import comgrasp_pin as cg
from comgrasp_pin.estimation import (
    batch,
    closed_form,
    estimator,
    ipopt,
    observability,
    one_pose,
    several_poses,
)
from comgrasp_pin.estimation.inputs import validate_inputs
from comgrasp_pin.estimation.regressor import stacked_regressor

ROBOTS = {"ur5": cg.RobotModel.ur5, "panda": panda}


@pytest.fixture(scope="module")
def robots() -> dict:
    return {name: make() for name, make in ROBOTS.items()}


def reference(robot, Q, dtau, sigma):
    """(mass, com_ee, cov, residuals, singular values) by SVD least squares, as the design
    states it: theta = (m, m c_ee) on the stacked regression; one pose: CoM across gravity."""
    k, n = Q.shape
    Y, T = stacked_regressor(robot, Q)
    if k == 1:
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


def fast_path(robot, Q, dtau, sigma, rcond=estimator.RCOND):
    """The closed form estimate_com takes for these poses and weights (None: declined)."""
    floor = max(closed_form.MIN_EIGEN_RATIO, 4.0 * rcond * rcond)
    if isinstance(sigma, np.ndarray):
        return closed_form.estimate(robot, Q, dtau, sigma, rcond)
    if len(Q) == 1:
        return one_pose.estimate(robot, Q[0], dtau[0], sigma, floor, closed_form.NOISE_FLOOR)
    return several_poses.estimate(robot, Q, dtau, sigma, floor, closed_form.NOISE_FLOOR)


def svd_path(robot, Q, dtau, sigma, method="lstsq", rcond=estimator.RCOND, **kwargs):
    """``estimate_com``'s general path with the Gram reduction switched off: SVD, lstsq."""
    options = {"loss": "l2", "huber_delta": 3.0, "com_prior": None, **kwargs}
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(observability, "by_gram", lambda *args: None)
        return estimator._estimate(robot, Q, dtau, sigma, method, rcond, options["loss"],
                                   options["huber_delta"], options["com_prior"], None)  # fmt: skip


def wrist_poses(robot, q, k, rng):
    offsets = np.zeros((k, robot.nq))
    offsets[1:, -3:] = rng.uniform(-0.8, 0.8, size=(k - 1, 3))
    return q + offsets


def assert_same(est, ref, rel=1e-11):
    m, c, cov, residuals, sv = ref
    assert est.mass == pytest.approx(m, rel=rel)
    np.testing.assert_allclose(est.com_ee, c, rtol=0, atol=rel * max(1.0, np.abs(c).max()))
    scale = np.abs(cov).max()
    np.testing.assert_allclose(est.cov, cov, rtol=0, atol=rel * scale)
    np.testing.assert_allclose(est.residuals, residuals, rtol=0, atol=1e-12)
    np.testing.assert_allclose(est.singular_values, sv, rtol=0, atol=rel * sv[0])


@settings(max_examples=60, deadline=None)
@given(
    seed=st.integers(0, 2**32 - 1),
    robot_name=st.sampled_from(list(ROBOTS)),
    k=st.sampled_from([1, 2, 4]),
    std=st.sampled_from(["none", "scalar", "per_joint"]),
    mass=st.floats(0.05, 5.0),
)
def test_fast_closed_form_is_plain_least_squares(robots, seed, robot_name, k, std, mass):
    robot = robots[robot_name]
    rng = np.random.default_rng(seed)
    q = robot.random_configuration(rng)
    Q = wrist_poses(robot, q, k, rng)
    com = rng.uniform(-0.2, 0.2, size=3)
    tb, ta = payload_torques(robot, Q, mass, com)
    ta = ta + rng.normal(scale=0.02, size=Q.shape)
    sigma = {"none": None, "scalar": 0.02, "per_joint": rng.uniform(0.01, 0.04, robot.nq)}[std]
    Qc, dtau, sig = validate_inputs(robot, Q, tb, ta, sigma)
    try:
        fast = fast_path(robot, Qc, dtau, sig)
    except cg.ComGraspError as exc:  # a light payload under noise: the SVD path agrees
        with pytest.raises(type(exc)):
            svd_path(robot, Qc, dtau, sig)
        return
    if fast is None:  # ill-conditioned: left to the SVD path, which must still answer
        spread = 1.0 if std != "per_joint" else sigma.max() / sigma.min()
        assert closed_form_condition(robot, Qc) * spread > closed_form.MAX_CONDITION / 2
        return
    assert_same(fast, reference(robot, Qc, dtau, sigma))
    svd = svd_path(robot, Qc, dtau, sig)
    assert fast.condition_number == pytest.approx(svd.condition_number, rel=1e-11)
    assert fast.residual_rms == pytest.approx(svd.residual_rms, rel=1e-9, abs=1e-15)
    assert (fast.noise_std is None) == (svd.noise_std is None)
    if fast.noise_std is not None:
        assert fast.noise_std == pytest.approx(svd.noise_std, rel=1e-9)
    if k == 1:
        np.testing.assert_allclose(fast.unobservable_ee, svd.unobservable_ee, atol=1e-15)
    else:
        assert fast.unobservable_ee is None and svd.unobservable_ee is None
    np.testing.assert_array_equal(fast.T_world_ee, svd.T_world_ee)
    assert not fast.com_ee.flags.writeable and not fast.cov.flags.writeable
    assert not fast.residuals.flags.writeable and not fast.T_world_ee.flags.writeable
    assert not fast.singular_values.flags.writeable
    via_api = cg.estimate_com(robot, Q, tb, ta, torque_std=sigma)
    assert via_api.mass == fast.mass and via_api.com_ee.tolist() == fast.com_ee.tolist()


def closed_form_condition(robot, Q):
    Y, T = stacked_regressor(robot, Q)
    if len(Q) == 1:
        R = T[0, :3, :3]
        Y = Y @ np.column_stack([[1, 0, 0, 0], np.r_[0, R[1]], np.r_[0, -R[0]]])
    s = np.linalg.svd(Y, compute_uv=False)
    return s[0] / s[-1]


def test_ill_conditioned_poses_go_to_the_svd_path_and_raise_as_before(robots):
    """Near the UR5's upright singularity the Gram matrix would lose digits: the fast path
    declines, and the estimate raises the SVD path's error (or answers as it does)."""
    ur5 = robots["ur5"]
    rng = np.random.default_rng(3)
    for offset in (1e-2, 1e-4, 1e-7):
        q = np.array([0.0, -np.pi / 2 + offset, 0.0, -np.pi / 2, 0.0, 0.0])
        tb, ta = payload_torques(ur5, q, 0.8, np.array([0.01, 0.0, 0.05]))
        ta = ta + rng.normal(scale=0.01, size=6)
        Q, dtau, sigma = validate_inputs(ur5, q, tb, ta, 0.01)
        assert fast_path(ur5, Q, dtau, sigma) is None
        same_as_svd(ur5, q, tb, ta, 0.01, estimator.RCOND)
    with pytest.raises(cg.UnobservableError):  # 1e-7 rad away: near singular
        cg.estimate_com(ur5, q, tb, ta, torque_std=0.01)


def same_as_svd(robot, q, tb, ta, torque_std, rcond):
    """estimate_com raises what the SVD path raises, or gives its estimate."""
    Q, dtau, sigma = validate_inputs(robot, q, tb, ta, torque_std)
    try:
        expected = svd_path(robot, Q, dtau, sigma, rcond=rcond)
    except cg.ComGraspError as exc:
        with pytest.raises(type(exc)):
            cg.estimate_com(robot, q, tb, ta, torque_std=torque_std, rcond=rcond)
        return
    est = cg.estimate_com(robot, q, tb, ta, torque_std=torque_std, rcond=rcond)
    assert est.mass == pytest.approx(expected.mass, rel=1e-11)
    np.testing.assert_allclose(est.com_ee, expected.com_ee, rtol=1e-11)


def test_same_wrist_orientation_is_rank_three_and_left_to_the_svd_path(robots):
    ur5 = robots["ur5"]
    q = ur5.random_configuration(np.random.default_rng(4))
    Q = np.array([q + [d, 0, 0, 0, 0, 0] for d in (0.0, 0.4, -0.7)])
    tb, ta = payload_torques(ur5, Q, 0.7, np.array([0.04, -0.03, 0.15]))
    Qc, dtau, sigma = validate_inputs(ur5, Q, tb, ta, 0.01)
    assert fast_path(ur5, Qc, dtau, sigma) is None
    assert cg.estimate_com(ur5, Q, tb, ta, torque_std=0.01).unobservable_ee is not None


@pytest.mark.parametrize("rcond", [0.05, 0.2, 0.5])
def test_a_large_rcond_is_decided_as_by_the_svd(robots, rcond):
    """Singular values near rcond leave the decision to the SVD path: the same outcome."""
    ur5 = robots["ur5"]
    rng = np.random.default_rng(5)
    for _ in range(10):
        q = ur5.random_configuration(rng)
        tb, ta = payload_torques(ur5, q, 0.7, np.array([0.04, -0.03, 0.15]))
        same_as_svd(ur5, q, tb, ta, 0.01, rcond)


def test_empty_gripper_and_bad_readings_raise_the_same_errors(robots):
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


@settings(max_examples=25, deadline=None)
@given(
    seed=st.integers(0, 2**32 - 1),
    k=st.sampled_from([1, 3]),
    kind=st.sampled_from(["prior", "l2", "huber"]),
    given_std=st.booleans(),
)
def test_ipopt_through_the_gram_reduction_is_the_svd_paths(robots, seed, k, kind, given_std):
    """IPOPT's problem, warm start and covariance from the Gram reduction (or, one pose with
    a prior, map_one_pose's Python floats) equal the SVD path's."""
    ur5 = robots["ur5"]
    rng = np.random.default_rng(seed)
    Q = wrist_poses(ur5, ur5.random_configuration(rng), k, rng)
    com = np.array([0.01, 0.0, 0.08]) + rng.uniform(-0.02, 0.02, 3)
    tb, ta = payload_torques(ur5, Q, 0.5, com)
    ta = ta + rng.normal(scale=0.01, size=Q.shape)
    kwargs = {
        "prior": {"com_prior": cg.AxisPrior(com, [1.0, 0.0, 0.0], 0.005)},
        "l2": {},
        "huber": {"loss": "huber"},
    }[kind]
    std = 0.01 if given_std or kind == "huber" else None
    Qc, dtau, sigma = validate_inputs(ur5, Q, tb, ta, std)
    Q = Q[0] if k == 1 else Q  # one pose as (n,): the lean MAP path
    try:
        expected = svd_path(ur5, Qc, dtau, sigma, "ipopt", **kwargs)
    except cg.ComGraspError as exc:
        with pytest.raises(type(exc)):
            cg.estimate_com(ur5, Q, tb.reshape(Q.shape), ta.reshape(Q.shape), method="ipopt",
                            torque_std=std, **kwargs)  # fmt: skip
        return
    est = cg.estimate_com(ur5, Q, tb.reshape(Q.shape), ta.reshape(Q.shape), method="ipopt",
                          torque_std=std, **kwargs)  # fmt: skip
    # (not the iteration counts: a start 1e-16 away can take IPOPT 13 iterations instead of
    # 3 to reach its tolerance, to the same optimum)
    assert est.solver_status in (*ipopt._ACCEPTED, ipopt._STALLED)
    assert (est.noise_std is None) == (expected.noise_std is None)
    assert est.mass == pytest.approx(expected.mass, rel=1e-9)
    np.testing.assert_allclose(est.com_ee, expected.com_ee, rtol=0, atol=1e-10)
    np.testing.assert_allclose(est.cov, expected.cov, rtol=1e-7, atol=1e-16)
    np.testing.assert_allclose(est.singular_values, expected.singular_values, rtol=1e-11)
    assert est.condition_number == pytest.approx(expected.condition_number, rel=1e-11)
    assert (est.unobservable_ee is None) == (expected.unobservable_ee is None)


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), log_cond=st.floats(0.0, 7.0))
def test_batch_closed_forms_are_lapacks_where_well_conditioned(seed, log_cond):
    """The batch's vectorised eigenvalues and adjugate inverses against LAPACK."""
    rng = np.random.default_rng(seed)
    V = np.linalg.qr(rng.normal(size=(50, 3, 3)))[0]
    lam = np.exp(rng.uniform(-log_cond, 0.0, size=(50, 3))) * 10 ** rng.uniform(-3, 3, (50, 1))
    N = V @ (lam[:, :, None] * V.transpose(0, 2, 1))
    N = 0.5 * (N + N.transpose(0, 2, 1))
    got_lam, got_inv = batch._eigenvalues_and_inverse(N)
    ref_lam = np.linalg.eigvalsh(N)
    gap = np.minimum(ref_lam[:, 2] - ref_lam[:, 1], ref_lam[:, 1] - ref_lam[:, 0])
    well = (ref_lam[:, 0] > closed_form.MIN_EIGEN_RATIO * ref_lam[:, 2]) & (
        gap >= one_pose.MIN_GAP * ref_lam[:, 2]
    )  # the others go to LAPACK
    scale = ref_lam[well, 2:]
    assert np.all(np.abs(got_lam[well] - ref_lam[well]) <= 1e-13 * scale)
    ref_inv = np.linalg.inv(N[well])
    tol = 1e-11 * np.abs(ref_inv).max(axis=(1, 2))[:, None, None]
    assert np.all(np.abs(got_inv[well] - ref_inv) <= tol)


def test_batch_near_a_singularity_equals_single_estimates(robots):
    """Grasps near the UR5's upright singularity go to LAPACK in the batch: the same
    estimates and refusals as one at a time."""
    ur5 = robots["ur5"]
    rng = np.random.default_rng(8)
    Q = np.array([ur5.random_configuration(rng) for _ in range(20)])
    Q[::4] = [0.0, -np.pi / 2 + 1e-2, 0.0, -np.pi / 2, 0.0, 0.0]  # cond(Yr) ~ 1e2 - 1e3
    tb, ta = payload_torques(ur5, Q, 0.8, np.array([0.01, 0.0, 0.05]))
    ta = ta + rng.normal(scale=1e-4, size=Q.shape)
    got = cg.estimate_com_batch(ur5, Q, tb, ta, torque_std=1e-4)
    for i in range(len(Q)):
        one = cg.estimate_com(ur5, Q[i], tb[i], ta[i], torque_std=1e-4)
        assert got.mass[i] == pytest.approx(one.mass, rel=1e-10)
        np.testing.assert_allclose(got.cov[i], one.cov, rtol=1e-8, atol=1e-18)
        assert got.condition_number[i] == pytest.approx(one.condition_number, rel=1e-8)
    Q[3] = [0.0, -np.pi / 2 + 1e-9, 0.0, -np.pi / 2, 0.0, 0.0]
    tb, ta = payload_torques(ur5, Q, 0.8, np.array([0.01, 0.0, 0.05]))
    with pytest.raises(cg.ComGraspError):
        cg.estimate_com_batch(ur5, Q, tb, ta, torque_std=1e-4, rcond=1e-3)
