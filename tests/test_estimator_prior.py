"""IPOPT's problem beyond least squares: the rod-axis prior, the robust loss, the posterior
covariance, near-singular poses. References: Pinocchio RNEA with a payload body
(tests/_payload.py), the truth drawn in the test, Monte Carlo spreads."""

import numpy as np
import pytest
from _payload import panda, payload_torques, ur10

import comgrasp_pin as cg
from comgrasp_pin.estimation import ipopt

ROBOTS = {"ur5": cg.RobotModel.ur5, "panda": panda, "ur10": ur10}


@pytest.fixture(scope="module", params=list(ROBOTS))
def robot(request) -> cg.RobotModel:
    return ROBOTS[request.param]()


@pytest.fixture(scope="module")
def ur5() -> cg.RobotModel:
    return cg.RobotModel.ur5()


def _tilted_axis(rng, R_world_ee, min_deg=20.0):
    """A unit rod axis in the ee frame at least ``min_deg`` from gravity."""
    down_ee = R_world_ee.T @ np.array([0.0, 0.0, -1.0])
    while True:
        d = rng.normal(size=3)
        d /= np.linalg.norm(d)
        if np.degrees(np.arccos(min(abs(d @ down_ee), 1.0))) > min_deg:
            return d


def test_one_pose_with_prior_finds_a_com_on_the_axis(robot):
    """Noise-free, one pose: the torques fix the vertical CoM line, the prior the point on the
    axis: within 0.1 mm of the truth, mass within 1e-4 (the paper's eq. 8, any tilt)."""
    rng = np.random.default_rng(1)
    for _ in range(5):
        q = robot.random_configuration(rng)
        d = _tilted_axis(rng, robot.ee_pose(q)[:3, :3])
        com = np.array([0.0, 0.0, 0.08]) + rng.uniform(-0.05, 0.05, 3)
        point = com - rng.uniform(-0.1, 0.1) * d  # some other point of the axis
        tb, ta = payload_torques(robot, q, 0.7, com)
        prior = cg.AxisPrior(point, 3.0 * d, 0.004)
        est = cg.estimate_com(robot, q, tb, ta, method="ipopt", torque_std=0.002,
                              com_prior=prior)  # fmt: skip
        assert est.unobservable_ee is None
        assert np.linalg.norm(est.com_ee - com) < 1e-4, (est.com_ee, com)
        assert abs(est.mass - 0.7) < 1e-4 * 0.7
        assert est.cov.shape == (4, 4) and np.all(np.linalg.eigvalsh(est.cov) > 0)


def test_prior_pulls_only_where_the_torques_are_weak(ur5):
    """Several wrist orientations observe the full CoM: a prior 5 cm off (std 1 cm) barely
    moves the estimate against 0.01 N m torque noise, while at one pose it decides the
    unseen component."""
    rng = np.random.default_rng(2)
    q = ur5.random_configuration(rng)
    Q = q + np.r_[np.zeros((1, 6)), np.c_[np.zeros((3, 3)), rng.uniform(-0.8, 0.8, (3, 3))]]
    com = np.array([0.01, -0.02, 0.09])
    tb, ta = payload_torques(ur5, Q, 0.6, com)
    prior = cg.AxisPrior(com + [0.05, 0.0, 0.0], [0.0, 1.0, 0.0], 0.01)
    free = cg.estimate_com(ur5, Q, tb, ta, method="ipopt", torque_std=0.01)
    pulled = cg.estimate_com(ur5, Q, tb, ta, method="ipopt", torque_std=0.01, com_prior=prior)
    # the posterior mean is the precision-weighted combination: the shift is bounded by the
    # prior's share of the information, which is small here
    assert np.linalg.norm(pulled.com_ee - free.com_ee) < 0.25 * 0.05
    assert np.all(np.diag(pulled.cov) <= np.diag(free.cov) * (1 + 1e-9))


def test_posterior_covariance_is_honest_by_monte_carlo(ur5):
    """The truth drawn from the prior, noise drawn from the sensor model: along each principal
    axis of ``cov``, the empirical variance of the error is 0.7-1.4 of the reported one."""
    rng = np.random.default_rng(3)
    q = ur5.random_configuration(rng)
    R = ur5.ee_pose(q)[:3, :3]
    d = _tilted_axis(rng, R, 30.0)
    point, s, sigma = np.array([0.0, 0.01, 0.1]), 0.004, 0.01
    across = np.linalg.svd(np.eye(3) - np.outer(d, d))[0][:, :2]
    prior = cg.AxisPrior(point, d, s)
    errors, covs = [], []
    for _ in range(400):
        com = point + rng.uniform(-0.05, 0.05) * d + across @ rng.normal(scale=s, size=2)
        mass = 0.5
        tb, ta = payload_torques(ur5, q, mass, com)
        tb = tb + rng.normal(scale=sigma, size=6)
        ta = ta + rng.normal(scale=sigma, size=6)
        est = cg.estimate_com(ur5, q, tb, ta, method="ipopt", torque_std=sigma, com_prior=prior)
        errors.append(np.r_[est.mass - mass, est.com_ee - com])
        covs.append(est.cov)
    errors, cov = np.array(errors), np.mean(covs, axis=0)
    values, vectors = np.linalg.eigh(cov)
    ratios = np.var(errors @ vectors, axis=0) / values
    assert np.all((0.7 < ratios) & (ratios < 1.4)), ratios


def test_huber_shrugs_off_one_bad_reading(ur5):
    """Four poses, 0.01 N m noise, one reading 1.5 N m off: least squares moves the CoM by
    an order of magnitude more than noise alone; pseudo-Huber by less than 2.5x."""
    rng = np.random.default_rng(4)
    q = ur5.random_configuration(rng)
    Q = q + np.r_[np.zeros((1, 6)), np.c_[np.zeros((3, 3)), rng.uniform(-0.8, 0.8, (3, 3))]]
    com, sigma = np.array([0.02, 0.0, 0.1]), 0.01
    tb, ta = payload_torques(ur5, Q, 0.8, com)
    noise_ls, noise_hub, bad_ls, bad_hub = [], [], [], []
    for _ in range(30):
        tan = ta + rng.normal(scale=sigma, size=ta.shape)
        tbn = tb + rng.normal(scale=sigma, size=tb.shape)
        spiked = tan.copy()
        spiked[2, 1] += 1.5
        for data, ls, hub in ((tan, noise_ls, noise_hub), (spiked, bad_ls, bad_hub)):
            args = (ur5, Q, tbn, data)
            ls.append(np.linalg.norm(cg.estimate_com(*args, torque_std=sigma).com_ee - com))
            est = cg.estimate_com(*args, method="ipopt", torque_std=sigma, loss="huber")
            hub.append(np.linalg.norm(est.com_ee - com))
    noise_only = np.sqrt(np.mean(np.square(noise_ls)))
    assert np.sqrt(np.mean(np.square(bad_ls))) > 10 * noise_only
    assert np.sqrt(np.mean(np.square(bad_hub))) < 2.5 * noise_only
    # on clean data the robust loss is (nearly) least squares
    assert np.sqrt(np.mean(np.square(noise_hub))) < 1.2 * noise_only


def test_ipopt_l2_equals_the_closed_form(ur5):
    rng = np.random.default_rng(5)
    q = ur5.random_configuration(rng)
    tb, ta = payload_torques(ur5, q, 0.4, np.array([0.01, 0.02, 0.07]))
    ta = ta + rng.normal(scale=0.01, size=6)
    a = cg.estimate_com(ur5, q, tb, ta, torque_std=0.01)
    b = cg.estimate_com(ur5, q, tb, ta, method="ipopt", torque_std=0.01)
    np.testing.assert_allclose(a.com_ee, b.com_ee, atol=1e-9)
    np.testing.assert_allclose(a.cov, b.cov, rtol=1e-6, atol=1e-15)


def test_one_problem_is_built_per_size_loss_and_prior(ur5):
    ipopt.build.cache_clear()
    rng = np.random.default_rng(6)
    prior = cg.AxisPrior([0.0, 0.0, 0.08], [1.0, 0.0, 0.0], 0.005)
    for _ in range(3):
        q = ur5.random_configuration(rng)
        tb, ta = payload_torques(ur5, q, 0.5, np.array([0.0, 0.0, 0.08]))
        cg.estimate_com(ur5, q, tb, ta, method="ipopt", torque_std=0.01, com_prior=prior)
        cg.estimate_com(ur5, q, tb, ta, method="ipopt", torque_std=0.01, loss="huber")
    info = ipopt.build.cache_info()
    assert info.misses == 2 and info.hits == 4


def test_near_singular_pose_is_refused_not_returned(ur5):
    """1e-4 rad from the UR5's upright singularity, a 0.8 kg payload and 0.01 N m noise: the
    mass is not determined; an UnobservableError says so (no torque_std: the noise comes
    from the residuals)."""
    rng = np.random.default_rng(7)
    q = np.array([0.0, -np.pi / 2 + 1e-4, 0.0, -np.pi / 2, 0.0, 0.0])
    tb, ta = payload_torques(ur5, q, 0.8, np.array([0.01, 0.0, 0.05]))
    for _ in range(5):
        tbn, tan = (t + rng.normal(scale=0.01, size=6) for t in (tb, ta))
        with pytest.raises(cg.UnobservableError, match="near singular"):
            cg.estimate_com(ur5, q, tbn, tan)


def test_bad_prior_and_options(ur5):
    q = ur5.random_configuration(np.random.default_rng(8))
    tb, ta = payload_torques(ur5, q, 0.5, np.array([0.0, 0.0, 0.08]))
    for args, message in (
        (([0, 0, 0], [0, 0, 0], 0.01), "non-zero"),
        (([0, 0, 0], [np.nan, 0, 1], 0.01), "finite"),
        (([0, 0], [1, 0, 0], 0.01), r"shape \(3,\)"),
        (([0, 0, 0], [1, 0, 0], 0.0), "> 0"),
        (([0, 0, 0], [1, 0, 0], -1.0), "> 0"),
        (([0, 0, 0], [1, 0, 0], "a"), "number"),
    ):
        with pytest.raises(cg.InvalidInputError, match=message):
            cg.AxisPrior(*args)
    prior = cg.AxisPrior([0, 0, 0.08], [1, 0, 0], 0.01)
    calls = (
        ({"method": "ipopt", "loss": "cauchy", "torque_std": 0.01}, "unknown loss"),
        ({"method": "ipopt", "loss": "huber"}, "needs torque_std"),
        ({"method": "lstsq", "com_prior": prior}, "needs method='ipopt'"),
        ({"method": "ipopt", "com_prior": "axis"}, "AxisPrior"),
        ({"method": "ipopt", "huber_delta": 0.0, "torque_std": 0.01}, "huber_delta"),
        ({"rcond": "1e-6"}, "rcond"),
    )
    for kwargs, message in calls:
        with pytest.raises(cg.InvalidInputError, match=message):
            cg.estimate_com(ur5, q, tb, ta, **kwargs)
    # a prior along the direction one pose cannot see settles nothing
    down_ee = ur5.ee_pose(q)[:3, :3].T @ np.array([0.0, 0.0, -1.0])
    vertical = cg.AxisPrior([0, 0, 0.08], down_ee, 0.01)
    with pytest.raises(cg.UnobservableError, match="prior's axis"):
        cg.estimate_com(ur5, q, tb, ta, method="ipopt", torque_std=0.01, com_prior=vertical)
