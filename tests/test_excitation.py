"""The excitation motion: limits, collisions and rest checked independently on a finer grid,
observability against random motions, the output files, the command line."""

from __future__ import annotations

import csv
import json
import sys
from pathlib import Path

import numpy as np
import pytest

from comgrasp_pin._paths import urdf_path
from comgrasp_pin.cli import main
from comgrasp_pin.errors import InvalidInputError, UnobservableError
from comgrasp_pin.estimation.payload_regressor import (
    condition_number,
    parameter_scale,
    payload_regressor,
)
from comgrasp_pin.planning.collision import SelfCollision
from comgrasp_pin.planning.excitation import (
    UR_HOME,
    ExcitationSettings,
    plan_excitation,
)
from comgrasp_pin.robot import RobotModel
from comgrasp_pin.robot_io.payload_files import motion_files

sys.path.append(str(Path(__file__).resolve().parents[1] / "benchmarks"))
from excitation_baseline import random_condition_numbers  # noqa: E402  (benchmarks/)

DURATION_S = 8.0
FAST = ExcitationSettings(n_random=300, n_starts=1, max_iter=40)  # a quick search for tests
UR5 = str(urdf_path("ur5_gripper.urdf"))


@pytest.fixture(scope="module")
def robot() -> RobotModel:
    return RobotModel.ur5()


@pytest.fixture(scope="module")
def motion(robot):
    return plan_excitation(robot, DURATION_S, settings=FAST, seed=0)


def _fine(motion, rate_hz=1000.0):
    """q on a grid 10x finer than the motion's, and qd, qdd by central differences of q: an
    independent check of the series' own derivatives."""
    dt = 1.0 / rate_hz
    t = np.arange(-2 * dt, motion.duration_s + 2.5 * dt, dt)
    q = motion.series.evaluate(t)[0]
    qd = np.gradient(q, dt, axis=0)
    qdd = np.gradient(qd, dt, axis=0)
    inside = slice(2, -2)
    return t[inside], q[inside], qd[inside], qdd[inside]


def test_within_the_limits_on_a_finer_grid(robot, motion):
    t, q, qd, qdd = _fine(motion)
    s = motion.settings
    assert t[-1] == pytest.approx(DURATION_S) and DURATION_S <= 20
    assert np.all(q >= robot.q_lower + s.position_margin_rad - 1e-9)
    assert np.all(q <= robot.q_upper - s.position_margin_rad + 1e-9)
    arm = np.array([s.arm_rate_scale] * 3 + [1.0] * 3)  # the wrist does most of the work
    v_max = arm * s.velocity_scale * robot.model.velocityLimit
    assert np.all(np.abs(qd) <= v_max * (1 + 1e-4))
    assert np.all(np.abs(qdd) <= arm * s.acceleration_limit * (1 + 1e-3))
    excursion = np.abs(q - UR_HOME).max(axis=0)
    assert np.all(excursion[:3] <= s.arm_range_rad + 1e-9)
    assert np.all(excursion[3:] <= s.wrist_range_rad + 1e-9)
    rms_speed = np.sqrt(np.mean(qd**2, axis=0))
    assert rms_speed[3:].mean() > 1.5 * rms_speed[:3].mean()


def test_free_of_self_collision_and_the_floor_on_a_finer_grid(robot, motion):
    checker = SelfCollision(robot)
    t = np.arange(0.0, motion.duration_s, 0.004)  # 250 Hz, the motion's samples are 100 Hz
    q = motion.series.evaluate(t)[0]
    assert not any(checker.in_collision(qi) for qi in q)
    lowest = min(min(robot.ee_pose(qi)[2, 3], robot.joint_origins(qi)[-3:, 2].min()) for qi in q)
    assert lowest >= motion.settings.min_height_m
    assert lowest == pytest.approx(motion.min_height_m, abs=5e-3)


def test_at_rest_at_the_start_at_both_ends(motion):
    t, q, qd, qdd = _fine(motion)
    np.testing.assert_allclose(q[0], UR_HOME, atol=1e-12)
    np.testing.assert_allclose(q[-1], UR_HOME, atol=1e-9)
    for i in (0, -1):
        # a first difference over h = 1 ms misses by jerk h^2 / 2 (jerk <= 100 rad/s^3)
        np.testing.assert_allclose(qd[i], 0.0, atol=5e-5)
        np.testing.assert_allclose(qdd[i], 0.0, atol=2e-2)  # differences of differences
    np.testing.assert_allclose(motion.qd[[0, -1]], 0.0, atol=1e-12)
    np.testing.assert_allclose(motion.qdd[[0, -1]], 0.0, atol=1e-12)


def test_ten_parameters_observable_and_better_than_random(robot, motion):
    Y = payload_regressor(robot, motion.q, motion.qd, motion.qdd)
    scale = parameter_scale(motion.settings.typical_length_m)
    assert np.linalg.matrix_rank(Y.reshape(-1, 10) * scale) == 10
    assert motion.condition_number == pytest.approx(condition_number(Y, scale))
    assert motion.condition_number_si == pytest.approx(np.linalg.cond(Y.reshape(-1, 10)))
    random = random_condition_numbers(robot, DURATION_S, settings=FAST, count=20)
    ratio = np.median(random) / motion.condition_number
    print(f"planned {motion.condition_number:.1f}, random median {np.median(random):.1f}, "
          f"ratio {ratio:.2f}")  # fmt: skip
    assert ratio > 1.5


def test_files_parse(motion, tmp_path):
    yaml = pytest.importorskip("yaml")
    data = json.loads(motion_files.write_json(motion, tmp_path / "m.json").read_text())
    assert data["settings"]["n_random"] == FAST.n_random
    assert data["condition_number"] == pytest.approx(motion.condition_number)
    np.testing.assert_allclose(data["samples"]["q_rad"], motion.q)
    with motion_files.write_csv(motion, tmp_path / "m.csv").open() as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == len(motion.t)
    name = motion.joint_names[4]
    got = [float(r[f"{name}.position"]) for r in rows]
    np.testing.assert_allclose(got, motion.q[:, 4], atol=1e-8)
    assert {f"{name}.velocity", f"{name}.acceleration", "time"} <= set(rows[0])
    script = motion_files.write_urscript(motion, tmp_path / "m.script").read_text()
    servoj = [line for line in script.splitlines() if line.strip().startswith("servoj(")]
    assert len(servoj) == round(DURATION_S / 0.008)
    assert script.count("movej(") == 1 and "stopj(" in script
    traj = yaml.safe_load(motion_files.write_ros2(motion, tmp_path / "m.yaml").read_text())
    assert traj["joint_names"] == list(motion.joint_names)
    points = traj["points"]
    assert len(points) == round(DURATION_S / 0.02)
    last = points[-1]
    assert last["time_from_start"] == {"sec": int(DURATION_S), "nanosec": 0}
    assert last["velocities"] == [0] * 6
    np.testing.assert_allclose(last["positions"], UR_HOME, atol=1e-9)
    stamps = [p["time_from_start"]["sec"] + 1e-9 * p["time_from_start"]["nanosec"] for p in points]
    assert np.all(np.diff(stamps) > 0) and stamps[0] > 0


def test_bad_input(robot):
    with pytest.raises(InvalidInputError, match="duration_s"):
        plan_excitation(robot, 25.0)
    with pytest.raises(InvalidInputError, match="inside"):
        plan_excitation(robot, 10.0, start=np.array([0, -1.57, 3.1, 0, 0, 0]))
    five = RobotModel.from_urdf(UR5, "wrist_2_link")
    with pytest.raises(UnobservableError, match="5 joints"):
        plan_excitation(five, 10.0)


FAST_CLI = ["--candidates", "100", "--starts", "1", "--iterations", "10"]


def test_cli_writes_the_files(tmp_path, capsys):
    out = tmp_path / "motion.json"
    args = ["plan-motion", "--urdf", UR5, "--ee-frame", "eelink", "--duration", "6",
            "--out", str(out), "--csv", str(tmp_path / "m.csv"), "--urscript",
            str(tmp_path / "m.script"), "--ros2", str(tmp_path / "m.yaml"), *FAST_CLI]  # fmt: skip
    assert main(args) == 0
    captured = capsys.readouterr()
    assert "condition number" in captured.out and "IPOPT" in captured.err
    assert json.loads(out.read_text())["duration_s"] == 6.0
    assert all((tmp_path / f).is_file() for f in ("m.csv", "m.script", "m.yaml"))


@pytest.mark.parametrize(
    "extra, message",
    [
        (["--ee-frame", "no_such_frame"], "not a frame"),
        (["--ee-frame", "eelink", "--duration", "30"], "duration"),
        (["--ee-frame", "eelink", "--duration", "1"], "duration"),
        (["--ee-frame", "eelink", "--start", "0,-1.57,2.9,-1.57,-1.57,0"], "collides"),
        (["--ee-frame", "eelink", "--start", "0,-1.57,3.2,0,0,0"], "limits"),
        (["--ee-frame", "eelink", "--start", "0,1"], "6 numbers"),
        (["--ee-frame", "wrist_2_link"], "not all observable"),
    ],
)
def test_cli_bad_input_exits_2(tmp_path, capsys, extra, message):
    args = ["plan-motion", "--urdf", UR5, *extra, "--out", str(tmp_path / "m.json"), *FAST_CLI]
    assert main(args) == 2
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err
    assert not (tmp_path / "m.json").exists()
