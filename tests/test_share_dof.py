"""The degrees of freedom of an interval whose friction share is estimated (Satterthwaite).

Checked against draws of the model itself: readings with white noise of known std plus the
friction the sides left, kappa times the sides' spread. Where the noise hides the friction on
most joints, kappa is learnt from the few joints where it shows, and the variance of an
estimate that rests on them scatters from draw to draw as a chi-square of few degrees of
freedom. The draws measure the coverage of the 95 % intervals without the code's formula;
where the friction is every reading's error the formula reduces to the readings less the
unknowns, derived in the test. kappa is REML's, fitted to each draw.
"""

import numpy as np
import pytest
from scipy.stats import t as student

from comgrasp_pin.estimation.side_friction import SideFriction, share_dof, side_friction_cov

K, N = 4, 7  # poses, joints: the live FR3's session
THETA = np.array([1.1, 0.033, -0.044, 0.055])  # (m, m c) of a payload


# per joint, as franky-sim's FR3 read them in a live session (N m): the std of a pose's
# difference of two averaged readings, and the sides' spread. The friction the sides leave
# (about 0.1 of the spread) shows above the noise on joints 2 and 4 only.
NOISE = np.array([8.4, 3.0, 6.4, 2.5, 33.0, 8.0, 765.0]) * 1e-3
SPREAD = np.array([7.0, 180.0, 6.0, 22.0, 16.0, 4.5, 500.0]) * 1e-3
KAPPA = 0.12
# another regime: the friction (spread 0.2 N m, kappa 0.3) shows above the noise on one
# joint of seven; on the others the noise (0.05 N m) hides it
ONE_JOINT_NOISE = np.r_[np.full(N - 1, 0.05), 0.005]
ONE_JOINT_SPREAD = np.r_[np.full(N - 1, 0.05), 0.2]


def problem(seed=0, noise=NOISE, spread=SPREAD):
    """(Y, noise covariance, spread): a regressor of torques of about 1 N m per kg or kg m,
    each joint's noise and spread (N m; the FR3's by default). Every pose has its joint's
    spread, so the mix rho changes nothing."""
    rng = np.random.default_rng(seed)
    Y = rng.standard_normal((K * N, 4)) * np.array([1.0, 10.0, 10.0, 10.0])
    return Y, np.diag(np.tile(noise**2, K)), np.tile(spread, (K, 1))


def draw(Y, cov, spread, kappa, rng):
    """One session: the torque differences of the model with share ``kappa``."""
    sd = np.sqrt(np.diag(cov) + kappa**2 * spread.ravel() ** 2)
    return Y @ THETA + sd * rng.standard_normal(len(sd))


def fitted(Y, cov, spread, dtau):
    """(theta_hat, its covariance, its dof) as the estimator states them (G = identity)."""
    found, cov_k = side_friction_cov(Y, dtau, cov, spread)
    W = np.linalg.inv(cov_k)
    cov_theta = np.linalg.inv(Y.T @ W @ Y)
    theta = cov_theta @ Y.T @ W @ dtau
    return theta, cov_theta, share_dof(Y, cov_k, found, np.eye(4)), found


def test_friction_on_every_reading_gives_the_readings_less_the_unknowns():
    """Noise 0: the friction is all the variance, E proportional to it, and the formula
    reduces to dof = K N - 4 exactly (tr(P E P E) = dof / kappa^4, dv = v / kappa^2)."""
    Y, _, spread = problem()
    cov = np.diag(np.full(K * N, 1e-12))
    found = SideFriction(spread, 0.5, 1.0)
    dof = share_dof(Y, cov + 0.25 * np.diag(spread.ravel() ** 2), found, np.eye(4))
    np.testing.assert_allclose(dof, K * N - 4, rtol=1e-6)


def test_no_share_is_known_noise():
    Y, cov, spread = problem()
    assert np.all(share_dof(Y, cov, SideFriction(spread, 0.0, None), np.eye(4)) == np.inf)


@pytest.mark.parametrize(
    "noise, spread, kappa, seed",
    [(NOISE, SPREAD, KAPPA, 1), (NOISE, SPREAD, KAPPA, 3),
     (ONE_JOINT_NOISE, ONE_JOINT_SPREAD, 0.3, 1)],
    ids=["fr3-1", "fr3-3", "one-joint-1"],
)  # fmt: skip
def test_intervals_of_the_stated_dof_cover_at_their_level(noise, spread, kappa, seed):
    """95 % intervals of Student's t of the stated dof hold the truth in 95 % of 2000
    (500 draws of 4 parameters: binomial sd about 0.5 %, more with the draws' parameters
    correlated): as franky-sim's FR3 reads, and where the friction shows on one joint."""
    Y, cov, spread = problem(seed, noise, spread)
    rng = np.random.default_rng(seed + 10)
    inside = 0
    for _ in range(500):
        theta, cov_theta, dof, _ = fitted(Y, cov, spread, draw(Y, cov, spread, kappa, rng))
        err = np.abs(theta - THETA) / np.sqrt(np.diag(cov_theta))
        inside += np.sum(err < student.ppf(0.975, dof))
    assert 0.925 < inside / 2000 < 0.97
