"""Torque differences with correlated errors: generalised least squares and the drift model.

References independent of the code under test: the GLS formula written here, the closed
form of E[min(s, t)] for uniform s, t, and Monte Carlo draws of the simulator's own torque
sensor (``simulation.torque_sensor``), whose drift is a random walk step by step.
"""

from __future__ import annotations

import numpy as np
import pytest
from _payload import payload_torques
from hypothesis import given, settings
from hypothesis import strategies as st

import comgrasp_pin as cg
from comgrasp_pin.config import TorqueSensorConfig
from comgrasp_pin.estimation import AxisPrior
from comgrasp_pin.estimation.drift import mean_min
from comgrasp_pin.estimation.regressor import stacked_regressor
from comgrasp_pin.procedures.cell import TorqueMeasurement
from comgrasp_pin.procedures.com_location import NoiseRule, drift_cov, pair_noise
from comgrasp_pin.simulation.torque_sensor import JointTorqueSensor
from comgrasp_pin.workcell import Q_PARK

ROBOT = cg.RobotModel.ur5()
N = ROBOT.nq


def poses(k: int, rng: np.random.Generator) -> np.ndarray:
    Q = np.tile(Q_PARK, (k, 1))
    Q[1:, 1:] += rng.uniform(-0.6, 0.6, size=(k - 1, N - 1))
    return Q


def spd(rows: int, rng: np.random.Generator, scale: float = 1e-4) -> np.ndarray:
    A = rng.standard_normal((rows, rows))
    return scale * (A @ A.T / rows + 0.2 * np.eye(rows))


@settings(max_examples=25, deadline=None)
@given(
    seed=st.integers(0, 2**32 - 1),
    k=st.integers(2, 4),
    method=st.sampled_from(["lstsq", "ipopt"]),
)
def test_gls_is_the_textbook_formula(seed, k, method):
    """theta = (Y^T S^-1 Y)^-1 Y^T S^-1 b and cov(theta) = (Y^T S^-1 Y)^-1, then the delta
    method to (m, c): written out here from the stacked regressor."""
    rng = np.random.default_rng(seed)
    Q = poses(k, rng)
    S = spd(k * N, rng)
    mass, com = rng.uniform(0.3, 2.0), rng.uniform(-0.1, 0.1, 3)
    tb, ta = payload_torques(ROBOT, Q, mass, com)
    ta = ta + (np.linalg.cholesky(S) @ rng.standard_normal(k * N)).reshape(k, N)
    Y, _ = stacked_regressor(ROBOT, Q)
    Si = np.linalg.inv(S)
    info = Y.T @ Si @ Y
    theta = np.linalg.solve(info, Y.T @ Si @ (ta - tb).ravel())
    G = np.zeros((4, 4))
    G[0, 0] = 1.0
    G[1:, 0] = -theta[1:] / theta[0] ** 2
    G[1:, 1:] = np.eye(3) / theta[0]
    cov = G @ np.linalg.inv(info) @ G.T

    est = cg.estimate_com(ROBOT, Q, tb, ta, method=method, dtau_cov=S)
    assert est.mass == pytest.approx(theta[0], rel=1e-7, abs=1e-9)
    np.testing.assert_allclose(est.com_ee, theta[1:] / theta[0], rtol=1e-6, atol=1e-8)
    np.testing.assert_allclose(est.cov, cov, rtol=1e-5, atol=1e-12)
    # the residuals are reported in N m, not whitened
    np.testing.assert_allclose(est.residuals.ravel(), (ta - tb).ravel() - Y @ theta,
                               rtol=1e-6, atol=1e-9)  # fmt: skip


@pytest.mark.parametrize("prior", [False, True])
def test_a_diagonal_covariance_is_torque_std(prior):
    """Independent readings of std sigma: dtau_cov = 2 sigma^2 I gives what torque_std does."""
    rng = np.random.default_rng(3)
    Q = poses(2, rng)
    tb, ta = payload_torques(ROBOT, Q, 0.8, np.array([0.03, 0.0, 0.06]))
    ta = ta + 0.004 * rng.standard_normal(ta.shape)
    com_prior = AxisPrior.from_rod(np.eye(4), 0.004) if prior else None
    method = "ipopt" if prior else "lstsq"
    a = cg.estimate_com(ROBOT, Q, tb, ta, method=method, torque_std=0.003, com_prior=com_prior)
    b = cg.estimate_com(ROBOT, Q, tb, ta, method=method, com_prior=com_prior,
                        dtau_cov=2 * 0.003**2 * np.eye(2 * N))  # fmt: skip
    assert b.mass == pytest.approx(a.mass, rel=1e-9)
    np.testing.assert_allclose(b.com_ee, a.com_ee, rtol=1e-7, atol=1e-10)
    np.testing.assert_allclose(b.cov, a.cov, rtol=1e-6, atol=1e-14)


@pytest.mark.parametrize(
    ("cov", "words"),
    [
        (np.eye(5), r"shape \(12, 12\)"),
        (np.full((12, 12), np.nan), "finite and symmetric"),
        (np.eye(12) + np.triu(np.ones((12, 12)), 1), "finite and symmetric"),
        (-np.eye(12), "not positive definite"),
        (np.ones((12, 12)), "not positive definite"),
        (np.eye(12).astype(complex), "complex"),
    ],
)
def test_bad_covariances_are_refused(cov, words):
    Q = poses(2, np.random.default_rng(0))
    tb, ta = payload_torques(ROBOT, Q, 0.8, np.zeros(3))
    with pytest.raises(cg.InvalidInputError, match=words):
        cg.estimate_com(ROBOT, Q, tb, ta, dtau_cov=cov)


def test_torque_std_and_a_covariance_are_not_both_taken():
    Q = poses(2, np.random.default_rng(0))
    tb, ta = payload_torques(ROBOT, Q, 0.8, np.zeros(3))
    with pytest.raises(cg.InvalidInputError, match="not both"):
        cg.estimate_com(ROBOT, Q, tb, ta, torque_std=0.01, dtau_cov=np.eye(12))


@pytest.mark.parametrize(
    ("a", "b", "expected"),
    [
        ((0.0, 1.0), (5.0, 1.0), 0.5),  # disjoint: the earlier window's mean
        ((5.0, 1.0), (0.0, 2.0), 1.0),
        ((2.0, 3.0), (2.0, 3.0), 3.0),  # the same window [a, a + T]: a + T / 3
        ((0.0, 2.0), (1.0, 2.0), None),  # overlapping: by quadrature below
    ],
)
def test_mean_min_of_uniform_times(a, b, expected):
    if expected is None:  # E[min] by a fine midpoint rule, written out
        s = a[0] + a[1] * (np.arange(2000) + 0.5) / 2000
        t = b[0] + b[1] * (np.arange(2000) + 0.5) / 2000
        expected = float(np.minimum(s[:, None], t[None, :]).mean())
    assert mean_min(a, b) == pytest.approx(expected, rel=5e-3)


def _window(sensor: JointTorqueSensor, start_step: int, steps: int, dt: float, state: dict):
    """Advance the sensor to ``start_step`` and average ``steps`` readings of zero torque."""
    sensor.skip(start_step - state["step"], dt)
    samples = sensor.read_many(np.zeros((steps, N)), dt)
    state["step"] = start_step + steps
    sem = samples.std(axis=0, ddof=1) / np.sqrt(steps)
    return samples.mean(axis=0), sem


def test_drift_covariance_matches_the_simulated_sensor():
    """The (k n, k n) covariance of the differences (held - empty window averages) at two
    poses, from ``drift_cov``, against 600 episodes of the simulator's torque sensor (its
    drift a random walk step by step, its offset per episode): every entry within the
    Monte Carlo's error."""
    dt, config = 0.01, TorqueSensorConfig(noise_std=0.05, drift_std=0.005, offset_std=0.2)
    # windows (start s, length s): empty at pose 0 and 1, then held at 0 and 1, the paper's
    # order; 10 s between a pose's empty and held windows, 6 s of them shared
    empty, held = [(0.0, 1.0), (2.5, 1.0)], [(10.0, 1.0), (13.0, 1.5)]
    order = sorted([(s, d, "e", i) for i, (s, d) in enumerate(empty)]
                   + [(s, d, "h", i) for i, (s, d) in enumerate(held)])  # fmt: skip
    diffs = []
    for episode in range(600):
        sensor = JointTorqueSensor(N, config, seed=episode)
        state, means = {"step": 0}, {}
        for start, length, kind, i in order:
            means[kind, i] = _window(sensor, round(start / dt), round(length / dt), dt, state)
        diffs.append(np.concatenate([means["h", i][0] - means["e", i][0] for i in range(2)]))
    diffs = np.array(diffs)
    sem_white = config.noise_std / np.sqrt(np.array([100, 100, 100, 150]))

    def measurement(span, sem):
        return TorqueMeasurement(np.zeros(N), np.full(N, sem), np.zeros(N), 1, span[1], span[0])

    before = [measurement(empty[i], sem_white[i]) for i in range(2)]
    after = [measurement(held[i], sem_white[2 + i]) for i in range(2)]
    model = drift_cov(before, after, config.drift_std)
    empirical = np.cov(diffs.T)
    # the sample covariance's standard error: sqrt((S_ii S_jj + S_ij^2) / n)
    se = np.sqrt((np.outer(np.diag(model), np.diag(model)) + model**2) / len(diffs))
    assert np.all(np.abs(empirical - model) < 4.0 * se + 1e-9)
    # the two poses share most of their drift: the model's correlation is large
    assert model[0, N] / model[0, 0] > 0.5


def test_stated_std_covers_the_truth_under_drift():
    """Monte Carlo of the drift model: 400 two-pose estimates with the drift's full
    covariance; their z = (estimate - truth) / stated std has rms within 0.9-1.1 (the
    independent-readings std would not know the shared drift)."""
    rng = np.random.default_rng(11)
    Q = poses(2, rng)
    mass, com = 0.6, np.array([0.05, 0.0, 0.02])
    tb, ta = payload_torques(ROBOT, Q, mass, com)

    def measurement(start, length):
        return TorqueMeasurement(np.zeros(N), np.full(N, 0.003), np.zeros(N), 1, length, start)

    before = [measurement(0.0, 1.0), measurement(3.0, 1.0)]
    after = [measurement(12.0, 1.0), measurement(15.0, 1.0)]
    rule = NoiseRule("measured", TorqueSensorConfig(drift_std=0.005), modelled=False)
    noise = pair_noise(before, after, rule)
    assert noise.std is None and noise.cov.shape == (2 * N, 2 * N)
    L = np.linalg.cholesky(noise.cov)
    z = []
    for _ in range(400):
        dtau = (ta - tb) + (L @ rng.standard_normal(2 * N)).reshape(2, N)
        est = cg.estimate_com(ROBOT, Q, np.zeros_like(dtau), dtau, dtau_cov=noise.cov)
        z.append((est.com_ee - com) / est.std[1:])
    z = np.array(z)
    rms = np.sqrt(np.mean(z**2, axis=0))
    assert np.all((rms > 0.9) & (rms < 1.1)), rms
