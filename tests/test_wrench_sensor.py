"""The simulated wrist force/torque sensor: MuJoCo's force and torque at the ``ft_sensor`` site
against the analytic wrench at rest and Pinocchio's Newton-Euler in motion, the frame against
Pinocchio's, the error model's statistics on long draws, and its random streams apart from
every other one of a run."""

import dataclasses
import xml.etree.ElementTree as ET

import mujoco
import numpy as np
import pinocchio as pin
import pytest
from test_payload_motion import CONFIG, HOME, SENSOR, fourier_motion

from comgrasp_pin._paths import urdf_path
from comgrasp_pin.config import (
    EpisodeConfig,
    WrenchSensorConfig,
    sensor_preset,
    wrench_preset,
)
from comgrasp_pin.config import paths as config_paths
from comgrasp_pin.errors import InvalidInputError
from comgrasp_pin.robot import RobotModel
from comgrasp_pin.simulation import world
from comgrasp_pin.simulation.arm_worlds import ARMS, SENSOR_FRAME, arm_robot, arm_world
from comgrasp_pin.simulation.payload_motion import MotionSimConfig, simulate_motion
from comgrasp_pin.simulation.payloads import reference_payloads
from comgrasp_pin.simulation.sim import Simulation
from comgrasp_pin.simulation.wrench_sensor import WrenchSensor, steps_per_sample
from comgrasp_pin.workcell import GRIPPER, Q_HOME, Q_PARK

POSES = (Q_HOME, Q_PARK, Q_HOME + np.array([0.3, -0.2, 0.1, 0.5, 0.4, 1.0]))
NOISE_FREE = WrenchSensorConfig(noise_std=(0.0, 0.0))


def _subtree(model: mujoco.MjModel, root: int) -> list[int]:
    """The bodies below ``root`` (itself included), by walking each body's parents."""

    def below(b: int) -> bool:
        while b not in (0, root):
            b = model.body_parentid[b]
        return b == root

    return [b for b in range(model.nbody) if below(b)]


def _static_wrench(model, data, bodies) -> np.ndarray:
    """(6,) the wrench the resting ``bodies`` put on the site ft_sensor: f = m g and
    tau = c x m g, in the site's frame (the wrench-log convention), from their masses and
    CoMs in ``data``."""
    site = model.site(world.FT_SITE).id
    R, p = data.site_xmat[site].reshape(3, 3), data.site_xpos[site]
    mass = model.body_mass[bodies].sum()
    c_world = (model.body_mass[bodies, None] * data.xipos[bodies]).sum(0) / mass
    g_s = R.T @ model.opt.gravity
    return np.r_[mass * g_s, np.cross(R.T @ (c_world - p), mass * g_s)]


# --- where the sensor is -------------------------------------------------------------------


def test_the_sensor_frame_is_a_massless_weld_between_flange_and_gripper():
    root = ET.parse(urdf_path()).getroot()
    joints = {j.get("name"): j for j in root.iter("joint")}
    weld = joints["ft_sensor_joint"]
    assert weld.get("type") == "fixed"
    ends = (weld.find("parent").get("link"), weld.find("child").get("link"))
    assert ends == ("tool0", "ft_sensor")
    assert weld.find("origin").get("xyz") == "0 0 0" and weld.find("origin").get("rpy") == "0 0 0"
    assert joints["gripper_base_joint"].find("parent").get("link") == "ft_sensor"
    model = world.build_model()
    body = model.body(world.FT_BODY)
    assert model.body(body.parentid[0]).name == "tool0"
    assert body.mass[0] == 0 and body.jntnum[0] == 0
    assert model.body(model.body("gripper_base").parentid[0]).name == world.FT_BODY
    site = model.site(world.FT_SITE)
    assert (
        site.bodyid[0] == body.id and not site.pos.any() and np.array_equal(site.quat, [1, 0, 0, 0])
    )


def _urdf_without_sensor_frame() -> str:
    """The project's URDF as it was without the ft_sensor link: the gripper on tool0."""
    root = ET.parse(urdf_path()).getroot()
    root.remove(next(link for link in root.iter("link") if link.get("name") == "ft_sensor"))
    root.remove(next(j for j in root.iter("joint") if j.get("name") == "ft_sensor_joint"))
    for joint in root.iter("joint"):
        if joint.get("name") == "gripper_base_joint":
            joint.find("parent").set("link", "tool0")
    return ET.tostring(root, encoding="unicode")


def test_the_sensor_frame_changes_no_dynamics_of_the_cell(monkeypatch):
    """The cell built from the URDF without the sensor's weld (its site then on tool0, whose
    subtree is the same gripper) and with it: the same masses, and a fixed trajectory with
    the jaws closing gives the same joint torques and wrenches, to the bit."""
    old_urdf = _urdf_without_sensor_frame()
    new_spec = world.robot_spec

    def old_spec():
        text = old_urdf.replace("package://example-robot-data/",
                                f"{world.example_robot_data_dir()}/")  # fmt: skip
        compiler = '<mujoco><compiler fusestatic="false" discardvisual="false" strippath="false"/>'
        return mujoco.MjSpec.from_string(text.replace("</robot>", compiler + "</mujoco></robot>"))

    runs = []
    for robot_spec, ft_body in ((old_spec, "tool0"), (new_spec, world.FT_BODY)):
        monkeypatch.setattr(world, "robot_spec", robot_spec)
        monkeypatch.setattr(world, "FT_BODY", ft_body)
        sim = Simulation(world.build_model(), seed=0)
        sim.reset_arm(Q_PARK)
        sim.grip_force = 5.0
        sim.track(np.linspace(Q_PARK, Q_HOME, 800))
        taus, wrenches = [], []
        for _ in range(200):
            sim.step()
            taus.append(sim.joint_torques())
            wrenches.append(sim.wrench_true())
        masses = {sim.model.body(b).name: sim.model.body_mass[b] for b in range(sim.model.nbody)}
        runs.append((np.array(taus), np.array(wrenches), masses, sim.data.qpos.copy()))
    (tau0, w0, m0, q0), (tau1, w1, m1, q1) = runs
    assert np.array_equal(tau0, tau1) and np.array_equal(q0, q1) and np.array_equal(w0, w1)
    assert m1.pop(world.FT_BODY) == 0.0 and m0 == m1


@pytest.mark.parametrize("arm", [*ARMS, "cell"])
def test_mujoco_sensor_site_is_pinocchios_sensor_frame(arm):
    if arm == "cell":
        model, robot, frame = world.build_model(), RobotModel.ur5(), "ft_sensor"
        qadr = [model.joint(j).qposadr[0] for j in world.ARM_JOINTS]
    else:
        model, names, _ = arm_world(arm)
        robot, frame = arm_robot(arm), SENSOR_FRAME[arm]
        qadr = [model.joint(j).qposadr[0] for j in names]
    data, fid = mujoco.MjData(model), robot.model.getFrameId(frame)
    site = model.site(world.FT_SITE).id
    rng = np.random.default_rng(1)
    for _ in range(10):
        q = rng.uniform(np.maximum(robot.q_lower, -3), np.minimum(robot.q_upper, 3))
        data.qpos[qadr] = q
        mujoco.mj_kinematics(model, data)
        pin.framesForwardKinematics(robot.model, robot.data, q)
        placement = robot.data.oMf[fid]
        np.testing.assert_allclose(data.site_xpos[site], placement.translation, atol=1e-12)
        np.testing.assert_allclose(data.site_xmat[site].reshape(3, 3), placement.rotation,
                                   atol=1e-12)  # fmt: skip


# --- what it measures ------------------------------------------------------------------------


@pytest.mark.parametrize("pose", range(len(POSES)))
def test_wrench_at_rest_is_the_gripper_weight_about_the_sensor(pose):
    sim = Simulation(seed=0)
    sim.reset_arm(POSES[pose])
    sim.hold(1.0)
    bodies = _subtree(sim.model, sim.model.body(world.FT_BODY).id)
    assert len(bodies) == 6  # the weld, the palm, two fingers, the TCP, the camera
    expected = _static_wrench(sim.model, sim.data, bodies)
    np.testing.assert_allclose(sim.wrench_true(), expected, atol=1e-6)
    assert abs(np.linalg.norm(expected[:3]) - 0.89 * 9.81) < 1e-9  # the URDF's 0.65 + 3 x 0.08


@pytest.mark.parametrize("pose", range(len(POSES)))
def test_a_held_payload_adds_m_g_and_its_moment_in_the_sensor_frame(pose):
    mass, p_ee = 0.5, np.array([0.03, -0.01, 0.02])

    def hold_payload(spec):
        body = spec.body("eelink").add_body(name="payload")
        body.mass, body.ipos, body.inertia = mass, p_ee, [1e-4] * 3
        body.explicitinertial = True

    sim = Simulation(world.build_model(extras=[hold_payload]), seed=0)
    sim.reset_arm(POSES[pose])
    sim.hold(1.0)
    m, d = sim.model, sim.data
    gripper = [b for b in _subtree(m, m.body(world.FT_BODY).id) if m.body(b).name != "payload"]
    site = m.site(world.FT_SITE).id
    g_s = d.site_xmat[site].reshape(3, 3).T @ m.opt.gravity
    c_s = p_ee + [0.0, 0.0, GRIPPER.tool_to_ee]  # eelink: 0.13 m along the flange's z
    payload = sim.wrench_true() - _static_wrench(m, d, gripper)
    np.testing.assert_allclose(payload, np.r_[mass * g_s, np.cross(c_s, mass * g_s)], atol=1e-6)


def _subtree_inertia(model, data, site: int) -> pin.Inertia:
    """The spatial inertia of the site's body's subtree, in the site's frame, from MuJoCo's
    body masses, CoMs and principal inertias."""
    R_s, p_s = data.site_xmat[site].reshape(3, 3), data.site_xpos[site]
    total = pin.Inertia.Zero()
    for b in _subtree(model, model.site_bodyid[site]):
        R = R_s.T @ data.ximat[b].reshape(3, 3)
        total += pin.Inertia(model.body_mass[b], R_s.T @ (data.xipos[b] - p_s),
                             R @ np.diag(model.body_inertia[b]) @ R.T)  # fmt: skip
    return total


@pytest.mark.parametrize("arm", ARMS)
def test_wrench_in_motion_is_pinocchios_newton_euler_of_the_hand(arm):
    """Driven by arbitrary torques (2 s, joint speeds up to 2-4 rad/s), MuJoCo's sensor reads
    what Pinocchio's Newton-Euler says the hand and payload need: the frame's body regressor
    (velocity and acceleration with gravity from RNEA at MuJoCo's q, qd, qdd) times the
    subtree's ten inertial parameters (measured: 6e-13 N)."""
    model, _, _ = arm_world(arm, reference_payloads()[2])
    data = mujoco.MjData(model)
    robot = arm_robot(arm)
    data.qpos[:] = HOME[arm]
    mujoco.mj_forward(model, data)
    site = model.site(world.FT_SITE).id
    params = _subtree_inertia(model, data, site).toDynamicParameters()
    fid = robot.model.getFrameId(SENSOR_FRAME[arm])
    adr = model.sensor(world.FT_SENSORS[0]).adr[0]
    phase = np.random.default_rng(0).uniform(0, 2 * np.pi, model.nv)
    worst, largest = 0.0, 0.0
    for k in range(2000):
        drive = 4.0 * np.sin(2 * np.pi * 0.7 * k * model.opt.timestep + phase)
        data.qfrc_applied[:] = data.qfrc_bias + drive
        mujoco.mj_forward(model, data)  # what the step's own forward pass computes
        pin.rnea(robot.model, robot.data, data.qpos, data.qvel, data.qacc)
        expected = pin.frameBodyRegressor(robot.model, robot.data, fid) @ params
        measured = data.sensordata[adr : adr + 6]  # MuJoCo: the arm's wrench on the hand
        worst = max(worst, np.abs(measured - expected).max())
        largest = max(largest, np.abs(expected).max())
        mujoco.mj_step(model, data)
    assert np.abs(data.qvel).max() > 1.0 and largest > 10.0  # it did move, and load
    assert worst < 1e-9


@pytest.fixture(scope="module")
def motion_logs():
    """The UR5 holding the box, with and without the (noise-free) wrist sensor's log; exact
    encoders, so that the log's positions are the simulator's."""
    config = dataclasses.replace(CONFIG, position_std=0.0, velocity_std=0.0)
    args = ("ur5", reference_payloads()[1], *fourier_motion(HOME["ur5"]))
    kwargs = {"sensor": SENSOR, "rate_hz": 500.0, "seed": 3, "config": config}
    alone = simulate_motion(*args, **kwargs)
    joints, wrench = simulate_motion(*args, **kwargs, wrench=NOISE_FREE)
    return alone, joints, wrench


def test_simulate_motion_logs_the_wrench_beside_the_same_joint_log(motion_logs):
    alone, joints, wrench = motion_logs
    for name in ("time", "position", "velocity", "effort"):
        assert np.array_equal(getattr(alone, name), getattr(joints, name))  # RNG apart
    stride = round(500.0 / NOISE_FREE.rate_hz)
    for name in ("time", "position", "velocity", "effort"):
        assert np.array_equal(getattr(wrench, name), getattr(joints, name)[::stride])
    assert wrench.sensor_frame == "ft_sensor" and wrench.joint_names == joints.joint_names
    assert wrench.source == joints.source


def test_simulate_motion_wrench_at_rest_is_payload_and_hand_weight(motion_logs):
    """At the end of the first rest (the servo settled), the logged wrench is the static one
    of hand and box at the logged configuration, through Pinocchio's frame."""
    _, _, log = motion_logs
    model, _, _ = arm_world("ur5", reference_payloads()[1])
    data = mujoco.MjData(model)
    robot = arm_robot("ur5")
    i = np.searchsorted(log.time, CONFIG.rest_s - 0.1)
    data.qpos[:] = log.position[i]
    mujoco.mj_kinematics(model, data)
    bodies = _subtree(model, model.site_bodyid[model.site(world.FT_SITE).id])
    mass = model.body_mass[bodies].sum()
    assert abs(mass - (0.89 + 1.0)) < 1e-12  # the hand and the 1 kg box
    placement = robot.frame_pose(log.position[i], "ft_sensor")
    g_s = placement[:3, :3].T @ np.array([0.0, 0.0, -9.81])
    c_s = placement[:3, :3].T @ ((model.body_mass[bodies, None] * data.xipos[bodies]).sum(0) / mass
                                 - placement[:3, 3])  # fmt: skip
    np.testing.assert_allclose(log.wrench[i], np.r_[mass * g_s, np.cross(c_s, mass * g_s)],
                               atol=1e-4)  # fmt: skip


def test_simulate_motion_refuses_a_sensor_rate_that_does_not_divide_the_log():
    motion = fourier_motion(HOME["ur5"], duration=1.0)
    with pytest.raises(InvalidInputError, match="wrist sensor's rate_hz must divide"):
        simulate_motion("ur5", None, *motion, rate_hz=500.0, config=MotionSimConfig(rest_s=0.1),
                        wrench=WrenchSensorConfig(rate_hz=300.0))  # fmt: skip


# --- the error model -------------------------------------------------------------------------


def _zeros(n: int) -> tuple[np.ndarray, np.ndarray]:
    return np.arange(n), np.zeros((n, 6))


def test_white_noise_has_the_data_sheet_std():
    config = wrench_preset("ideal")
    readings = WrenchSensor(config, seed=4).read(*_zeros(200_000))
    expected = np.repeat(config.noise_std, 3)
    np.testing.assert_allclose(readings.std(axis=0), expected, rtol=0.01)  # 0.16 % is 1 sigma
    assert np.all(np.abs(readings.mean(axis=0)) < 4 * expected / np.sqrt(len(readings)))
    lag = (readings[1:] * readings[:-1]).mean(axis=0) / readings.var(axis=0)
    assert np.all(np.abs(lag) < 0.01)  # white: no correlation between samples


def test_bias_is_constant_and_the_offset_is_drawn_per_episode():
    bias = (1.0, 2.0, 3.0, 0.1, 0.2, 0.3)
    config = WrenchSensorConfig(noise_std=(0.0, 0.0), bias=bias, bias_std=(0.5, 0.02))
    offsets = []
    for seed in range(2000):
        readings = WrenchSensor(config, seed).read(np.array([0, 50, 999]), np.zeros((3, 6)))
        assert np.array_equal(readings[0], readings[1]) and np.array_equal(readings[0], readings[2])
        offsets.append(readings[0] - bias)
    offsets = np.array(offsets)
    std = np.repeat(config.bias_std, 3)
    np.testing.assert_allclose(offsets.std(axis=0), std, rtol=0.08)  # 1.6 % is 1 sigma
    assert np.all(np.abs(offsets.mean(axis=0)) < 4 * std / np.sqrt(len(offsets)))


def test_random_walk_drift_grows_as_the_square_root_of_time():
    config = WrenchSensorConfig(noise_std=(0.0, 0.0), drift_std=(0.01, 5e-4))
    seconds = np.array([1.0, 4.0, 16.0, 64.0])
    indices = np.round(seconds * config.rate_hz).astype(int)
    drift = np.array([WrenchSensor(config, seed).read(indices, np.zeros((4, 6)))
                      for seed in range(600)])  # fmt: skip
    std = np.repeat(config.drift_std, 3)
    ratio = drift.var(axis=0) / (std[None] ** 2 * seconds[:, None])  # (4, 6), 1 expected
    assert np.all(np.abs(ratio - 1.0) < 0.25), ratio  # 5.8 % is 1 sigma of a variance


def test_temperature_drift_is_a_ramp_of_a_rate_drawn_per_episode():
    config = WrenchSensorConfig(noise_std=(0.0, 0.0), drift_rate_std=(2e-4, 1e-5))
    rates = []
    for seed in range(1000):
        sensor = WrenchSensor(config, seed)
        readings = sensor.read(np.array([0, 100, 400]), np.zeros((3, 6)))
        np.testing.assert_allclose(readings, sensor.drift_rate * [[0.0], [1.0], [4.0]],
                                   rtol=1e-12, atol=1e-18)  # fmt: skip
        rates.append(sensor.drift_rate)
    np.testing.assert_allclose(np.std(rates, axis=0), np.repeat(config.drift_rate_std, 3),
                               rtol=0.1)  # fmt: skip


def test_a_sample_reads_the_same_whatever_was_read_before():
    config = wrench_preset("ft300s")
    truth = np.random.default_rng(0).normal(size=(1000, 6))
    whole = WrenchSensor(config, 7).read(np.arange(1000), truth)
    pieces = WrenchSensor(config, 7)
    parts = [pieces.read(np.arange(a, b), truth[a:b]) for a, b in ((0, 10), (10, 600), (600, 1000))]
    assert np.array_equal(np.vstack(parts), whole)
    sparse = WrenchSensor(config, 7)
    picked = np.array([3, 4, 250, 999])
    assert np.array_equal(sparse.read(picked, truth[picked]), whole[picked])


def test_sensor_refuses_samples_read_twice_or_out_of_order():
    sensor = WrenchSensor(wrench_preset("ideal"), 0)
    sensor.read(np.arange(10), np.zeros((10, 6)))
    with pytest.raises(InvalidInputError, match="start at 10"):
        sensor.read(np.array([5]), np.zeros((1, 6)))
    with pytest.raises(InvalidInputError, match="must increase"):
        sensor.read(np.array([12, 11]), np.zeros((2, 6)))
    with pytest.raises(InvalidInputError, match=r"wrench_true \(N, 6\)"):
        sensor.read(np.array([20]), np.zeros((1, 3)))
    with pytest.raises(InvalidInputError, match="must divide the simulation's 500 Hz"):
        steps_per_sample(WrenchSensorConfig(rate_hz=300.0), 0.002)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [({"model": "ati"}, "model must be one of"),
     ({"rate_hz": 0.0}, "rate_hz must be a number > 0"),
     ({"rate_hz": float("inf")}, "rate_hz must be a number > 0"),
     ({"noise_std": (0.1,)}, "noise_std must be"),
     ({"drift_std": (-0.1, 0.0)}, "drift_std must be"),
     ({"bias_std": (float("nan"), 0.0)}, "bias_std must be"),
     ({"drift_rate_std": (0.0, True)}, "drift_rate_std must be"),
     ({"bias": (0.0,) * 5}, "bias must be six finite numbers")],
)  # fmt: skip
def test_config_refuses_bad_numbers(kwargs, message):
    with pytest.raises(InvalidInputError, match=message):
        WrenchSensorConfig(**kwargs)
    with pytest.raises(InvalidInputError, match="the classes are"):
        wrench_preset("ati_axia80")


def test_presets_ideal_is_the_noise_alone_realistic_the_ft300s():
    ideal, realistic = sensor_preset("ideal").wrench, sensor_preset("realistic").wrench
    assert ideal == WrenchSensorConfig() == EpisodeConfig().sensors.wrench
    assert ideal.noise_std == (0.1, 0.005) and ideal.rate_hz == 100.0
    assert ideal.bias_std == ideal.drift_std == ideal.drift_rate_std == (0.0, 0.0)
    assert realistic == wrench_preset("ft300s") == sensor_preset("realistic_current").wrench
    assert realistic.noise_std == ideal.noise_std and min(realistic.bias_std) > 0
    assert wrench_preset("ur_eseries").noise_std == (3.5, 0.2)  # UR5e data sheet's precision
    record = dataclasses.asdict(sensor_preset("realistic"))  # what run.json records
    assert record["wrench"]["model"] == "ft300s" and record["wrench"]["bias_std"] == (1.0, 0.05)
    swept = config_paths.with_values(EpisodeConfig(), {"sensors.wrench.noise_std.1": 0.01})
    assert swept.sensors.wrench.noise_std == (0.1, 0.01)


# --- apart from every other random draw -------------------------------------------------------


def test_joint_torques_are_the_same_with_the_wrist_sensor_read_or_not():
    """Two worlds of one seed, the realistic torque sensor: one reads joint torques alone with
    the ideal wrist sensor, the other reads both over the same windows with the realistic
    wrist sensor. Torques and states are the same to the bit; and a wrench window reads the
    same whether or not the windows before it read the wrench."""
    torque = sensor_preset("realistic").torque
    alone = Simulation(seed=5, sensor=torque, wrench=wrench_preset("ideal"))
    both = Simulation(seed=5, sensor=torque, wrench=wrench_preset("ft300s"))
    late = Simulation(seed=5, sensor=torque, wrench=wrench_preset("ft300s"))
    for sim in (alone, both, late):
        sim.reset_arm(Q_HOME)
    for q in POSES:
        for sim in (alone, both, late):
            sim.q_des = q
        first = alone.measure_torques(0.3, 0.2)
        second, wrench = both.measure(0.3, 0.2)
        assert np.array_equal(first.tau, second.tau) and np.array_equal(first.q, second.q)
        assert np.array_equal(first.std_error, second.std_error)
        assert wrench.n_samples == 20 and wrench.sensor_frame == "ft_sensor"
        assert np.array_equal(wrench.q, second.q) and wrench.time == second.time
    assert np.array_equal(alone.data.qpos, both.data.qpos)
    for q in POSES[:2]:  # torque-only windows, then one with the wrench
        late.q_des = q
        late.measure_torques(0.3, 0.2)
    late.q_des = POSES[2]
    assert np.array_equal(late.measure_wrench(0.3, 0.2).wrench, wrench.wrench)


def test_measured_wrench_averages_to_the_truth_within_its_error():
    sim = Simulation(seed=2, wrench=wrench_preset("ideal"))
    sim.reset_arm(Q_HOME)
    measured = sim.measure_wrench(0.5, 1.0)
    assert measured.n_samples == 100 and measured.duration == pytest.approx(1.0)
    z = (measured.wrench - sim.wrench_true()) / measured.std_error
    assert np.all(np.abs(z) < 4.5)
    expected_se = np.repeat(wrench_preset("ideal").noise_std, 3) / 10.0
    np.testing.assert_allclose(measured.std_error, expected_se, rtol=0.35)
