"""The joint-torque reading is what a joint torque sensor would report."""

import mujoco
import numpy as np

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
