"""`comgrasp estimate --wrench` (static) end to end: a wrist sensor's log as a real ROS 2 bag
(rosbags) and as a CSV, the RESULT.json against the payload the log was made from, the payload
files read back, and bad input refused with exit status 2 and a message."""

from __future__ import annotations

import json
import re
import subprocess
import sys

import numpy as np
import pytest
from test_wrench_static import _log

from comgrasp_pin._paths import urdf_path
from comgrasp_pin.cli import main
from comgrasp_pin.robot import RobotModel
from comgrasp_pin.robot_io.log_files import write_wrench_bag, write_wrench_csv

URDF = str(urdf_path("ur5_gripper.urdf"))
MASS, COM_SENSOR = 1.2, np.array([0.01, -0.005, 0.15])
STD = np.r_[[0.1] * 3, [0.005] * 3]


@pytest.fixture(scope="module")
def wrench_log():
    robot = RobotModel.ur5()
    rng = np.random.default_rng(21)
    return _log(robot, "ft_sensor", MASS, COM_SENSOR, rng.normal(size=6), STD, rng)


def _com_ee(robot, c_sensor):
    T = np.linalg.solve(robot.ee_pose(np.zeros(6)), robot.frame_pose(np.zeros(6), "ft_sensor"))
    return T[:3, :3] @ c_sensor + T[:3, 3]


def _args(log_args, out, *more):
    return ["estimate", "--wrench", "--urdf", URDF, "--ee-frame", "eelink", *log_args,
            "--out", str(out), *more]  # fmt: skip


@pytest.mark.parametrize("storage", ["sqlite3", "mcap"])
def test_a_bag_gives_the_payload_and_the_files(wrench_log, tmp_path, storage, capsys):
    """The tool identified first with nothing held (--keep-tool, then --tool), as the docs
    say: with the URDF's tool alone the verdict is unreliable and no file is written."""
    rng = np.random.default_rng(22)
    empty = _log(RobotModel.ur5(), "ft_sensor", 0.0, np.zeros(3), rng.normal(size=6), STD, rng)
    tool = tmp_path / "TOOL.json"
    empty_bag = write_wrench_bag(tmp_path / "empty", empty, storage=storage)
    assert main(_args(["--bag", str(empty_bag)], tool, "--keep-tool")) == 0
    bag = write_wrench_bag(tmp_path / "bag", wrench_log, storage=storage)
    out, rapid, urdf = tmp_path / "R.json", tmp_path / "load.mod", tmp_path / "robot.urdf"
    args = _args(["--bag", str(bag)], out, "--flange-frame", "tool0", "--export-abb",
                 str(rapid), "--export-urdf", str(urdf))  # fmt: skip
    assert main(args) == 2 and not rapid.exists()  # the URDF's tool
    assert "URDF's links beyond the sensor" in capsys.readouterr().err
    assert main([*args, "--tool", str(tool)]) == 0
    r = json.loads(out.read_text())
    std = np.sqrt(np.diag(r["cov"]))
    assert r["wrench"]["sensor_frame"] == "ft_sensor" and r["at_rest"]["n_poses"] == 4
    assert r["verdict"] == "identified" and r["frame"] == "eelink"
    assert abs(r["mass_kg"] - MASS) < 4 * std[0]
    assert np.all(
        np.abs(np.array(r["com_m"]) - _com_ee(RobotModel.ur5(), COM_SENSOR)) < 4 * std[1:]
    )
    assert len(r["wrench"]["sensor_bias"]) == 6 and len(r["wrench"]["sensor_bias_std"]) == 6
    assert "VERDICT: identified" in capsys.readouterr().out
    # RAPID loaddata: mass and the CoG in mm of tool0 (ft_sensor sits at tool0)
    m = re.search(r"loaddata\s+\w+\s*:=\s*\[\s*([-\d.eE+]+)\s*,\s*\[([^\]]*)\]", rapid.read_text())
    assert float(m.group(1)) == pytest.approx(r["mass_kg"], rel=1e-6)
    cog_mm = [float(v) for v in m.group(2).split(",")]
    np.testing.assert_allclose(cog_mm, 1e3 * np.array(r["wrench"]["com_sensor_m"]), atol=1e-3)
    assert urdf.exists()


def test_a_csv_needs_its_sensor_frame_named(wrench_log, tmp_path):
    csv = write_wrench_csv(tmp_path / "w.csv", wrench_log)
    out = tmp_path / "R.json"
    assert main(_args(["--csv", str(csv), "--sensor-frame", "ft_sensor"], out)) == 0  # no file
    assert json.loads(out.read_text())["at_rest"]["n_poses"] == 4
    assert main(_args(["--csv", str(csv), "--sensor-frame", "ft_sensor", "--auto"], out)) == 0
    both = ["--csv", str(csv), "--sensor-frame", "ft_sensor", "--auto", "--windows", "0:1"]
    assert main(_args(both, out)) == 2
    cmd = [sys.executable, "-m", "comgrasp_pin.cli", *_args(["--csv", str(csv)], out)]
    res = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
    assert res.returncode == 2 and "Traceback" not in res.stderr
    assert "sensor" in res.stderr and "frame" in res.stderr


def test_too_few_orientations_exit_2_naming_what_is_missing(wrench_log, tmp_path):
    csv = write_wrench_csv(tmp_path / "w.csv", wrench_log)
    out = tmp_path / "R.json"
    log_args = ["--csv", str(csv), "--sensor-frame", "ft_sensor", "--windows", "0.1:1.8,3.1:4.7"]
    cmd = [sys.executable, "-m", "comgrasp_pin.cli", *_args(log_args, out)]
    res = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
    assert res.returncode == 2 and "Traceback" not in res.stderr
    assert "at least 3" in res.stderr and not out.exists()


def test_nothing_held_writes_no_payload_file(tmp_path):
    robot = RobotModel.ur5()
    rng = np.random.default_rng(4)
    log = _log(robot, "ft_sensor", 0.0, np.zeros(3), rng.normal(size=6), STD, rng)
    csv = write_wrench_csv(tmp_path / "w.csv", log)
    out, script = tmp_path / "R.json", tmp_path / "p.script"
    assert main(_args(["--csv", str(csv), "--sensor-frame", "ft_sensor"], out)) == 0
    r = json.loads(out.read_text())
    assert r["verdict"] == "unreliable" and r["com_m"] is None  # and the URDF's tool unknown
    assert "no payload seen" in r["reasons"][0] and "URDF's links" in r["reasons"][1]
    assert abs(r["mass_kg"]) < 3 * r["std"]["mass_kg"]
    args = _args(
        ["--csv", str(csv), "--sensor-frame", "ft_sensor"], out, "--export-ur", str(script)
    )
    assert main(args) == 2 and not script.exists()


def test_pairs_and_orientations_at_rest_are_not_mixed(wrench_log, tmp_path):
    csv = write_wrench_csv(tmp_path / "w.csv", wrench_log)
    args = _args(["--csv", str(csv), "--sensor-frame", "ft_sensor"], tmp_path / "R.json",
                 "--before", "0:1", "--after", "3:4", "--auto")  # fmt: skip
    assert main(args) == 2
    assert main([*args[:-1], "--grasp-time", "2"]) == 2


def test_a_tool_identified_before_replaces_a_misstated_urdf_tool(tmp_path):
    """The real gripper is 3 % heavier than the URDF says: the URDF's tool leaves that in the
    payload; the tool identified with nothing held (--keep-tool, then --tool) takes it out."""
    from comgrasp_pin.estimation.wrench_com import tool_beyond

    robot = RobotModel.ur5()
    urdf_tool = tool_beyond(robot, "ft_sensor")
    extra_m, extra_c = 0.03 * urdf_tool.mass, np.array(urdf_tool.lever)
    m = MASS + extra_m
    c = (MASS * COM_SENSOR + extra_m * extra_c) / m
    rng = np.random.default_rng(8)
    empty = _log(robot, "ft_sensor", extra_m, extra_c, rng.normal(size=6), STD, rng)
    loaded = _log(robot, "ft_sensor", m, c, rng.normal(size=6), STD, rng)
    e_csv = write_wrench_csv(tmp_path / "empty.csv", empty)
    l_csv = write_wrench_csv(tmp_path / "loaded.csv", loaded)
    tool, out = tmp_path / "TOOL.json", tmp_path / "R.json"
    frame = ["--sensor-frame", "ft_sensor"]
    assert main(_args(["--csv", str(e_csv), *frame], tool, "--keep-tool")) == 0
    t = json.loads(tool.read_text())
    assert t["mass_kg"] == pytest.approx(urdf_tool.mass + extra_m, abs=4 * t["std"]["mass_kg"])
    assert main(_args(["--csv", str(l_csv), *frame], out)) == 0
    urdf_way = json.loads(out.read_text())
    assert urdf_way["mass_kg"] - MASS > 10 * urdf_way["std"]["mass_kg"]  # the 27 g show
    assert main(_args(["--csv", str(l_csv), *frame], out, "--tool", str(tool))) == 0
    r = json.loads(out.read_text())
    assert abs(r["mass_kg"] - MASS) < 4 * r["std"]["mass_kg"]
    com_ee = _com_ee(robot, COM_SENSOR)
    assert np.all(np.abs(np.array(r["com_m"]) - com_ee) < 4 * np.array(r["std"]["com_m"]))
    assert r["std"]["mass_kg"] > urdf_way["std"]["mass_kg"]  # the tool's own error added
    bad = _args(["--csv", str(l_csv), *frame], out, "--tool", str(out))  # not a --keep-tool run
    assert main(bad) == 2


def test_dynamic_from_bags_with_an_empty_run_and_a_payload_file(tmp_path):
    """`--wrench --dynamic`: a motion's wrench and joint torques (Pinocchio's RNEA with the
    tool and the payload beyond the sensor, tests/test_wrench_dynamic.py) as real bags, the
    tool's own run of another motion; the inertia and each source's share in RESULT.json,
    the URDF export read back with ElementTree."""
    import xml.etree.ElementTree as ET

    from test_wrench_dynamic import PAYLOAD, fourier_motion, wrench_log

    robot = RobotModel.ur5()
    loaded = wrench_log(robot, PAYLOAD, fourier_motion(robot), seed=6)
    empty = wrench_log(robot, None, fourier_motion(robot, seed=5), seed=7)
    bag = write_wrench_bag(tmp_path / "loaded", loaded, storage="mcap")
    empty_bag = write_wrench_bag(tmp_path / "empty", empty, storage="mcap")
    out, urdf = tmp_path / "R.json", tmp_path / "robot.urdf"
    args = _args(["--bag", str(bag)], out, "--dynamic", "--empty-bag", str(empty_bag),
                 "--export-urdf", str(urdf))  # fmt: skip
    assert main(args) == 0
    r = json.loads(out.read_text())
    assert abs(r["mass_kg"] - PAYLOAD.mass) < 4.5 * r["std"]["mass_kg"]
    assert len(r["wrench"]["sensor_bias"]) == 6 and set(r["sources"]) >= {"wrench"}
    assert np.array(r["inertia"]["inertia_kgm2"]).shape == (3, 3)
    link = next(
        lk for lk in ET.parse(urdf).getroot().findall("link") if lk.get("name") == "payload"
    )
    assert float(link.find("inertial/mass").get("value")) == pytest.approx(r["mass_kg"], rel=1e-6)
    assert main([*args, "--windows", "0:1,2:3,4:5"]) == 2  # a motion takes --window


def test_the_sensors_drift_from_its_data_sheet_is_taken(wrench_log, tmp_path):
    csv = write_wrench_csv(tmp_path / "w.csv", wrench_log)
    log_args = ["--csv", str(csv), "--sensor-frame", "ft_sensor"]
    out, drifting = tmp_path / "R.json", tmp_path / "D.json"
    assert main(_args(log_args, out)) == 0
    assert main(_args(log_args, drifting, "--wrench-drift", "0.01,0.0005,2e-4,1e-5")) == 0
    plain, with_drift = (json.loads(p.read_text())["std"]["mass_kg"] for p in (out, drifting))
    assert with_drift > plain  # the windows' shared drift widens the interval
    assert main(_args(log_args, out, "--wrench-drift", "0.01")) == 2
    assert main(_args(log_args, out, "--wrench-drift=-1,0")) == 2


def test_before_and_after_pairs_use_the_wrench_and_the_joint_torques(tmp_path, capsys):
    """A log at three poses empty, a grasp, the same poses holding: efforts from MuJoCo
    (tests/_logs.py, a payload body on eelink), the wrench written out here (the URDF's tool
    and the payload hanging at the sensor, f = m g, tau = c x m g, plus an offset and noise).
    Both sources are used, each one's share is stated, and without efforts the wrench alone."""
    from _logs import mujoco_torques, session

    from comgrasp_pin.estimation.wrench_com import tool_beyond
    from comgrasp_pin.robot_io import WrenchLog

    robot = RobotModel.ur5()
    Q = np.array([[0.0, -1.6, 1.6, -1.57, -1.57, 0.0], [0.4, -1.2, 1.2, -0.4, 0.8, 1.0],
                  [-0.5, -1.9, 1.5, -2.5, -0.6, -1.2]])  # fmt: skip
    mass, com_ee = 0.6, np.array([0.03, -0.015, 0.04])
    jlog, before, after, grasp = session(Q, mujoco_torques(mass, com_ee), robot.joint_names,
                                         200.0, 0.05, seed=3)  # fmt: skip
    T_s_ee = np.linalg.solve(robot.frame_pose(np.zeros(6), "ft_sensor"), robot.ee_pose(np.zeros(6)))
    c_s = T_s_ee[:3, :3] @ com_ee + T_s_ee[:3, 3]
    tool = tool_beyond(robot, "ft_sensor")
    rng = np.random.default_rng(4)
    bias = rng.normal(size=6)
    wrench = []
    for t, q in zip(jlog.time, jlog.position):
        g = robot.frame_pose(q, "ft_sensor")[:3, :3].T @ np.array([0.0, 0.0, -9.81])
        w = _hanging(tool.mass, tool.lever, g) + (_hanging(mass, c_s, g) if t >= grasp else 0)
        wrench.append(w + bias + rng.normal(size=6) * STD)
    log = WrenchLog(jlog.time, jlog.joint_names, jlog.position, np.array(wrench), "ft_sensor",
                    "test", effort=jlog.effort)  # fmt: skip
    csv = write_wrench_csv(tmp_path / "w.csv", log)
    out = tmp_path / "R.json"
    win = ["--before", ",".join(f"{a}:{b}" for a, b in before),
           "--after", ",".join(f"{a}:{b}" for a, b in after)]  # fmt: skip
    assert main(_args(["--csv", str(csv), "--sensor-frame", "ft_sensor", *win], out)) == 0
    r = json.loads(out.read_text())
    std = np.sqrt(np.diag(r["cov"]))
    assert list(r["sources"]) == ["wrench", "joint_torques"] and r["at_rest"]["n_poses"] == 3
    assert abs(r["mass_kg"] - mass) < 4 * std[0]
    assert np.all(np.abs(np.array(r["com_m"]) - com_ee) < 4 * std[1:])
    for unknown in r["sources"]["wrench"]:
        total = sum(np.array(r["sources"][s][unknown]) for s in r["sources"])
        np.testing.assert_allclose(total, 1.0, atol=1e-9)
    assert "share of the information from wrench: mass [" in capsys.readouterr().out
    alone = WrenchLog(log.time, log.joint_names, log.position, log.wrench, "ft_sensor", "test")
    csv2 = write_wrench_csv(tmp_path / "w2.csv", alone)
    assert main(_args(["--csv", str(csv2), "--sensor-frame", "ft_sensor", *win], out)) == 0
    r2 = json.loads(out.read_text())
    assert list(r2["sources"]) == ["wrench"] and np.sqrt(r2["cov"][0][0]) >= std[0]
    assert main(_args(["--csv", str(csv), "--sensor-frame", "ft_sensor", *win[:2]], out)) == 2


def _hanging(m, c, g):
    return np.r_[m * g, np.cross(np.asarray(c) * m, g)]
