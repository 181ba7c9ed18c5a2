"""Static joint torques with stuck joint friction: joined windows and the residuals' rule.

A joint that stops under a position controller holds its stuck friction: the torque read at
rest is the gravity torque plus up to the friction's limit, with the sign of the approach.
The log here is made from an independent model (Pinocchio RNEA with a payload body,
tests/_payload) plus, at every visit of a pose, a friction torque drawn per joint with the
approach's sign, plus white noise. Approached from both sides and joined
(``T0:T1+T2:T3``), the friction cancels to first order; read from one side it does not, and
the residuals widen the interval to hold it. Readings that no rigid payload explains (a
cable) are unreliable.
"""

import numpy as np
import pytest
from _payload import panda, payload_torques
from hypothesis import given, settings
from hypothesis import strategies as st

from comgrasp_pin.errors import InvalidInputError
from comgrasp_pin.estimation.regressor import stacked_regressor
from comgrasp_pin.estimation.side_friction import side_friction_cov
from comgrasp_pin.robot_io import JointLog, estimate_from_log
from comgrasp_pin.robot_io.at_rest import parse_windows, read_window
from comgrasp_pin.robot_io.at_rest.windows import read_joined

Q = np.array(
    [
        [0.0, -0.3, 0.0, -2.2, 0.0, 2.0, 0.8],
        [0.5, -0.6, 0.3, -1.8, 1.2, 1.2, -0.6],
        [-0.4, 0.2, -0.2, -2.4, -1.0, 2.6, 1.5],
        [0.2, -0.5, 0.4, -2.0, 0.8, 1.6, 0.1],
    ]
)
MASS, COM = 0.9, np.array([0.03, -0.02, 0.06])
FRICTION_NM = (0.3, 0.9)  # the stuck friction's range at a visit (N m), as the FR3's sim shows
ASYMMETRY = 0.03  # the two sides' friction differ by up to this share
RATE_HZ, HOLD_S, MOVE_S, NOISE = 200.0, 0.6, 0.3, 0.05


@pytest.fixture(scope="module")
def robot():
    return panda()


def friction_log(robot, seed=0, common=False, asymmetry=ASYMMETRY):
    """(log, joined before, joined after, one-sided before, one-sided after).

    Each run (empty, then loaded) visits each pose twice, approaching from +, then from -;
    each visit holds HOLD_S with the friction torque of that visit. ``common``: the two
    sides' asymmetry is one draw per visit for all joints (a pose's joints err together).
    ``asymmetry``: the two sides' friction differ by up to this share.
    """
    rng = np.random.default_rng(seed)
    tb, ta = payload_torques(robot, Q, MASS, COM)
    qs, taus, windows = [], [], {False: [], True: []}
    t = 0.0
    dt = 1.0 / RATE_HZ
    for loaded, tau_g in ((False, tb), (True, ta)):
        for i, q in enumerate(Q):
            f = rng.uniform(*FRICTION_NM, size=robot.nq)
            sides = []
            for sign in (1.0, -1.0):
                u = rng.uniform(-1, 1, 1 if common else robot.nq)
                f_side = f * (1 + 3 * asymmetry * u) if common else f * (1 + asymmetry * u)
                n_move, n_hold = int(MOVE_S * RATE_HZ), int(HOLD_S * RATE_HZ)
                ramp = q + sign * 0.05 * np.sin(np.linspace(0, np.pi, n_move))[:, None]
                hold = np.tile(q, (n_hold, 1))
                qs += [ramp, hold]
                taus += [
                    np.tile(tau_g[i], (n_move, 1)),
                    np.tile(tau_g[i] + sign * f_side, (n_hold, 1)),
                ]
                t_hold = t + n_move * dt
                sides.append((t_hold + 0.1, t_hold + HOLD_S - 0.1))
                t += (n_move + n_hold) * dt
            windows[loaded].append(sides)
    q = np.concatenate(qs)
    tau = np.concatenate(taus) + NOISE * rng.standard_normal(q.shape)
    log = JointLog(np.arange(len(q)) * dt, tuple(robot.joint_names), q, tau, "friction")
    joined = {k: [(*w[0], *w[1]) for w in v] for k, v in windows.items()}
    one_side = {k: [w[0] for w in v] for k, v in windows.items()}
    return log, joined[False], joined[True], one_side[False], one_side[True]


def test_parse_joined_windows():
    assert parse_windows("1:2+3:4, 5:6", joined=True) == [(1.0, 2.0, 3.0, 4.0), (5.0, 6.0)]
    with pytest.raises(InvalidInputError, match="joined by"):
        parse_windows("1:2+3", joined=True)
    with pytest.raises(InvalidInputError):
        parse_windows("1:2+3:4")  # joins are only for the readings at rest
    with pytest.raises(InvalidInputError, match="T0 < T1"):
        parse_windows("1:2+4:3", joined=True)


def test_joined_reading_is_the_mean_of_the_spans(robot):
    log, before, *_ = friction_log(robot)
    w = before[0]
    a, b = read_window(log, w[0], w[1]), read_window(log, w[2], w[3])
    r = read_joined(log, w)
    np.testing.assert_allclose(r.tau, (a.tau + b.tau) / 2)
    np.testing.assert_allclose(r.q, (a.q + b.q) / 2)
    expected = np.sqrt(a.tau_mean_std**2 + b.tau_mean_std**2) / 2
    np.testing.assert_allclose(r.tau_mean_std, expected)
    single = read_joined(log, w[:2])
    np.testing.assert_array_equal(single.tau, a.tau)


def test_both_sides_cancel_the_friction(robot):
    log, before, after, _, _ = friction_log(robot)
    est = estimate_from_log(robot, log, before, after)
    assert est.verdict == "identified", est.reasons
    assert abs(est.mass - MASS) < 0.02 * MASS
    assert np.linalg.norm(est.com_ee - COM) < 5e-3
    # the residuals (the friction's asymmetry) exceed the samples' noise: the covariance
    # is theirs; the share left is estimated from readings where the friction dominates
    # the noise, so Satterthwaite's dof are nearly the readings less the unknowns, 4 * 7 - 4
    assert np.all(est.dof <= 4 * 7 - 4) and np.all(est.dof > 20)
    half = est.t95[0] * est.std[0]
    assert abs(est.mass - MASS) < half


def test_one_side_is_honest_not_precise(robot):
    """Read from one side, the friction stays in: the residuals widen the interval to hold it."""
    log, before, after, b1, a1 = friction_log(robot)
    joined = estimate_from_log(robot, log, before, after)
    one = estimate_from_log(robot, log, b1, a1)
    assert one.std[0] > 10 * joined.std[0]
    assert abs(one.mass - MASS) < one.t95[0] * one.std[0]


def test_readings_no_payload_explains_are_unreliable(robot):
    """A cable pulling with a torque that follows no rigid body (random per loaded pose, as
    large as the payload's): the payload explains too little of the differences."""
    log, before, after, _, _ = friction_log(robot)
    rng = np.random.default_rng(7)
    effort = log.effort.copy()
    for w in after:
        sel = (log.time >= w[0]) & (log.time <= w[3])
        effort[sel] += rng.normal(0.0, 4.0, robot.nq)
    pulled = JointLog(log.time, log.joint_names, log.position, effort, "pulled")
    est = estimate_from_log(robot, pulled, before, after)
    assert est.verdict == "unreliable"
    assert any("of the torque differences" in r for r in est.reasons), est.reasons


def test_intervals_cover_the_truth_over_seeds(robot):
    """The residuals' covariance covers the mass in about 95 % of sessions (binomial band)."""
    inside = 0
    n = 40
    for seed in range(n):
        log, before, after, _, _ = friction_log(robot, seed=100 + seed)
        est = estimate_from_log(robot, log, before, after)
        inside += abs(est.mass - MASS) < est.t95[0] * est.std[0]
    assert 0.85 * n <= inside  # P(X < 34 | n=40, p=0.95) < 0.5 %


def test_pose_errors_cover_errors_a_pose_shares(robot):
    """Errors common to a pose's joints: the poses' block sandwich (``pose_errors``) covers
    the mass at about its 95 %, with at most k - 1 = 3 degrees of freedom."""
    inside, n = 0, 40
    for seed in range(n):
        log, before, after, _, _ = friction_log(robot, seed=300 + seed, common=True)
        est = estimate_from_log(robot, log, before, after, pose_errors=True)
        assert np.all(est.dof <= 3.0 + 1e-9) and np.all(est.dof >= 1.0)
        inside += abs(est.mass - MASS) < est.t95[0] * est.std[0]
    assert 0.85 * n <= inside


def test_pose_errors_need_two_poses(robot):
    log, before, after, _, _ = friction_log(robot)
    with pytest.raises(InvalidInputError, match="2 poses or more"):
        estimate_from_log(robot, log, before[:1], after[:1], pose_errors=True)


def test_the_sides_measure_the_stuck_friction(robot):
    """Each pose's sides' spread is its stuck friction: f ~ U(a, b) per visit has
    E[f^2] = (b^3 - a^3) / (3 (b - a)), and V_ij sums the empty and the loaded run's."""
    a, b = FRICTION_NM
    expected = 2 * (b**3 - a**3) / (3 * (b - a))
    mean_sq = []
    for seed in range(5):
        log, before, after, _, _ = friction_log(robot, seed=500 + seed)
        est = estimate_from_log(robot, log, before, after)
        assert est.joint_torques.side_friction.spread.shape == (len(Q), robot.nq)
        mean_sq.append(np.mean(est.joint_torques.side_friction.spread**2))
    assert abs(np.mean(mean_sq) / expected - 1) < 0.1  # 140 draws of V: relative sd about 4 %


def test_the_share_left_and_its_intervals(robot):
    """Sides whose friction differs by up to a share s (uniform u): a run's mean at a
    pose keeps f s (u1 - u2) / 2, of variance f^2 s^2 / 6, and the sides' spread is f, so
    the difference of the two runs has the variance V_ij s^2 / 6 whatever the mix of a
    pose's own V and the joint's mean: kappa = s / sqrt(6). Estimated from 24 degrees of
    freedom (relative sd about 15 %); the mass and CoM's 95 % intervals (Student's t of
    Satterthwaite's dof, nearly 24 where the friction dominates the noise as here) cover the
    truth at about their level."""
    share, kappas, inside, z = 0.3, [], 0, []
    for seed in range(40):
        log, before, after, _, _ = friction_log(robot, seed=700 + seed, asymmetry=share)
        est = estimate_from_log(robot, log, before, after)
        kappas.append(est.joint_torques.side_friction.share_left)
        assert np.all(est.dof <= len(Q) * robot.nq - 4) and np.all(est.dof > 20)
        x = np.r_[est.mass, est.com_ee] - np.r_[MASS, COM]
        z.append(x / est.std)
        inside += np.sum(np.abs(x) < est.t95 * est.std)
    assert abs(np.median(kappas) / (share / np.sqrt(6)) - 1) < 0.15
    assert 0.90 * 160 <= inside <= 0.99 * 160  # 95 % of 160 intervals: binomial sd 1.7 %
    assert 0.8 < np.sqrt(np.mean(np.square(z))) < 1.25


def reml_nll(Y, dtau, sd):
    """REML's -log likelihood of readings of independent errors of std ``sd``, by hand:
    sum log sd + 1/2 log det(A^T A) + 1/2 |r|^2 of the whitened fit (constants dropped)."""
    A, b = Y / sd[:, None], dtau / sd
    r = b - A @ np.linalg.lstsq(A, b, rcond=None)[0]
    return np.sum(np.log(sd)) + 0.5 * np.linalg.slogdet(A.T @ A)[1] + 0.5 * r @ r


def test_the_share_is_the_restricted_likelihoods_highest():
    """kappa and rho maximise the restricted likelihood (computed here by hand): a kappa 3 %
    either side, or another rho of the grid at its own best kappa, is less likely; pure noise
    within its level leaves kappa 0 and the covariance as given."""
    rng = np.random.default_rng(3)
    k, n = 6, 5
    Y = rng.standard_normal((k * n, 4))
    spread = rng.uniform(0.1, 1.0, (k, n))
    noise, theta = np.full(k * n, 0.02), np.array([1.0, 0.1, -0.2, 0.05])
    cov = np.diag(noise**2)
    dtau = Y @ theta + 0.4 * spread.ravel() * rng.standard_normal(k * n)
    found, cov_k = side_friction_cov(Y, dtau, cov, spread)
    V = spread**2

    def nll(kappa, rho):
        scale = ((1 - rho) * V.mean(axis=0) + rho * V).ravel()
        return reml_nll(Y, dtau, np.sqrt(noise**2 + kappa**2 * scale))

    kappa, rho = found.share_left, found.own_pose
    assert 0.0 <= rho <= 1.0 and kappa > 0
    best = nll(kappa, rho)
    assert best < nll(0.97 * kappa, rho) and best < nll(1.03 * kappa, rho)
    for other in np.linspace(0.0, 1.0, 11):
        kappas = kappa * np.geomspace(0.2, 5.0, 81)
        assert best <= min(nll(x, other) for x in kappas) + 1e-9
    scale = ((1 - rho) * V.mean(axis=0) + rho * V).ravel()
    assert np.allclose(np.diag(cov_k), noise**2 + kappa**2 * scale)
    quiet = Y @ theta + 0.5 * noise * rng.standard_normal(k * n)
    found0, cov0 = side_friction_cov(Y, quiet, cov, spread)
    assert found0.share_left == 0.0 and found0.own_pose is None and cov0 is cov


def test_a_pose_whose_own_friction_errs_is_weighed_by_its_own_spread():
    """Friction left only where a pose's own spread is large (one pose of six): the mix
    goes to the pose's own spread (rho near 1), whose weights bring the estimate nearer
    the truth than the joint's mean's (rho 0, computed here by hand)."""
    rng = np.random.default_rng(11)
    k, n, theta = 6, 5, np.array([1.0, 0.1, -0.2, 0.05])
    errs_own, errs_mean = [], []
    for _ in range(30):
        Y = rng.standard_normal((k * n, 4))
        spread = np.full((k, n), 0.01)
        spread[rng.integers(k)] = 1.0  # one pose stopped with much friction
        cov = np.diag(np.full(k * n, 1e-4))
        dtau = Y @ theta + 0.5 * spread.ravel() * rng.standard_normal(k * n)
        found, cov_k = side_friction_cov(Y, dtau, cov, spread)
        w = 1 / np.sqrt(np.diag(cov_k))
        errs_own.append(np.linalg.norm(np.linalg.lstsq(Y * w[:, None], dtau * w)[0] - theta))
        w0 = 1 / np.sqrt(1e-4 + np.tile((spread**2).mean(axis=0), k))
        errs_mean.append(np.linalg.norm(np.linalg.lstsq(Y * w0[:, None], dtau * w0)[0] - theta))
        assert found.own_pose >= 0.5
    assert np.median(errs_own) < 0.5 * np.median(errs_mean)


def test_one_sided_windows_have_no_side_friction(robot):
    log, _, _, before, after = friction_log(robot)
    est = estimate_from_log(robot, log, before, after)
    assert est.joint_torques.side_friction is None


def test_the_regressor_of_the_share_is_the_estimators(robot):
    """The share is found on the stacked regressor of (m, m c): the payload's torques are
    Y theta (checked against the independent RNEA model of tests/_payload)."""
    tb, ta = payload_torques(robot, Q, MASS, COM)
    Y, _ = stacked_regressor(robot, Q)
    assert np.allclose(Y @ np.r_[MASS, MASS * COM], (ta - tb).ravel(), atol=1e-9)


@settings(max_examples=40, deadline=None)
@given(
    seed=st.integers(0, 2**31 - 1),
    k=st.integers(2, 6),
    noise=st.floats(1e-4, 0.1),
    left=st.floats(0.0, 3.0),
    zero_joints=st.integers(0, 3),
)
def test_the_share_is_found_whatever_the_readings(seed, k, noise, left, zero_joints):
    """Any regressor, spreads (some joints' zero), noise and friction left: kappa >= 0,
    rho in [0, 1] (None with kappa 0), the covariance only grows on its diagonal, and where
    kappa is inside its range the restricted likelihood (by hand) is highest there."""
    from comgrasp_pin.estimation.side_friction import MAX_SHARE, MIN_SHARE

    rng = np.random.default_rng(seed)
    n = 7
    Y = rng.standard_normal((k * n, 4))
    spread = rng.uniform(0.0, 1.0, (k, n))
    spread[:, :zero_joints] = 0.0
    cov = np.diag(np.full(k * n, noise**2))
    dtau = Y @ rng.standard_normal(4) + noise * rng.standard_normal(k * n)
    dtau += left * spread.ravel() * rng.standard_normal(k * n)
    found, cov_k = side_friction_cov(Y, dtau, cov, spread)
    assert found.share_left >= 0.0 and np.all(np.isfinite(cov_k))
    assert np.allclose(cov_k - np.diag(np.diag(cov_k)), 0.0)
    assert np.all(np.diag(cov_k) >= np.diag(cov))
    if found.share_left == 0.0:
        assert found.own_pose is None
        return
    assert 0.0 <= found.own_pose <= 1.0
    kappa, V = found.share_left, spread**2
    scale = ((1 - found.own_pose) * V.mean(axis=0) + found.own_pose * V).ravel()

    def nll(x):
        return reml_nll(Y, dtau, np.sqrt(noise**2 + x**2 * scale))

    assert nll(kappa) < nll(0.0) + 1e-9
    if 1.01 * MIN_SHARE < kappa < MAX_SHARE / 1.01:
        assert nll(kappa) <= min(nll(0.99 * kappa), nll(1.01 * kappa)) + 1e-9
