"""The payload from a wrist force/torque sensor at rest: estimation.wrench,
robot_io.at_rest.wrench_static.

References: the wrench of a hanging body written out in the test (f = m g, tau = c x m g in the
sensor frame), the URDF's inertials read with xml.etree, and the coverage of the intervals over
many noisy draws.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from comgrasp_pin.errors import InvalidInputError, LogError, UnobservableError
from comgrasp_pin.estimation.wrench import fit_static_wrench
from comgrasp_pin.estimation.wrench_com import tool_beyond
from comgrasp_pin.planning.measurement_poses import plan_measurement_poses
from comgrasp_pin.robot import RobotModel
from comgrasp_pin.robot_io.at_rest.wrench_static import estimate_wrench_static
from comgrasp_pin.robot_io.log_files.log_types import WrenchLog

G = np.array([0.0, 0.0, -9.81])
TILTS = Rotation.from_rotvec(np.radians([[0, 0, 0], [60, 0, 0], [0, 60, 0], [-45, -45, 0]]))


def _orientations(seed: int) -> np.ndarray:
    """(4, 3) gravity in the sensor frame: four tilts well apart, the sensor mounted at random."""
    mount = Rotation.random(random_state=seed)
    return (TILTS * mount).apply(G, inverse=True)


def _hanging(m, c, g_sensor, bias):
    """(k, 6) the wrench of a body (m, c) at rest, gravity g_sensor (k, 3), plus a bias."""
    return np.array([np.r_[m * g, np.cross(c, m * g)] for g in g_sensor]) + bias


@given(
    m=st.floats(0.2, 5.0),
    c=st.tuples(*[st.floats(-0.2, 0.2)] * 3),
    seed=st.integers(0, 10_000),
)
@settings(max_examples=40, deadline=None)
def test_exact_readings_give_the_body_and_the_bias_back(m, c, seed):
    rng = np.random.default_rng(seed)
    g_sensor = _orientations(seed)
    bias = rng.normal(size=6)
    fit = fit_static_wrench(g_sensor, _hanging(m, np.array(c), g_sensor, bias), 0.01)
    assert fit.mass == pytest.approx(m, rel=1e-9, abs=1e-9)
    np.testing.assert_allclose(fit.com_sensor, c, atol=1e-9)
    np.testing.assert_allclose(fit.bias, bias, atol=1e-8)
    assert fit.held


def test_intervals_cover_the_truth_over_many_draws():
    """White noise of known std: the 95 % intervals of m and c hold the truth ~95 % of draws."""
    rng = np.random.default_rng(7)
    std = np.r_[[0.05] * 3, [0.003] * 3]
    inside, draws = [], 300
    for k in range(draws):
        m, c = rng.uniform(0.5, 2.0), rng.uniform(-0.05, 0.05, 3) + [0, 0, 0.1]
        g_sensor = _orientations(k)
        w = _hanging(m, c, g_sensor, rng.normal(size=6)) + rng.normal(size=(4, 6)) * std
        fit = fit_static_wrench(g_sensor, w, std)
        z = (np.r_[fit.mass, fit.com_sensor] - np.r_[m, c]) / np.sqrt(np.diag(fit.cov))
        inside.extend(np.abs(z) < 1.96)
    assert 0.92 < np.mean(inside) < 0.98


def test_rotations_about_gravity_only_are_refused_naming_the_tilts():
    g_sensor = Rotation.from_euler("z", [[0], [60], [120], [180]], degrees=True).apply(
        G, inverse=True
    )
    with pytest.raises(UnobservableError, match="tilts of the sensor about two axes"):
        fit_static_wrench(g_sensor, _hanging(1.0, np.zeros(3), g_sensor, 0), 0.01)


def test_a_small_arc_names_the_rotation_across_it():
    """Rotations about the sensor's y by 0-40 deg move gravity along x only: tilt about x."""
    g_sensor = Rotation.from_euler("y", [[0], [20], [40]], degrees=True).apply(G, inverse=True)
    with pytest.raises(UnobservableError, match=r"about its axis \[[-+]0\.9\d.*mostly x"):
        fit_static_wrench(g_sensor, _hanging(1.0, np.zeros(3), g_sensor, 0), 0.01)


def test_two_orientations_are_refused():
    g_sensor = Rotation.from_euler("x", [[0], [90]], degrees=True).apply(G, inverse=True)
    with pytest.raises(UnobservableError, match="at least 3"):
        fit_static_wrench(g_sensor, _hanging(1.0, np.zeros(3), g_sensor, 0), 0.01)


def test_bad_arrays_are_refused():
    g_sensor = _orientations(1)
    w = _hanging(1.0, np.zeros(3), g_sensor, 0)
    with pytest.raises(InvalidInputError, match="finite"):
        fit_static_wrench(g_sensor, np.where(w > 0, np.nan, w), 0.01)
    with pytest.raises(InvalidInputError, match=r"\(k, 6\)"):
        fit_static_wrench(g_sensor, w[:, :5], 0.01)
    with pytest.raises(InvalidInputError, match="> 0"):
        fit_static_wrench(g_sensor, w, 0.0)


def test_nothing_held_gives_an_interval_on_zero_and_no_com():
    rng = np.random.default_rng(3)
    g_sensor = _orientations(3)
    std = np.r_[[0.1] * 3, [0.005] * 3]
    fit = fit_static_wrench(g_sensor, rng.normal(size=(4, 6)) * std + 2.0, std)
    assert not fit.held
    assert abs(fit.mass) < 3 * np.sqrt(fit.cov[0, 0])
    assert np.all(np.isnan(fit.com_sensor))


def _urdf_tool_beyond_tool0():
    """Mass and CoM (tool0 frame) of the links hung below tool0 in the URDF, from its XML."""
    root = ET.parse(RobotModel.ur5().urdf_path).getroot()
    joints = {j.find("child").get("link"): j for j in root.findall("joint")}
    links = {lk.get("name"): lk for lk in root.findall("link")}
    mass, moment = 0.0, np.zeros(3)
    for name, link in links.items():
        inertial = link.find("inertial")
        chain, p = name, np.zeros(3)
        if inertial is None:
            continue
        p = np.array([float(v) for v in inertial.find("origin").get("xyz").split()])
        while chain in joints and chain != "tool0":
            j = joints[chain]
            o = j.find("origin")
            rpy = [float(v) for v in o.get("rpy", "0 0 0").split()]
            xyz = np.array([float(v) for v in o.get("xyz", "0 0 0").split()])
            p = Rotation.from_euler("xyz", rpy).apply(p) + xyz
            chain = j.find("parent").get("link")
        if chain == "tool0":
            m = float(inertial.find("mass").get("value"))
            mass, moment = mass + m, moment + m * p
    return mass, moment / mass


def test_the_tool_beyond_the_sensor_is_the_urdfs_links_below_it():
    robot = RobotModel.ur5()
    mass, com = _urdf_tool_beyond_tool0()
    tool = tool_beyond(robot, "tool0")
    assert mass > 0.5
    assert tool.mass == pytest.approx(mass, rel=1e-12)
    np.testing.assert_allclose(tool.lever, com, atol=2e-3)  # the fingers' locked opening


def _log(robot, sensor, m, c_sensor, bias, std, rng, hold=200, move=100):
    """A log at rest at each planned pose, moving between them, white noise of ``std``."""
    plan = plan_measurement_poses(robot, k=4)
    tool = tool_beyond(robot, sensor)
    rows, qs = [], []
    for q, q_next in zip(plan.q, np.roll(plan.q, -1, axis=0)):
        g = robot.frame_pose(q, sensor)[:3, :3].T @ G
        w = _hanging(m, c_sensor, [g], bias)[0] + _hanging(tool.mass, tool.lever, [g], 0)[0]
        rows += list(w + rng.normal(size=(hold, 6)) * std)
        qs += [q] * hold
        for s in np.linspace(0, 1, move):
            qs.append(q + s * (q_next - q))
            rows.append(w)
    t = 0.01 * np.arange(len(qs))
    return WrenchLog(t, tuple(robot.joint_names), np.array(qs), np.array(rows), sensor, "test")


def test_a_log_at_four_planned_poses_gives_the_payload_in_the_ee_frame():
    robot = RobotModel.ur5()
    rng = np.random.default_rng(11)
    c_sensor, bias = np.array([0.02, -0.01, 0.12]), rng.normal(size=6)
    std = np.r_[[0.1] * 3, [0.005] * 3]
    log = _log(robot, "tool0", 1.5, c_sensor, bias, std, rng)
    urdf_way = estimate_wrench_static(robot, log)  # the URDF's tool: its error is not known
    assert urdf_way.verdict == "unreliable" and "URDF's links beyond" in urdf_way.reasons[0]
    tool = tool_beyond(robot, "tool0")  # the same tool, as if identified with nothing held
    known = (np.r_[tool.mass, tool.mass * np.asarray(tool.lever)], np.zeros((4, 4)))
    est = estimate_wrench_static(robot, log, tool=known)
    assert est.at_rest.n_poses == 4 and est.verdict == "identified"
    assert est.mass == pytest.approx(urdf_way.mass, rel=1e-12)
    T_world_s = robot.frame_pose(np.zeros(6), "tool0")
    T_world_ee = robot.frame_pose(np.zeros(6), robot.ee_frame)
    c_ee = np.linalg.solve(T_world_ee, T_world_s @ np.r_[c_sensor, 1])[:3]
    sd = np.sqrt(np.diag(est.cov))
    assert abs(est.mass - 1.5) < 4 * sd[0] and sd[0] < 0.01
    assert np.all(np.abs(est.com_ee - c_ee) < 4 * sd[1:]) and np.all(sd[1:] < 1e-3)
    assert np.all(np.abs(est.wrench.sensor_bias - bias) < 4 * est.wrench.sensor_bias_std)


def test_a_log_that_never_rests_is_refused():
    robot = RobotModel.ur5()
    t = np.linspace(0, 5, 500)
    q = np.outer(t, np.ones(6))
    log = WrenchLog(t, tuple(robot.joint_names), q, np.zeros((500, 6)), "tool0", "moving.csv")
    with pytest.raises(LogError, match="no still window"):
        estimate_wrench_static(robot, log)


def test_a_sensor_frame_off_the_last_link_is_refused():
    robot = RobotModel.ur5()
    log = _log(robot, "tool0", 1.0, np.zeros(3), 0, 0.01, np.random.default_rng(0))
    bad = WrenchLog(log.time, log.joint_names, log.position, log.wrench, "forearm_link")
    with pytest.raises(InvalidInputError, match="not on the same link chain"):
        estimate_wrench_static(robot, bad)


def test_a_hand_named_as_the_sensor_frame_is_on_the_tool_side():
    """The Panda's hand as the sensor frame (the sensor at its mounting face): the hand and
    its fingers are what the sensor carries, their masses read from the URDF's XML."""
    from comgrasp_pin._paths import example_robot_urdf
    from comgrasp_pin.robot_io import load_robot

    urdf = example_robot_urdf("panda_description/urdf/panda.urdf")
    robot = load_robot(urdf, "panda_hand_tcp")
    links = {lk.get("name"): lk for lk in ET.parse(urdf).getroot().findall("link")}
    names = ("panda_hand", "panda_leftfinger", "panda_rightfinger")
    mass = sum(float(links[n].find("inertial/mass").get("value")) for n in names)
    assert tool_beyond(robot, "panda_hand").mass == pytest.approx(mass, rel=1e-12)
    assert tool_beyond(robot, "panda_link8").mass == pytest.approx(mass, rel=1e-12)


def test_poses_planned_for_the_wrist_sensor_keep_the_promised_std():
    """plan-poses --sensor-frame: the planned orientations pass the observability check, and
    the scatter of estimates over noisy draws at them matches the std the plan predicts."""
    robot = RobotModel.ur5()
    plan = plan_measurement_poses(robot, k=4, n_candidates=400, sensor_frame="ft_sensor",
                                  wrench_std=(0.05, 0.002))  # fmt: skip
    assert plan.sensor_frame == "ft_sensor" and plan.q.shape == (4, 6)
    g_sensor = np.array([robot.frame_pose(q, "ft_sensor")[:3, :3].T @ G for q in plan.q])
    T = np.linalg.solve(robot.frame_pose(np.zeros(6), "ft_sensor"), robot.ee_pose(np.zeros(6)))
    std = np.r_[[0.05] * 3, [0.002] * 3]
    rng = np.random.default_rng(2)
    est = []
    for _ in range(400):  # a 1 kg payload at the ee origin, the plan's assumption
        w = _hanging(plan.mass, T[:3, 3], g_sensor, rng.normal(size=6))
        fit = fit_static_wrench(g_sensor, w + rng.normal(size=(4, 6)) * std, std)
        est.append(np.r_[fit.mass, T[:3, :3].T @ fit.com_sensor])
    spread = np.std(est, axis=0)
    np.testing.assert_allclose(spread, plan.predicted_std, rtol=0.15)
