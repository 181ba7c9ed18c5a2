"""One rule for payload files (issue 41, DESIGN.md 4f): every estimate mode, driven through the
command line with a case whose verdict is not ``identified``, exits 2, writes RESULT.json with
the verdict's reasons and no payload file; ``--export-anyway`` writes the file with the
verdict in its header and never calls the payload identified. The same rule in Python.

The unreliable cases are the mistakes a user makes: a wrench logged in mN (every reading
x 1000: the payload comes out heavier than the arm), a motion with no empty run (the URDF's
nominal arm model), a motion whose tool is only the URDF's.
"""

from __future__ import annotations

import json

import numpy as np
import pinocchio as pin
import pytest
from _logs import rnea_torques, session
from test_dynamic_estimate import fourier_motion, rnea_log
from test_wrench_dynamic import PAYLOAD, wrench_log
from test_wrench_static import G, _hanging, _log

from comgrasp_pin._paths import urdf_path
from comgrasp_pin.cli import main
from comgrasp_pin.errors import InvalidInputError, NotIdentifiedError
from comgrasp_pin.estimation.trust import inertia_verdict
from comgrasp_pin.estimation.wrench_com import tool_beyond
from comgrasp_pin.robot import RobotModel
from comgrasp_pin.robot_io import (
    JointLog,
    WrenchLog,
    estimate_from_log,
    estimate_payload,
    payload_in_flange,
    read_any_log,
    write_csv,
)
from comgrasp_pin.robot_io.log_files import write_wrench_csv
from comgrasp_pin.robot_io.payload_files import urscript

URDF = str(urdf_path("ur5_gripper.urdf"))
SENSOR = "ft_sensor"
Q3 = np.array([[0.0, -1.6, 1.6, -1.57, -1.57, 0.0], [0.4, -1.2, 1.2, -0.4, 0.8, 1.0],
               [-0.5, -1.9, 1.5, -2.5, -0.6, -1.2]])  # fmt: skip
STD = np.r_[[0.1] * 3, [0.005] * 3]


@pytest.fixture(scope="module")
def robot():
    return RobotModel.ur5()


def _run(tmp_path, log_args, *more):
    """(exit status, RESULT.json or None, the UR script's path) of `comgrasp estimate`."""
    out, script = tmp_path / "R.json", tmp_path / "payload.script"
    args = ["estimate", "--urdf", URDF, "--ee-frame", "eelink", *log_args, "--out", str(out),
            "--export-ur", str(script), *more]  # fmt: skip
    code = main(args)
    return code, (json.loads(out.read_text()) if out.exists() else None), script


def _check_gate(tmp_path, capsys, log_args, phrase):
    """Refused: exit 2, the reasons printed and in RESULT.json, no file; then --export-anyway."""
    code, result, script = _run(tmp_path, log_args)
    err = capsys.readouterr().err
    assert code == 2 and not script.exists()
    assert result["verdict"] != "identified" and any(phrase in r for r in result["reasons"])
    assert "no payload file written" in err and phrase in err and "--export-anyway" in err
    code, again, script = _run(tmp_path, log_args, "--export-anyway")
    assert code == 0 and script.exists()
    text = script.read_text()
    header = [line for line in text.splitlines() if line.startswith("#")]
    assert f"verdict on this payload is {result['verdict']!r}" in header[0]
    assert not any("payload identified" in line for line in header)
    assert any(phrase in line for line in header)
    assert f"set_target_payload({again['mass_kg']:.9g}," in text
    return result


def _pairs_wrench(robot, scale):
    """A wrist sensor's wrench at the same three poses empty then holding 1 kg (x ``scale``)."""
    tool = tool_beyond(robot, SENSOR)
    c = np.array([0.01, 0.0, 0.1])

    def wrench(Qs, loaded):
        g = [robot.frame_pose(q, SENSOR)[:3, :3].T @ G for q in Qs]
        w = _hanging(tool.mass, tool.lever, g, 0.3) + (_hanging(1.0, c, g, 0) if loaded else 0)
        return scale * w

    log, before, after, _ = session(Q3, wrench, robot.joint_names, noise=0.01 * scale)
    wlog = WrenchLog(log.time, log.joint_names, log.position, log.effort, SENSOR, "test")
    return wlog, before, after


def _windows(pairs):
    return ",".join(f"{a}:{b}" for a, b in pairs)


def test_static_joint_torques_logged_in_mN_m_are_refused(robot, tmp_path, capsys):
    torques = rnea_torques(robot, 0.7, np.array([0.01, 0.02, 0.05]))
    log, before, after, _ = session(Q3, torques, robot.joint_names, noise=0.05)
    milli = JointLog(log.time, log.joint_names, log.position, 1000 * log.effort, "mN m")
    csv = write_csv(milli, tmp_path / "log.csv")
    args = ["--csv", str(csv), "--before", _windows(before), "--after", _windows(after)]
    result = _check_gate(tmp_path, capsys, args, "heavier than the arm")
    assert result["mass_kg"] == pytest.approx(700, rel=0.05)


def test_static_wrench_logged_in_mN_is_refused(robot, tmp_path, capsys):
    rng = np.random.default_rng(3)
    log = _log(robot, SENSOR, 1.2, np.array([0.01, 0.0, 0.1]), rng.normal(size=6), STD, rng)
    milli = WrenchLog(log.time, log.joint_names, log.position, 1000 * log.wrench, SENSOR, "mN")
    csv = write_wrench_csv(tmp_path / "w.csv", milli)
    args = ["--wrench", "--csv", str(csv), "--sensor-frame", SENSOR]
    _check_gate(tmp_path, capsys, args, "heavier than the arm")


def test_wrench_pairs_logged_in_mN_are_refused(robot, tmp_path, capsys):
    log, before, after = _pairs_wrench(robot, 1000.0)
    csv = write_wrench_csv(tmp_path / "w.csv", log)
    args = ["--wrench", "--csv", str(csv), "--sensor-frame", SENSOR, "--before",
            _windows(before), "--after", _windows(after)]  # fmt: skip
    _check_gate(tmp_path, capsys, args, "heavier than the arm")


def test_a_motion_without_an_empty_run_is_refused(robot, tmp_path, capsys):
    loaded = write_csv(rnea_log(robot, PAYLOAD, fourier_motion(robot, seed=5), seed=6),
                       tmp_path / "loaded.csv")  # fmt: skip
    _check_gate(tmp_path, capsys, ["--dynamic", "--csv", str(loaded)], "nominal model")


def test_a_motions_wrench_with_only_the_urdfs_tool_is_refused(robot, tmp_path, capsys):
    log = wrench_log(robot, PAYLOAD, fourier_motion(robot), effort=False)
    csv = write_wrench_csv(tmp_path / "w.csv", log)
    args = ["--wrench", "--dynamic", "--csv", str(csv), "--sensor-frame", SENSOR]
    _check_gate(tmp_path, capsys, args, "the tool's own wrench is the URDF's links")


def test_python_writers_follow_the_same_rule(robot):
    torques = rnea_torques(robot, 0.7, np.array([0.01, 0.02, 0.05]))
    log, before, after, _ = session(Q3, torques, robot.joint_names, noise=0.05)
    good = estimate_from_log(robot, log, before, after)
    assert good.verdict == "identified"
    assert "payload identified by comgrasp_pin" in urscript(payload_in_flange(robot, good))
    one_pose = estimate_from_log(robot, log, before[:1], after[:1])  # the CoM's line only
    assert one_pose.verdict == "unreliable" and "not observed" in one_pose.reasons[0]
    with pytest.raises(NotIdentifiedError, match="not observed"):
        payload_in_flange(robot, one_pose)
    text = urscript(payload_in_flange(robot, one_pose, anyway=True))
    assert "'unreliable'" in text and "payload identified" not in text


def test_an_inertia_the_motion_did_not_determine_is_not_written(robot):
    """Per part: the inertia's verdict against its principal moments and their std; a
    payload file gets the inertia asked for (--inertia) where the motion did not give it."""
    I, big = np.diag([2e-3, 3e-3, 1e-3]), np.eye(9) * 0.05**2
    assert inertia_verdict(I, np.eye(9) * 1e-4**2)[0] == "identified"
    word, reasons = inertia_verdict(I, big)
    assert word == "not determined" and "--inertia" in reasons[0]
    rod = np.diag([1e-2, 1e-2, 1e-7])  # a thin rod: its smallest moment need not be resolved
    assert inertia_verdict(rod, np.eye(9) * 1e-4**2)[0] == "identified"
    empty = rnea_log(robot, None, fourier_motion(robot, seed=5), seed=7)
    loaded = rnea_log(robot, pin.Inertia(0.8, np.array([0.02, -0.01, 0.08]), np.zeros((3, 3))),
                      fourier_motion(robot, seed=5), seed=6)  # fmt: skip
    est = estimate_payload(robot, loaded, motion=True, empty=empty)
    assert est.verdict == "identified" and est.inertia.verdict == "not determined"
    p = payload_in_flange(robot, est, inertia="box:0.1,0.2,0.3")
    np.testing.assert_allclose(p.inertia_flange, pin.Inertia.FromBox(est.mass, 0.1, 0.2, 0.3)
                               .inertia, atol=1e-12)  # fmt: skip
    assert "did not determine the inertia" in urscript(p)


def test_the_front_door_reads_any_log_and_picks_the_mode(robot, tmp_path):
    rng = np.random.default_rng(5)
    wlog = _log(robot, SENSOR, 1.2, np.array([0.01, 0.0, 0.1]), rng.normal(size=6), STD, rng)
    wrench = read_any_log(write_wrench_csv(tmp_path / "w.csv", wlog), robot, SENSOR)
    assert isinstance(wrench, WrenchLog)
    est = estimate_payload(robot, wrench)  # at rest: the still windows found
    assert est.wrench is not None and est.at_rest.n_poses == 4
    assert est.mass == pytest.approx(1.2, abs=4 * est.std[0])
    torques = rnea_torques(robot, 0.7, np.array([0.01, 0.02, 0.05]))
    log, before, after, _ = session(Q3, torques, robot.joint_names, noise=0.05)
    joints = read_any_log(write_csv(log, tmp_path / "j.csv"), robot)
    assert isinstance(joints, JointLog)
    est = estimate_payload(robot, joints, before, after, torque_std=0.05 / np.sqrt(200))
    assert est.joint_torques is not None and est.verdict == "identified"
    with pytest.raises(InvalidInputError, match="before= and after="):
        estimate_payload(robot, joints)
    with pytest.raises(InvalidInputError, match="takes no"):
        estimate_payload(robot, joints, before, after, cutoff_hz=4.0)


def test_result_json_reads_back_and_refuses_other_schemas(robot, tmp_path):
    """One schema, written and read back by one module; a file of schema 1 (before 0.3.0) or
    no RESULT.json at all is refused naming what is wrong."""
    from comgrasp_pin.errors import InvalidInputError as Bad
    from comgrasp_pin.robot_io import read_result, write_result
    from comgrasp_pin.robot_io.results.result_file import prior_of_result

    torques = rnea_torques(robot, 0.7, np.array([0.01, 0.02, 0.05]))
    log, before, after, _ = session(Q3, torques, robot.joint_names, noise=0.05)
    est = estimate_from_log(robot, log, before, after)
    data = read_result(write_result(est, tmp_path / "R.json"))
    assert data["schema_version"] == 3 and data["mass_kg"] == est.mass
    np.testing.assert_allclose(data["cov"], est.cov, rtol=1e-15)
    lo, hi = data["interval95_mass_kg"]
    assert lo < est.mass < hi and hi - lo == pytest.approx(2 * est.t95[0] * est.std[0], rel=1e-6)
    mean, cov = prior_of_result(tmp_path / "R.json")
    np.testing.assert_allclose(mean, np.r_[est.mass, est.com_ee], rtol=1e-15)
    old = tmp_path / "old.json"
    old.write_text(json.dumps({"mass_kg": 1.0, "com_m": [0, 0, 0], "cov": np.eye(4).tolist()}))
    with pytest.raises(Bad, match="schema_version None"):
        read_result(old)
    (tmp_path / "bad.json").write_text("{not json")
    with pytest.raises(Bad, match="not a readable RESULT.json"):
        read_result(tmp_path / "bad.json")
