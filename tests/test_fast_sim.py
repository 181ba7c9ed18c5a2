"""The simulation's fast paths give, to the bit, what the plain per-step code gives.

The torque sensor forms only the samples somebody reads (``skip``, ``read_many``), the
servo writes into MjData's ctrl, and a path of commands is stepped in one call (``track``):
each is checked here against the per-step formula or call it replaced.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from comgrasp_pin.config import TorqueSensorConfig
from comgrasp_pin.errors import InvalidInputError
from comgrasp_pin.simulation.servo import ArmServo
from comgrasp_pin.simulation.sim import Simulation
from comgrasp_pin.simulation.torque_sensor import make_torque_sensor

Q_HOLD = np.array([0.0, -1.2, 1.4, -1.8, -1.57, 0.3])
DT = 0.002

_configs = st.builds(
    TorqueSensorConfig,
    noise_std=st.sampled_from([0.0, 0.05]),
    drift_std=st.sampled_from([0.0, 0.005]),
    offset_std=st.sampled_from([0.0, 0.2]),
    bias=st.sampled_from([0.0, -0.1]),
)


@settings(max_examples=30, deadline=None)
@given(
    config=_configs,
    plan=st.lists(
        st.tuples(st.sampled_from(["skip", "many", "one"]), st.integers(0, 2500)),
        min_size=1,
        max_size=6,
    ),  # fmt: skip
    seed=st.integers(0, 2**31),
)
def test_link_sensor_skip_and_read_many_are_read_per_step(config, plan, seed):
    fast, plain = make_torque_sensor(6, config, seed), make_torque_sensor(6, config, seed)
    rng = np.random.default_rng(seed)
    for what, count in plan:  # the blocks of noise are 2048 steps: plans cross them
        tau = rng.normal(size=(max(count, 1), 6))
        if what == "skip":
            fast.skip(count, DT)
            for row in tau[:count]:
                plain.read(row, DT)
        elif what == "many":
            got = fast.read_many(tau, DT)
            expected = np.array([plain.read(row, DT) for row in tau])
            np.testing.assert_array_equal(got, expected)
        else:
            np.testing.assert_array_equal(fast.read(tau[0], DT), plain.read(tau[0], DT))
    last = rng.normal(size=6)  # the states (noise stream, drift) end the same
    np.testing.assert_array_equal(fast.read(last, DT), plain.read(last, DT))


@settings(max_examples=20, deadline=None)
@given(n=st.integers(1, 3000), still=st.floats(0.0, 1.0), seed=st.integers(0, 2**31))
def test_current_sensor_read_many_keeps_the_friction_of_each_steps_last_motion(n, still, seed):
    config = TorqueSensorConfig(
        kind="current",
        noise_std=0.1,
        drift_std=0.005,
        offset_std=0.2,
        coulomb=(3.0, 3.0, 2.0, 1.0, 1.0, 1.0),
        viscous=(0.5,) * 6,
    )
    fast, plain = make_torque_sensor(6, config, seed), make_torque_sensor(6, config, seed)
    rng = np.random.default_rng(seed)
    qd = rng.normal(scale=0.01, size=(n, 6))
    qd[rng.random((n, 6)) < still] = 0.0  # joints at rest for a while: the sign is held
    tau = rng.normal(size=(n, 6))
    expected = np.array([plain.read(t, DT, v) for t, v in zip(tau, qd, strict=True)])
    np.testing.assert_array_equal(fast.read_many(tau, DT, qd), expected)
    np.testing.assert_array_equal(fast.friction_sign, plain.friction_sign)


def test_a_velocity_dependent_sensor_cannot_skip():
    sensor = make_torque_sensor(6, TorqueSensorConfig(kind="current"), 1)
    with pytest.raises(InvalidInputError, match="velocities"):
        sensor.skip(3, DT)


@settings(max_examples=50, deadline=None)
@given(seed=st.integers(0, 2**31), limit=st.floats(0.01, 5.0))
def test_servo_writing_into_ctrl_is_the_plain_formula(seed, limit):
    rng = np.random.default_rng(seed)
    servo = ArmServo(6, kp=800.0, ki=4.0, tau_i_limit=limit)
    tau_i = np.zeros(6)
    out = np.empty(6)
    for _ in range(20):
        q, q_des, tau_ff = rng.normal(size=(3, 6))
        servo.ctrl(q, q_des, tau_ff, DT, out)
        tau_i = np.clip(tau_i + (4.0 * 800.0 * DT) * (q_des - q), -limit, limit)
        np.testing.assert_array_equal(out, q_des + (tau_ff + tau_i) * (1.0 / 800.0))
        np.testing.assert_array_equal(servo.tau_i, tau_i)
    fresh = ArmServo(6, kp=800.0, ki=4.0, tau_i_limit=limit)  # without ``out``: a new array
    q, q_des, tau_ff = rng.normal(size=(3, 6))
    tau_i = np.clip((4.0 * 800.0 * DT) * (q_des - q), -limit, limit)
    np.testing.assert_array_equal(fresh.ctrl(q, q_des, tau_ff, DT),
                                  q_des + (tau_ff + tau_i) * (1.0 / 800.0))  # fmt: skip


def _sensor_reader(sim: Simulation) -> None:
    """An observer that reads the sensor at every step (the old, eager sampling)."""
    sim.tau_measured  # noqa: B018


def test_lazy_sensor_windows_and_tracking_match_per_step_sampling_to_the_bit():
    config = TorqueSensorConfig(noise_std=0.05, drift_std=0.005, offset_std=0.2)
    lazy, eager = Simulation(sensor=config, seed=4), Simulation(sensor=config, seed=4)
    eager.observers.append(_sensor_reader)
    path = Q_HOLD + np.linspace(0.0, 0.05, 400)[:, None]
    results = []
    for sim in (lazy, eager):
        sim.reset_arm(Q_HOLD)
        sim.hold(0.3)
        sim.track(path)
        first = sim.measure_torques(settle=0.2, window=0.3)
        sim.hold(0.1)
        second = sim.measure_torques(settle=0.0, window=0.2)
        results.append((first, second, sim.tau_measured.copy(), sim.data.qpos.copy()))
    for a, b in zip(*results, strict=True):
        if isinstance(a, np.ndarray):
            np.testing.assert_array_equal(a, b)
        else:
            for field in ("tau", "std_error", "q"):
                np.testing.assert_array_equal(getattr(a, field), getattr(b, field))
    assert not np.array_equal(results[0][0].tau, results[0][1].tau)  # the readings moved


def test_track_is_one_step_per_commanded_row():
    path = Q_HOLD + np.linspace(0.0, 0.1, 300)[:, None] * np.array([1, -1, 1, 0, 1, 0])
    tracked, stepped = Simulation(seed=2), Simulation(seed=2)
    for sim in (tracked, stepped):
        sim.reset_arm(Q_HOLD)
    tracked.track(path)
    for row in path:
        stepped.q_des = row
        stepped.step(1)
    np.testing.assert_array_equal(tracked.data.qpos, stepped.data.qpos)
    np.testing.assert_array_equal(tracked.data.ctrl, stepped.data.ctrl)
    np.testing.assert_array_equal(tracked.q_des, path[-1])
    assert tracked.data.time == stepped.data.time
    assert np.isclose(tracked.data.time, 300 * tracked.model.opt.timestep)
