"""The joint-torque reading is what a joint torque sensor would report."""

import mujoco
import numpy as np
import pytest

from comgrasp_pin.simulation import Simulation, build_model

G = np.array([0.0, 0.0, -9.81])
Q_HOLD = np.array([0.3, -1.6, 1.7, -1.7, -1.57, 0.5])


def test_reading_equals_gravity_torques_when_settled(ur5):
    sim = Simulation()
    sim.reset_arm(Q_HOLD + 0.01)
    sim.q_des = Q_HOLD
    sim.hold(1.0)
    # In steady state the integral servo leaves no position error, so the reading is the
    # static torque at the commanded configuration.
    np.testing.assert_allclose(sim.q, Q_HOLD, atol=1e-7)
    np.testing.assert_allclose(sim.joint_torques(), ur5.gravity_torques(sim.q), atol=1e-4)


def _weld_point_mass(mass, p_gripper):
    def extra(spec: mujoco.MjSpec) -> None:
        body = spec.body("gripper_base").add_body(name="payload", pos=list(p_gripper))
        body.mass = mass
        body.ipos = [0.0, 0.0, 0.0]
        body.inertia = [1e-7, 1e-7, 1e-7]
        body.explicitinertial = 1

    return extra


def test_payload_torque_difference_is_analytic(ur5):
    mass, p_gripper = 0.7, np.array([0.08, -0.02, 0.13])
    readings = []
    for extras in [(), (_weld_point_mass(mass, p_gripper),)]:
        sim = Simulation(build_model(extras=extras))
        sim.reset_arm(Q_HOLD)
        sim.hold(1.5)
        readings.append(sim.joint_torques())
        q = sim.q
    # Analytic: the drive holds the moment of the weight about each joint axis.
    T_world_gripper = ur5.frame_pose(q, "gripper_base")
    c = T_world_gripper[:3, :3] @ p_gripper + T_world_gripper[:3, 3]
    a, p = ur5.joint_axes(q), ur5.joint_origins(q)
    expected = -np.einsum("ij,ij->i", a, np.cross(c - p, mass * G))
    np.testing.assert_allclose(readings[1] - readings[0], expected, atol=1e-3)
    assert np.abs(expected).max() > 1.0  # the check is not vacuous


def test_sensor_noise_bias_and_drift_statistics():
    from comgrasp_pin.simulation.torque_sensor import JointTorqueSensor, TorqueSensorConfig

    tau = np.array([1.0, -2.0, 3.0, 0.0, 0.5, -0.1])
    white = JointTorqueSensor(6, TorqueSensorConfig(noise_std=0.05, bias=0.2), seed=5)
    samples = np.array([white.read(tau, 1e-3) for _ in range(20000)])
    np.testing.assert_allclose(samples.mean(0), tau + 0.2, atol=4 * 0.05 / np.sqrt(20000))
    np.testing.assert_allclose(samples.std(0), 0.05, rtol=0.03)
    # A random walk of 0.01 N m / sqrt(s): after 4 s its spread over many sensors is 0.02 N m.
    drifting = JointTorqueSensor(2000, TorqueSensorConfig(noise_std=0.0, drift_std=0.01), seed=6)
    for _ in range(4000):
        last = drifting.read(np.zeros(2000), 1e-3)
    assert abs(last.std() - 0.02) < 0.02 * 0.1


def test_measured_average_is_unbiased_with_honest_error_bar(ur5):
    sim = Simulation(seed=7)
    sim.reset_arm(Q_HOLD)
    measurement = sim.measure_torques(settle=0.3, window=0.5)
    n = round(0.5 / sim.model.opt.timestep)  # one sample per control step
    assert measurement.n_samples == n
    np.testing.assert_allclose(measurement.std_error, 0.05 / np.sqrt(n), rtol=0.2)
    error = measurement.tau - ur5.gravity_torques(measurement.q)
    assert np.all(np.abs(error) < 5 * measurement.std_error), error / measurement.std_error


def test_link_sensor_offsets_change_per_episode_and_cancel_in_a_difference():
    from comgrasp_pin.config import TorqueSensorConfig
    from comgrasp_pin.simulation.torque_sensor import make_torque_sensor

    config = TorqueSensorConfig(noise_std=0.0, offset_std=0.2)
    tau = np.array([1.0, -2.0, 3.0, 0.0, 0.5, -0.1])
    first, second = (make_torque_sensor(6, config, seed) for seed in (1, 2))
    assert not np.allclose(first.offsets, second.offsets)
    np.testing.assert_allclose(first.read(tau, 1e-3), tau + first.offsets)
    # The same episode, the same offset: tau_after - tau_before is free of it.
    np.testing.assert_allclose(first.read(tau + 1.0, 1e-3) - first.read(tau, 1e-3), 1.0)
    spread = np.concatenate([make_torque_sensor(6, config, s).offsets for s in range(300)])
    assert abs(spread.std() - 0.2) < 0.02


def test_current_sensor_at_rest_keeps_the_friction_of_the_last_motion():
    from comgrasp_pin.config import TorqueSensorConfig
    from comgrasp_pin.simulation.torque_sensor import make_torque_sensor

    coulomb = (3.0, 3.0, 2.0, 1.0, 1.0, 1.0)
    config = TorqueSensorConfig(kind="current", noise_std=0.0, coulomb=coulomb,
                                viscous=(0.5,) * 6)  # fmt: skip
    sensor = make_torque_sensor(6, config, seed=3)
    tau, up, down, rest = np.ones(6), np.full(6, 0.2), np.full(6, -0.2), np.zeros(6)
    np.testing.assert_allclose(sensor.read(tau, 1e-3, up), tau + coulomb + 0.5 * up)
    after_up = sensor.read(tau, 1e-3, rest)
    sensor.read(tau, 1e-3, down)
    after_down = sensor.read(tau, 1e-3, rest)
    # The same load at rest reads 2 * Coulomb apart, by the direction the joint came from.
    np.testing.assert_allclose(after_up - after_down, 2 * np.array(coulomb))
    np.testing.assert_allclose(after_up, tau + coulomb)


def test_presets():
    from comgrasp_pin.config import EpisodeConfig, SensorConfig, sensor_preset
    from comgrasp_pin.errors import InvalidInputError

    assert sensor_preset("ideal") == SensorConfig() == EpisodeConfig().sensors
    realistic = sensor_preset("realistic")
    # D415 at the table, 1.25 m: d^2 0.08 / (f b) from Intel's tuning guide.
    assert realistic.top_depth.axial_std(1.0) == pytest.approx(0.0014, rel=0.05)
    assert realistic.side_depth.axial_std(0.5) == pytest.approx(0.00094, rel=0.05)
    assert sensor_preset("realistic_current").torque.kind == "current"
    with pytest.raises(InvalidInputError, match="presets are"):
        sensor_preset("perfect")


def _payload_estimate(ur5, mass_error, tau_before, seed):
    """The CoM estimate (theta = m, m c_ee) of a welded point mass, measured in a world whose
    gripper is ``mass_error`` heavier and 5 mm off (the model error), with tau_before
    "measured" (empty arm, same pose) or "model" (RobotModel.gravity_torques)."""
    import comgrasp_pin as cg
    from comgrasp_pin.config import TorqueSensorConfig
    from comgrasp_pin.simulation.scene import misstate_gripper

    misstate = [lambda s: misstate_gripper(s, mass_error, 0.005)] if mass_error else []
    sensor = TorqueSensorConfig(noise_std=0.05)
    taus, qs = [], []
    for extras in (misstate, misstate + [_weld_point_mass(0.5, np.array([0.02, 0.0, 0.2]))]):
        sim = Simulation(build_model(extras=extras), sensor=sensor, seed=seed)
        sim.reset_arm(Q_HOLD)
        m = sim.measure_torques(settle=1.0, window=1.0)
        taus.append(m.tau)
        qs.append(m.q)
    before = taus[0] if tau_before == "measured" else ur5.gravity_torques(qs[0])
    return cg.estimate_com(ur5, qs[1], before, taus[1]).mass


def test_measured_tau_before_absorbs_the_gripper_model_error(ur5):
    exact = _payload_estimate(ur5, 0.0, "measured", seed=4)
    with_error = _payload_estimate(ur5, 0.05, "measured", seed=4)
    from_model = _payload_estimate(ur5, 0.05, "model", seed=4)
    assert exact == pytest.approx(0.5, abs=0.01)
    assert with_error == pytest.approx(exact, abs=0.005)  # within the noise
    # Not vacuous: the model's tau_before carries the 5 % (32 g) error into the estimate.
    assert abs(from_model - 0.5) > 0.02


def test_sensors_option_reaches_the_episode_config():
    from comgrasp_pin.cli import build_parser
    from comgrasp_pin.cli.experiments import run_options
    from comgrasp_pin.config import EpisodeConfig
    from comgrasp_pin.experiments.trials import episode_config, settings_summary

    args = build_parser().parse_args(["accuracy", "--sensors", "realistic", "--noise", "0.02"])
    opts = run_options(args)
    assert opts.sensors == "realistic"
    config = episode_config(opts.noise, opts.estimator, opts.sensors)
    assert config.sensors.preset == "realistic" and config.sensors.torque.noise_std == 0.02
    assert config.sensors.top_depth.enabled and config.sensors.gripper_mass_error > 0
    assert settings_summary(sensors="realistic")["sensors"]["preset"] == "realistic"
    assert episode_config() == EpisodeConfig()  # the default is the ideal world, unchanged
    with pytest.raises(SystemExit):
        build_parser().parse_args(["demo", "--sensors", "perfect"])
