"""Static torque measurements as a real arm needs them: the windows and the approach
(procedures/trial_steps.py), the differences' noise (procedures/com_location.py).

The window rules against sample statistics computed here from the samples themselves; the
same-direction approach in MuJoCo with a current-based (friction, hysteresis) reading.
"""

from dataclasses import replace

import numpy as np
import pytest

from comgrasp_pin.config import EpisodeConfig, TrialConfig, hardware_trial
from comgrasp_pin.procedures import com_location, trial_steps
from comgrasp_pin.procedures.cell import TorqueMeasurement

Q_HOLD = np.array([0.3, -1.6, 1.7, -1.7, -1.57, 0.5])  # the arm held out over the table


def _measurement(samples: np.ndarray, dt: float = 0.002, time: float = 0.0):
    n = len(samples)
    return TorqueMeasurement(samples.mean(axis=0), samples.std(axis=0, ddof=1) / np.sqrt(n),
                             np.zeros(6), n, n * dt, time)  # fmt: skip


def _rule(config: EpisodeConfig) -> com_location.NoiseRule:
    trial = config.trial
    modelled = trial.tau_before != "measured"
    return com_location.NoiseRule(trial.torque_std_from, config.sensors.torque, modelled)


def test_two_windows_combine_as_one_window_of_all_their_samples():
    rng = np.random.default_rng(0)
    a, b = rng.normal(1.0, 0.1, (500, 6)), rng.normal(1.0, 0.1, (700, 6))
    both = trial_steps.combine(_measurement(a), _measurement(b))
    np.testing.assert_allclose(both.tau, np.vstack([a, b]).mean(axis=0), rtol=1e-12)
    assert both.n_samples == 1200 and both.duration == pytest.approx(2.4)
    # the standard error of 1200 samples of std 0.1
    np.testing.assert_allclose(both.std_error, 0.1 / np.sqrt(1200), rtol=0.1)


def test_the_window_grows_with_the_measured_noise_to_its_limit():
    rng = np.random.default_rng(1)
    quiet = _measurement(rng.normal(0.0, 0.05, (500, 6)))  # 2.2 mN m after 1 s
    noisy = _measurement(rng.normal(0.0, 0.10, (500, 6)))  # 4.5 mN m after 1 s
    assert trial_steps.extra_window(quiet, 0.003, 4.0) == 0.0
    worst = float(noisy.std_error.max())
    # white noise: sem^2 * T is constant, so T = 1 s * (worst / 0.003)^2
    assert trial_steps.extra_window(noisy, 0.003, 4.0) == pytest.approx((worst / 0.003) ** 2 - 1.0)
    assert trial_steps.extra_window(noisy, 0.001, 4.0) == pytest.approx(3.0)  # capped at 4 s
    assert trial_steps.extra_window(noisy, 0.0, 4.0) == 0.0  # no target: the fixed window


def test_pair_std_from_the_spec_and_from_the_measurements():
    rng = np.random.default_rng(2)
    before = _measurement(rng.normal(0.0, 0.05, (500, 6)), time=10.0)
    after = _measurement(rng.normal(0.0, 0.05, (500, 6)), time=30.0)
    spec = com_location.pair_std([before], [after], _rule(EpisodeConfig()))
    assert spec == pytest.approx(0.05 / np.sqrt(500))
    config = EpisodeConfig(trial=hardware_trial(TrialConfig()))
    config = replace(config, sensors=replace(config.sensors, torque=replace(
        config.sensors.torque, drift_std=0.005)))  # fmt: skip
    measured = com_location.pair_std([before], [after], _rule(config))
    # a difference of two readings: both variances and a random walk's over the 20 s between
    by_hand = np.sqrt(0.5 * (before.std_error**2 + after.std_error**2 + 0.005**2 * 20.0))
    np.testing.assert_allclose(measured, by_hand, rtol=1e-12)
    one_reading = com_location.pair_std([None], [after], _rule(config))  # tau_before from the model
    np.testing.assert_allclose(one_reading, np.sqrt(0.5) * after.std_error, rtol=1e-12)


@pytest.mark.slow
def test_the_same_approach_cancels_a_current_readings_friction():
    """A UR CB3-style reading (Coulomb 1-3 N m, hysteresis) at one pose, reached from above
    and from below in every joint: 2 x Coulomb apart; reached through the same approach pose
    from either side: the same to the noise and drift (the procedure's mitigation)."""
    from comgrasp_pin.experiments.trials import episode_config
    from comgrasp_pin.simulation.cell import SimCell
    from comgrasp_pin.simulation.scene import Scene, World

    config = episode_config(sensors="realistic_current")
    world = World(Scene.sample("obj2", 0), config, 0)
    try:
        cell, trial = SimCell(world), config.trial
        straight = replace(trial, approach_deg=0.0)
        coulomb = np.array(config.sensors.torque.coulomb)
        readings = {}
        for name, rule in (("straight", straight), ("approach", trial)):
            for side in (+1.0, -1.0):
                cell.move_to(Q_HOLD + side * np.radians(8.0), duration=1.5)
                trial_steps.arrive(cell, Q_HOLD, rule.approach_deg, rule.approach_time,
                                   duration=1.5)  # fmt: skip
                readings[name, side] = trial_steps.average(
                    cell, 0.5, rule.window, rule.window_sem, rule.window_max
                ).tau
    finally:
        world.close()
    # from above, every joint last moved down: the friction reads -coulomb; from below +
    straight_gap = readings["straight", 1.0] - readings["straight", -1.0]
    np.testing.assert_allclose(straight_gap, -2 * coulomb, atol=0.1)
    approach_gap = readings["approach", 1.0] - readings["approach", -1.0]
    np.testing.assert_allclose(approach_gap, 0.0, atol=0.1)
