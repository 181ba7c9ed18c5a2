"""The static estimate's error bars, two-sided (issue 33, item 7).

A stated covariance can be wrong both ways: too narrow (over-confident) or too wide (an error
bar that never fails a check). Each test draws Gaussian noise on both torque readings (or a
correlated drift, or the truth from an ``AxisPrior``), estimates through the public
``estimate_com``, and requires the rms of z = (estimate - truth) / stated std, pooled over the
draws and taken per observable component, to lie in RMS_Z_BAND. With a correct covariance z
is standard normal (the model is linear in (m, m c); the CoM's ratio is nearly linear at
these noise levels) and the rms of a few hundred draws is 1 +- 0.05; a covariance whose
variance is 3 times too large or too small gives rms z 0.58 or 1.73 and fails, 100 times
(std 10 times) gives 0.1 or 10.

Independent reference: the torques are Pinocchio's RNEA with the payload appended as a body
(``_payload.payload_torques``), not the estimator's regressor.
"""

import numpy as np
import pytest
from _payload import payload_torques

import comgrasp_pin as cg

RMS_Z_BAND = (0.8, 1.25)
Q0 = np.array([0.3, -1.4, 1.5, -1.7, -1.5, 0.4])
WRIST = np.array([[0.0, 0.0, 0.0], [0.6, -0.5, 0.7], [-0.5, 0.6, -0.8], [0.4, 0.7, 1.2]])
MASS, COM_EE = 0.5, np.array([0.03, -0.01, 0.12])
SIGMA = 0.02  # N m, the std of each torque reading


@pytest.fixture(scope="module")
def robot():
    return cg.RobotModel.ur5()


def _poses(k: int) -> np.ndarray:
    """Q0 (k = 1, shape (6,)) or Q0 and k - 1 wrist variations (k, 6)."""
    if k == 1:
        return Q0.copy()
    Q = np.tile(Q0, (k, 1))
    Q[:, 3:] += WRIST[:k]
    return Q


def _observable_z(est, mass: float, com_ee: np.ndarray) -> np.ndarray:
    """z of the mass and of the CoM's observable components: all three, or for one pose the
    two across ``est.unobservable_ee`` (its component along gravity is not estimated)."""
    err = np.r_[est.mass - mass, est.com_ee - com_ee]
    if est.unobservable_ee is None:
        basis = np.eye(4)
    else:  # an orthonormal basis of the plane across the unobservable direction
        u = np.asarray(est.unobservable_ee)
        across = np.linalg.svd(np.eye(3) - np.outer(u, u))[0][:, :2]
        basis = np.zeros((4, 3))
        basis[0, 0], basis[1:, 1:] = 1.0, across
    cov = basis.T @ est.cov @ basis
    return (basis.T @ err) / np.sqrt(np.diag(cov))


def _rms_z(z: np.ndarray) -> np.ndarray:
    """(components,) rms over the draws, and the pooled rms last."""
    z = np.asarray(z)
    return np.r_[np.sqrt(np.mean(z**2, axis=0)), np.sqrt(np.mean(z**2))]


def _assert_in_band(rms: np.ndarray) -> None:
    lo, hi = RMS_Z_BAND
    assert np.all((rms > lo) & (rms < hi)), f"rms z {np.round(rms, 3)} outside {RMS_Z_BAND}"


def white_noise_rms_z(robot, k: int, method: str, draws: int, seed: int) -> np.ndarray:
    """rms z over ``draws`` estimates with independent noise SIGMA on every reading."""
    rng = np.random.default_rng(seed)
    Q = _poses(k)
    tau_before, tau_after = payload_torques(robot, Q, MASS, COM_EE)
    z = []
    for _ in range(draws):
        before = tau_before + rng.normal(scale=SIGMA, size=np.shape(Q))
        after = tau_after + rng.normal(scale=SIGMA, size=np.shape(Q))
        est = cg.estimate_com(robot, Q, before, after, torque_std=SIGMA, method=method)
        z.append(_observable_z(est, MASS, COM_EE))
    return _rms_z(z)


def prior_rms_z(robot, k: int, draws: int, seed: int, prior_std: float = 0.01) -> np.ndarray:
    """rms z of IPOPT with an ``AxisPrior``, the truth drawn from the prior itself.

    The rod's axis runs along ee x through (0, 0, 0.1): across gravity at Q0, so that with
    one pose the prior pins the component along gravity the torques cannot see. Each draw's
    true CoM is a point of the axis (a uniform position along it) plus a Gaussian offset of
    ``prior_std`` in each of the two directions across it: the distribution the prior
    states, so the posterior's covariance is the right error bar over the draws.
    """
    rng = np.random.default_rng(seed)
    Q = _poses(k)
    point, direction = np.array([0.0, 0.0, 0.1]), np.array([1.0, 0.0, 0.0])
    prior = cg.AxisPrior(point, direction, prior_std)
    z = []
    for _ in range(draws):
        com = point + rng.uniform(-0.05, 0.05) * direction
        com[1:] += prior_std * rng.standard_normal(2)
        tau_before, tau_after = payload_torques(robot, Q, MASS, com)
        before = tau_before + rng.normal(scale=SIGMA, size=np.shape(Q))
        after = tau_after + rng.normal(scale=SIGMA, size=np.shape(Q))
        est = cg.estimate_com(robot, Q, before, after, torque_std=SIGMA, method="ipopt",
                              com_prior=prior)  # fmt: skip
        assert est.unobservable_ee is None  # the prior pins the direction along gravity
        z.append(_observable_z(est, MASS, com))
    return _rms_z(z)


def drift_covariance(k: int, n: int) -> np.ndarray:
    """(k n, k n) covariance of stacked torque differences: white noise on each reading plus
    a per-joint drift shared by the poses, decaying with the poses' distance in time."""
    lag = np.abs(np.subtract.outer(np.arange(k), np.arange(k)))
    drift_std = 0.03 * (1 + np.arange(n) / n)  # N m, larger on the base joints' side
    return 2 * SIGMA**2 * np.eye(k * n) + np.kron(0.8**lag, np.diag(drift_std**2))


def drift_rms_z(robot, k: int, draws: int, seed: int) -> np.ndarray:
    """rms z of the ``dtau_cov`` path: differences drawn from ``drift_covariance``."""
    rng = np.random.default_rng(seed)
    Q = _poses(k)
    tau_before, tau_after = payload_torques(robot, Q, MASS, COM_EE)
    C = drift_covariance(k, robot.nq)
    L = np.linalg.cholesky(C)
    z = []
    for _ in range(draws):
        dtau = (tau_after - tau_before) + (L @ rng.standard_normal(len(C))).reshape(k, -1)
        est = cg.estimate_com(robot, Q, np.zeros_like(dtau), dtau, dtau_cov=C)
        z.append(_observable_z(est, MASS, COM_EE))
    return _rms_z(z)


@pytest.mark.parametrize("method", ["lstsq", "ipopt"])
@pytest.mark.parametrize("k", [1, 3])
def test_white_noise_error_bars_are_neither_too_wide_nor_too_narrow(robot, k, method):
    _assert_in_band(white_noise_rms_z(robot, k, method, draws=300, seed=10 + k))


@pytest.mark.parametrize("k", [1, 3])
def test_an_axis_prior_posterior_covers_a_truth_drawn_from_the_prior(robot, k):
    _assert_in_band(prior_rms_z(robot, k, draws=300, seed=20 + k))


def test_correlated_drift_error_bars_are_neither_too_wide_nor_too_narrow(robot):
    _assert_in_band(drift_rms_z(robot, 3, draws=300, seed=30))
