"""The motion world of issue 26: bare arms in MuJoCo against Pinocchio, payloads against
MuJoCo's own inertia, and simulated logs against Pinocchio's RNEA of the payload alone."""

import mujoco
import numpy as np
import pinocchio as pin
import pytest
from _payload import payload_torques
from scipy.signal import butter, filtfilt

from comgrasp_pin.config import sensor_preset
from comgrasp_pin.errors import InvalidInputError, UnstablePhysicsError
from comgrasp_pin.robot_io import write_bag, write_csv
from comgrasp_pin.robot_io.log_files import read_bag, read_csv
from comgrasp_pin.simulation.arm_worlds import ARMS, EE_FRAME, arm_robot, arm_world
from comgrasp_pin.simulation.payload_motion import (
    MotionSimConfig,
    motion_reference,
    simulate_motion,
)
from comgrasp_pin.simulation.payloads import Payload, Solid, reference_payloads
from comgrasp_pin.simulation.torque_sensor import make_torque_sensor

PAYLOADS = {p.name: p for p in reference_payloads()}
HOME = {
    "panda": np.array([0.0, -0.3, 0.0, -2.2, 0.0, 2.0, 0.8]),
    "ur5": np.array([0.0, -1.6, 1.6, -1.57, -1.57, 0.0]),
}
CONFIG = MotionSimConfig(rest_s=1.5)
SENSOR = sensor_preset("realistic").torque
RATE = 500.0
SESSION_OFFSETS = 0  # offsets_seed shared by the runs of one arm: one sensor, one session


def fourier_motion(q0, duration=8.0, rate=200.0, harmonics=3, amplitude=0.35, seed=0):
    """q(t) = q0 + sum_l d_l (1 - cos(l w t)), w = 2 pi / duration: at rest at q0 at both
    ends; the last harmonic's d makes qdd zero there too (sum_l d_l l^2 = 0)."""
    rng = np.random.default_rng(seed)
    ls = np.arange(1, harmonics + 1)[:, None]
    d = rng.uniform(-1, 1, (harmonics, len(q0))) * amplitude / ls
    d[-1] = -(d[:-1] * ls[:-1] ** 2).sum(0) / harmonics**2
    t = np.arange(round(duration * rate) + 1) / rate
    w = ls[:, :, None] * 2 * np.pi / duration  # (L, 1, 1)
    arg = w * t[None, :, None]
    q = q0 + (d[:, None] * (1 - np.cos(arg))).sum(0)
    qd = (d[:, None] * w * np.sin(arg)).sum(0)
    qdd = (d[:, None] * w**2 * np.cos(arg)).sum(0)
    return t, q, qd, qdd


_RUNS: dict = {}


def run(arm, name):
    """The log of ``arm`` holding payload ``name`` ("empty": nothing), realistic sensor."""
    if (arm, name) not in _RUNS:
        payload = PAYLOADS.get(name)
        seed = 1 + list(PAYLOADS).index(name) if payload else 0
        _RUNS[arm, name] = simulate_motion(arm, payload, *fourier_motion(HOME[arm]),
                                           sensor=SENSOR, rate_hz=RATE, seed=seed,
                                           offsets_seed=SESSION_OFFSETS, config=CONFIG)  # fmt: skip
    return _RUNS[arm, name]


def with_payload(robot, payload):
    """Pinocchio's arm with the payload appended at the ee frame (independent of MuJoCo)."""
    model = pin.Model(robot.model)
    frame = model.frames[robot.ee_frame_id]
    model.appendBodyToJoint(frame.parentJoint, payload.inertia(), frame.placement)
    return model


def lowpass(x, cutoff_hz=5.0):
    b, a = butter(4, cutoff_hz / (RATE / 2))
    return filtfilt(b, a, x, axis=0)


# --- the arms and payloads -----------------------------------------------------------------


@pytest.mark.parametrize("arm", ARMS)
@pytest.mark.parametrize("payload", [None, "off_axis_weight"])
def test_mujoco_arm_dynamics_match_pinocchio(arm, payload):
    """MuJoCo's bias forces and mass matrix of the built arm are Pinocchio's RNEA and CRBA
    (the payload appended by Pinocchio itself), at random states."""
    body = PAYLOADS.get(payload)
    model, names, ee_body = arm_world(arm, body)
    robot = arm_robot(arm)
    ref = with_payload(robot, body) if body else robot.model
    ref_data, data = ref.createData(), mujoco.MjData(model)
    assert names == tuple(robot.joint_names) and ee_body == EE_FRAME[arm]
    assert model.nq == model.nv == robot.nq  # the fingers are welded, as Pinocchio locks them
    rng = np.random.default_rng(0)
    for _ in range(10):
        q, v = robot.random_configuration(rng), rng.normal(size=robot.nq)
        data.qpos[:], data.qvel[:] = q, v
        mujoco.mj_forward(model, data)
        M = np.zeros((model.nv, model.nv))
        mujoco.mj_fullM(model, data, M)
        M_pin = pin.crba(ref, ref_data, q)
        M_pin = np.triu(M_pin) + np.triu(M_pin, 1).T
        np.testing.assert_allclose(data.qfrc_bias, pin.rnea(ref, ref_data, q, v, 0 * v), atol=1e-6)
        np.testing.assert_allclose(M, M_pin, atol=1e-6)


def _mujoco_body_of(parts):
    """MuJoCo's compiled inertia of a body made of geoms (mass given, MuJoCo's formulas)."""
    spec = mujoco.MjSpec()
    body = spec.worldbody.add_body(name="payload")
    quat = {"x": [np.sqrt(0.5), 0, np.sqrt(0.5), 0], "y": [np.sqrt(0.5), -np.sqrt(0.5), 0, 0],
            "z": [1, 0, 0, 0]}  # fmt: skip  # a cylinder's geom axis is its z
    for part in parts:
        geom = body.add_geom(pos=list(part.p_centre_ee), mass=part.mass)
        if part.shape == "cylinder":
            geom.type, geom.size = (
                mujoco.mjtGeom.mjGEOM_CYLINDER,
                [part.size[0], part.size[1] / 2, 0],
            )
            geom.quat = quat[part.axis]
        elif part.shape == "box":
            geom.type, geom.size = mujoco.mjtGeom.mjGEOM_BOX, np.array(part.size) / 2
        else:
            geom.type, geom.size = mujoco.mjtGeom.mjGEOM_SPHERE, [part.size[0], 0, 0]
    model = spec.compile()
    R = np.zeros(9)
    mujoco.mju_quat2Mat(R, model.body_iquat[1])
    R = R.reshape(3, 3)
    return model.body_mass[1], model.body_ipos[1], R @ np.diag(model.body_inertia[1]) @ R.T


@pytest.mark.parametrize("name", list(PAYLOADS))
def test_payload_inertia_matches_mujoco(name):
    payload = PAYLOADS[name]
    mass, p_com, I_com = _mujoco_body_of(payload.parts)
    assert payload.mass >= 0.5
    assert payload.mass == pytest.approx(mass, rel=1e-12)
    np.testing.assert_allclose(payload.p_com_ee, p_com, atol=1e-12)
    np.testing.assert_allclose(payload.I_com_ee, I_com, atol=1e-9 * np.abs(I_com).max())
    # The ten parameters: m, m c, and the inertia moved to the ee origin (parallel axes).
    c = payload.p_com_ee
    I_o = payload.I_com_ee + payload.mass * (c @ c * np.eye(3) - np.outer(c, c))
    expected = [mass, *(mass * c), I_o[0, 0], I_o[0, 1], I_o[1, 1], I_o[0, 2], I_o[1, 2],
                I_o[2, 2]]  # fmt: skip
    np.testing.assert_allclose(payload.dynamic_parameters(), expected, atol=1e-12)


def test_bad_payloads_arms_and_motions_are_refused():
    with pytest.raises(InvalidInputError, match="mass > 0"):
        Payload("nothing", 0.0, np.zeros(3), np.eye(3))
    with pytest.raises(InvalidInputError, match="positive definite"):
        Payload("flat", 1.0, np.zeros(3), np.diag([1.0, 1.0, -1.0]))
    with pytest.raises(InvalidInputError, match="cylinder"):
        Solid("cone", (0.1,), 1.0, (0, 0, 0))
    with pytest.raises(InvalidInputError, match="'ur5', 'panda'"):
        arm_world("kuka")
    t, q, qd, qdd = fourier_motion(HOME["panda"], duration=1.0)
    with pytest.raises(InvalidInputError, match="at rest"):
        simulate_motion("panda", None, t[:-50], q[:-50], qd[:-50], qdd[:-50])
    with pytest.raises(InvalidInputError, match=r"limits of \['panda_joint4'\]"):
        simulate_motion("panda", None, t, q + [0, 0, 0, 2.5, 0, 0, 0], qd, qdd)
    with pytest.raises(InvalidInputError, match="rate_hz"):
        simulate_motion("panda", None, t, q, qd, qdd, rate_hz=300.0)


def test_a_payload_beyond_the_servo_is_reported():
    anvil = Payload("anvil", 300.0, np.array([0.0, 0.0, 0.3]), np.eye(3))
    with pytest.raises(UnstablePhysicsError, match="lost track"):
        simulate_motion("panda", anvil, *fourier_motion(HOME["panda"], duration=1.0),
                        config=MotionSimConfig(rest_s=0.2))  # fmt: skip


# --- the simulated logs ----------------------------------------------------------------------


@pytest.mark.parametrize("arm", ARMS)
def test_motion_within_limits_and_tracked_within_3_mrad(arm):
    robot = arm_robot(arm)
    t, q, qd, qdd = fourier_motion(HOME[arm])
    assert np.all(q > robot.q_lower) and np.all(q < robot.q_upper)
    for name in ("empty", *PAYLOADS):
        log = run(arm, name)
        q_d, _, _ = motion_reference(log.time, t, q, qd, qdd, CONFIG.rest_s)
        assert log.time[1] == pytest.approx(1 / RATE) and log.duration == pytest.approx(11.0)
        assert np.abs(log.position - q_d).max() < 3e-3, name


@pytest.mark.parametrize("arm", ARMS)
@pytest.mark.parametrize("name", ["box", "off_axis_weight"])
def test_efforts_at_rest_are_gravity_with_the_payload(arm, name):
    """Before the motion the arm rests: the sensor reads Pinocchio's gravity torques of the
    arm with the payload plus its offsets, within the noise, drift and friction."""
    robot, payload, log = arm_robot(arm), PAYLOADS[name], run(arm, name)
    rest = (log.time > 0.5) & (log.time < CONFIG.rest_s - 0.1)
    q_rest = log.position[rest].mean(0)
    offsets = make_torque_sensor(robot.nq, SENSOR, SESSION_OFFSETS).offsets
    _, tau_ref = payload_torques(robot, q_rest, payload.mass, payload.p_com_ee)
    error = log.effort[rest].mean(0) - offsets - tau_ref
    # drift 0.005 N m / sqrt(s) over 1.4 s (3 std: 0.018), noise 0.05 / sqrt(450), friction
    assert np.abs(error).max() < 0.03, error
    assert np.abs(offsets).max() > 0.1  # the offsets are there: the test needs them removed


@pytest.mark.parametrize("arm", ARMS)
@pytest.mark.parametrize("name", list(PAYLOADS))
def test_loaded_minus_empty_efforts_are_rnea_of_the_payload(arm, name):
    """Along the motion, the loaded run's efforts minus the empty run's are Pinocchio's RNEA
    of the payload alone (with minus without it) at the logged states, after filtering."""
    robot, payload = arm_robot(arm), PAYLOADS[name]
    loaded, empty = run(arm, name), run(arm, "empty")
    model = with_payload(robot, payload)
    data, data_empty = model.createData(), robot.model.createData()
    qd = lowpass(loaded.velocity)
    qdd = lowpass(np.gradient(qd, loaded.time, axis=0))
    reference = np.array([
        pin.rnea(model, data, *x) - pin.rnea(robot.model, data_empty, *x)
        for x in zip(loaded.position, qd, qdd)
    ])  # fmt: skip
    error = lowpass(loaded.effort - empty.effort) - reference
    # The sensors' offsets and drifts: a line through the error's means over the rests before
    # and after the motion (what the static windows are for).
    t = loaded.time
    before, after = (t > 0.5) & (t < 1.4), t > t[-1] - 1.0
    t0, t1 = t[before].mean(), t[after].mean()
    e0, e1 = error[before].mean(0), error[after].mean(0)
    error = error - (e0 + np.outer((t - t0) / (t1 - t0), e1 - e0))
    inner = slice(round(RATE), -round(RATE))  # away from the filter's ends
    rms = np.sqrt(np.mean(error[inner] ** 2, axis=0))
    signal = np.sqrt(np.mean(reference[inner] ** 2, axis=0))
    # 0.05 N m of noise per sample in both runs, 5 Hz of 250: 0.01 N m rms; what is left of
    # two 0.005 N m/sqrt(s) random walks over 11 s once their ends are removed: ~0.01 N m.
    assert rms.max() < 0.03 and np.abs(error[inner]).max() < 0.1, (rms, np.abs(error).max(0))
    assert signal.max() > 50 * 0.03  # the payload's torques stand far above the tolerance


def test_log_written_as_a_bag_and_a_csv_reads_back(tmp_path):
    log = run("panda", "rod")
    back = read_bag(write_bag(log, tmp_path / "bag", "mcap"), log.joint_names)
    assert back.joint_names == log.joint_names
    np.testing.assert_allclose(back.time, log.time, atol=1e-6)  # float stamps of 1.7e9 s
    for field in ("position", "velocity", "effort"):
        np.testing.assert_array_equal(getattr(back, field), getattr(log, field))
    back = read_csv(write_csv(log, tmp_path / "log.csv"), log.joint_names)
    for field in ("time", "position", "velocity", "effort"):
        np.testing.assert_allclose(getattr(back, field), getattr(log, field), rtol=1e-9,
                                   atol=1e-12)  # fmt: skip
