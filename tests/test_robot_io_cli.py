"""`comgrasp estimate` and `comgrasp plan-poses` end to end: the project's UR5, efforts from
MuJoCo (qfrc_bias of the URDF compiled by MuJoCo, a payload body on eelink) plus 0.05 N m
noise, written as real bags by rosbags; bad logs exit 2 with a message, no traceback."""

import json
import subprocess
import sys

import numpy as np
import pytest
from _logs import mujoco_torques, session

from comgrasp_pin._paths import urdf_path
from comgrasp_pin.cli import main
from comgrasp_pin.robot_io import JointLog, write_bag, write_csv
from comgrasp_pin.robot_io.front_door import load_robot

URDF = str(urdf_path("ur5_gripper.urdf"))
MASS, COM = 0.6, np.array([0.03, -0.015, 0.04])
UR_Q = np.array(
    [[0.0, -1.6, 1.6, -1.57, -1.57, 0.0], [0.4, -1.2, 1.2, -0.4, 0.8, 1.0],
     [-0.5, -1.9, 1.5, -2.5, -0.6, -1.2]]
)  # fmt: skip
FINGERS = {"finger_left_joint": 0.01, "finger_right_joint": 0.01}


def _windows(ws):
    return ",".join(f"{a:.4f}:{b:.4f}" for a, b in ws)


@pytest.fixture(scope="module")
def ur5_session():
    robot = load_robot(URDF, "eelink")
    return session(UR_Q, mujoco_torques(MASS, COM), robot.joint_names, 500.0, 0.05, seed=11)


@pytest.fixture(scope="module", params=["sqlite3", "mcap"])
def bag(request, ur5_session, tmp_path_factory):
    path = tmp_path_factory.mktemp(request.param) / "bag"
    return write_bag(ur5_session[0], path, request.param, extra_joints=FINGERS)


def _estimate_args(log_args, before, after, out):
    return ["estimate", "--urdf", URDF, "--ee-frame", "eelink", *log_args, "--before",
            _windows(before), "--after", _windows(after), "--out", str(out)]  # fmt: skip


def _check_result(path):
    r = json.loads(path.read_text())
    assert set(r) >= {"schema_version", "mass_kg", "com_m", "frame", "cov", "std",
                      "interval95_mass_kg", "verdict", "reasons", "sources", "unobservable",
                      "at_rest", "joint_torques"}  # fmt: skip
    assert r["schema_version"] == 3 and r["verdict"] == "identified"
    assert set(r["at_rest"]) >= {"n_poses", "q_rad", "windows", "residual_rms"}
    std = np.sqrt(np.diag(r["cov"]))
    assert r["frame"] == "eelink" and r["at_rest"]["n_poses"] == 3 and r["unobservable"] is None
    assert abs(r["mass_kg"] - MASS) < 3 * std[0]
    assert np.all(np.abs(np.array(r["com_m"]) - COM) < 3 * std[1:])
    return r


def test_estimate_from_bag(bag, ur5_session, tmp_path, capsys):
    _, before, after, _ = ur5_session
    out = tmp_path / "RESULT.json"
    ur, fr, ros = tmp_path / "p.script", tmp_path / "f.json", tmp_path / "p.yaml"
    args = _estimate_args(["--bag", str(bag)], before, after, out)
    args += ["--flange-frame", "tool0", "--export-ur", str(ur), "--export-franka", str(fr),
             "--export-ros2", str(ros)]  # fmt: skip
    assert main(args) == 0
    r = _check_result(out)
    text = capsys.readouterr().out
    assert "mass" in text and "+-" in text and "eelink" in text
    # eelink is 0.13 m along tool0's z (urdf/ur5_gripper.urdf: gripper_base at tool0, eelink)
    franka = json.loads(fr.read_text())
    np.testing.assert_allclose(franka["F_x_Cload"], np.array(r["com_m"]) + [0, 0, 0.13],
                               atol=1e-9)  # fmt: skip
    assert "set_target_payload(" in ur.read_text() and "ur_msgs" in ros.read_text()


def test_estimate_auto_windows(bag, ur5_session, tmp_path):
    grasp = ur5_session[3]
    out = tmp_path / "RESULT.json"
    args = ["estimate", "--urdf", URDF, "--ee-frame", "eelink", "--bag", str(bag), "--auto",
            "--grasp-time", f"{grasp}", "--out", str(out)]  # fmt: skip
    assert main(args) == 0
    _check_result(out)


def test_estimate_from_csv_with_ipopt(ur5_session, tmp_path):
    log, before, after, _ = ur5_session
    csv = write_csv(log, tmp_path / "log.csv")
    out = tmp_path / "RESULT.json"
    assert (
        main([*_estimate_args(["--csv", str(csv)], before, after, out), "--method", "ipopt"]) == 0
    )
    r = _check_result(out)
    assert r["at_rest"]["solver_status"] == "Solve_Succeeded"


def test_estimate_as_a_subprocess(ur5_session, tmp_path):
    log, before, after, _ = ur5_session
    bag = write_bag(log, tmp_path / "bag", "mcap", extra_joints=FINGERS)
    out = tmp_path / "RESULT.json"
    cmd = [sys.executable, "-m", "comgrasp_pin.cli",
           *_estimate_args(["--bag", str(bag)], before, after, out)]  # fmt: skip
    res = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
    assert res.returncode == 0, res.stderr
    _check_result(out)


def _bad(args, capsys, *words):
    assert main(args) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err
    for w in words:
        assert w in err, err


def test_estimate_with_the_sensors_drift(ur5_session, tmp_path):
    """--drift-std: recorded in RESULT.json, and the drift between the windows widens the
    stated std against the same log without it."""
    log, before, after, _ = ur5_session
    csv = write_csv(log, tmp_path / "log.csv")
    stds = {}
    for drift in ("0", "0.01"):
        out = tmp_path / f"RESULT_{drift}.json"
        assert main([*_estimate_args(["--csv", str(csv)], before, after, out),
                     "--drift-std", drift]) == 0  # fmt: skip
        r = _check_result(out)
        assert r["joint_torques"]["torque_drift_Nm_per_sqrt_s"] == float(drift)
        stds[drift] = np.array(r["std"]["com_m"])
    assert np.all(stds["0.01"] > 1.5 * stds["0"])
    _bad_out = tmp_path / "R.json"
    assert main([*_estimate_args(["--csv", str(csv)], before, after, _bad_out),
                 "--drift-std", "-1"]) == 2  # fmt: skip
    assert not _bad_out.exists()


def test_bad_logs_exit_2_with_a_message(bag, ur5_session, tmp_path, capsys):
    log, before, after, _ = ur5_session
    out = tmp_path / "R.json"
    moving = [(before[0][1] + 0.2, before[1][0] + 0.1)]
    _bad(_estimate_args(["--bag", str(bag)], moving, after[:1], out), capsys, "not static")
    late = [(log.duration + 1, log.duration + 2)]
    _bad(_estimate_args(["--bag", str(bag)], late, after[:1], out), capsys, "outside the log")
    _bad(_estimate_args(["--bag", str(bag)], before, after[:2], out), capsys, "window(s)")
    _bad(_estimate_args(["--bag", str(tmp_path / "nope")], before, after, out), capsys, "not found")
    _bad(_estimate_args(["--bag", str(bag), "--topic", "/x"], before, after, out), capsys, "/x")
    assert not out.exists()


def test_log_without_efforts_exits_2(ur5_session, tmp_path, capsys):
    log, before, after, _ = ur5_session
    empty = JointLog(log.time, log.joint_names, log.position, np.empty((len(log.time), 0)))
    bag = write_bag(empty, tmp_path / "bag")
    _bad(_estimate_args(["--bag", str(bag)], before, after, tmp_path / "R.json"), capsys,
         "no joint efforts")  # fmt: skip


def test_log_with_other_joint_names_exits_2(ur5_session, tmp_path, capsys):
    log, before, after, _ = ur5_session
    renamed = JointLog(log.time, tuple(f"ur_{n}" for n in log.joint_names), log.position,
                       log.effort)  # fmt: skip
    bag = write_bag(renamed, tmp_path / "bag")
    _bad(_estimate_args(["--bag", str(bag)], before, after, tmp_path / "R.json"), capsys,
         "never appear", "shoulder_pan_joint")  # fmt: skip


def test_bad_log_as_a_subprocess_has_no_traceback(ur5_session, tmp_path):
    log, before, after, _ = ur5_session
    csv = write_csv(log, tmp_path / "log.csv")
    late = [(log.duration + 1, log.duration + 2)]
    cmd = [sys.executable, "-m", "comgrasp_pin.cli",
           *_estimate_args(["--csv", str(csv)], late, after[:1], tmp_path / "R.json")]  # fmt: skip
    res = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
    assert res.returncode == 2 and "outside the log" in res.stderr
    assert "Traceback" not in res.stderr


def test_plan_poses_cli(tmp_path, capsys):
    out, script = tmp_path / "poses.json", tmp_path / "poses.script"
    args = ["plan-poses", "--urdf", URDF, "--ee-frame", "eelink", "--k", "3", "--start",
            "0,-1.6,1.6,-1.57,-1.57,0", "--out", str(out), "--urscript", str(script)]  # fmt: skip
    assert main(args) == 0
    plan = json.loads(out.read_text())
    assert np.array(plan["q_rad"]).shape == (3, 6)
    np.testing.assert_allclose(plan["q_rad"][0], [0, -1.6, 1.6, -1.57, -1.57, 0])
    assert script.read_text().count("movej(") == 3
    assert "predicted std" in capsys.readouterr().out


def test_help_shows_defaults(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["estimate", "--help"])
    assert exc.value.code == 0
    text = capsys.readouterr().out
    assert "/joint_states" in text and "AVERAGED" in text and "default: 0.01" in text


def test_bad_flange_or_inertia_exits_2_before_writing(bag, ur5_session, tmp_path, capsys):
    _, before, after, _ = ur5_session
    out = tmp_path / "R.json"
    args = _estimate_args(["--bag", str(bag)], before, after, out)
    _bad([*args, "--export-ur", str(tmp_path / "p.script"), "--flange-frame", "nope"], capsys,
         "nope", "tool0")  # fmt: skip
    _bad([*args, "--export-ur", str(tmp_path / "p.script"), "--inertia", "ball"], capsys,
         "cylinder:L,R,AXIS")  # fmt: skip
    assert not out.exists() and not (tmp_path / "p.script").exists()
