"""Values no sensor gives (issue 41): every log reader refuses them, naming where they are.

A damaged file (one value 1e300, a time in ns) must never reach a fit that would call its
answer identified. Each reader kind (the project's joint CSV, a UR recording, the wrench
CSV, a UR recording's wrench, JointState and WrenchStamped bags written by the project's
own writers) is given a file with one bad value put at a line and column chosen here, and
the message must name them; values just inside the ceilings are read, and the real logs of
../shared/realdata read as before. ``calibrate-gains`` given one run as both loaded and
empty says that the runs show no payload, instead of printing absurd gains.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from _payload import payload_model

from comgrasp_pin._paths import urdf_path
from comgrasp_pin.cli import main
from comgrasp_pin.config import (
    MAX_ABS_FORCE_N,
    MAX_ABS_JOINT_EFFORT,
    MAX_ABS_JOINT_POSITION_RAD,
    MAX_ABS_JOINT_VELOCITY_RAD_S,
    MAX_ABS_TIME_S,
    MAX_ABS_TORQUE_NM,
)
from comgrasp_pin.errors import LogError
from comgrasp_pin.robot_io import JointLog, load_robot, parse_gains, write_bag, write_csv
from comgrasp_pin.robot_io.log_files import Gains, read_bag, read_csv, read_rtde
from comgrasp_pin.robot_io.log_files.log_types import WrenchLog
from comgrasp_pin.robot_io.log_files.record import (
    DEFAULT_WRENCH_TOPIC,
    T0_NS,
    write_wrench_bag,
    write_wrench_csv,
)
from comgrasp_pin.robot_io.log_files.wrench_files import read_wrench_bag, read_wrench_csv
from comgrasp_pin.robot_io.log_files.wrench_sources import read_rtde_wrench

NAMES = ("j0", "j1", "j2", "j3", "j4", "j5")
K = np.array([10.0, 10.6956, 8.4566, 9.0029, 9.48, 10.1232])  # UR10e, N m per A
GAINS = ",".join(map(str, K))
REALDATA = Path(__file__).resolve().parents[2] / "shared" / "realdata"
UR_DIR = REALDATA / "ur10e_rtde"
URDF = str(urdf_path("ur5_gripper.urdf"))
HUGE = 1e300
NO_SENSOR = "values no sensor gives"


def _real(path: Path) -> Path:
    if not path.exists():
        pytest.skip(f"the real data is not here: {path} (../shared/realdata)")
    return path


def _joint_log(n_samples=30, seed=0) -> JointLog:
    rng = np.random.default_rng(seed)
    return JointLog(
        np.arange(n_samples) * 0.01, NAMES, rng.uniform(-3, 3, (n_samples, 6)),
        rng.uniform(-40, 40, (n_samples, 6)), "synthetic", rng.uniform(-1, 1, (n_samples, 6)),
    )  # fmt: skip


def _set_cell(path: Path, line: int, column: str, value: str, sep: str = ",") -> Path:
    """Write ``value`` into ``column`` on the file's 1-based ``line`` (the header is line 1)."""
    lines = path.read_text().splitlines()
    header = lines[0].split(sep) if sep else lines[0].split()
    cells = lines[line - 1].split(sep) if sep else lines[line - 1].split()
    cells[header.index(column)] = value
    lines[line - 1] = (sep or " ").join(cells)
    path.write_text("\n".join(lines) + "\n")
    return path


def _ur_recording(path: Path, n_samples=40, seed=0, extra=()) -> Path:
    """A record.py file (space-separated): timestamp, actual_q, actual_qd, actual_current."""
    rng = np.random.default_rng(seed)
    names = ["timestamp"] + [f"{v}_{i}" for v in ("actual_q", "actual_qd", "actual_current",
                                                  *extra) for i in range(6)]  # fmt: skip
    rows = rng.uniform(-3, 3, (n_samples, len(names)))
    rows[:, 0] = 838.465 + 0.008 * np.arange(n_samples)
    lines = [" ".join(names)] + [" ".join(f"{x:.6f}" for x in r) for r in rows]
    path.write_text("\n".join(lines) + "\n")
    return path


# --- text files: the line a text editor shows, the column's name ------------------------------


def test_joint_csv_names_the_line_and_column(tmp_path):
    path = _set_cell(write_csv(_joint_log(), tmp_path / "a.csv"), 13, "j4.effort", "1e300")
    with pytest.raises(LogError) as exc:
        read_csv(path, NAMES)
    message = str(exc.value)
    assert f"CSV {path}" in message and NO_SENSOR in message
    assert "on line 13 in 'j4.effort': 1e+300" in message
    assert "+-1e+06" in message and "MAX_ABS_JOINT_EFFORT" in message


def test_blank_and_comment_lines_count_as_lines(tmp_path):
    """The loader skips them; the line named is still the editor's."""
    path = write_csv(_joint_log(), tmp_path / "a.csv")
    lines = path.read_text().splitlines()
    lines[5:5] = ["", "# a note by hand", ""]  # lines 6-8; the old line 6 becomes line 9
    path.write_text("\n".join(lines) + "\n")
    _set_cell(path, 9, "j1.velocity", "-2e7")
    with pytest.raises(LogError, match=r"on line 9 in 'j1.velocity': -2e\+07"):
        read_csv(path, NAMES)


def test_joint_csv_nan_is_refused_with_its_line(tmp_path):
    path = _set_cell(write_csv(_joint_log(), tmp_path / "a.csv"), 4, "j0.position", "nan")
    with pytest.raises(LogError, match=r"NaN or inf values \(1\), first on line 4 in 'j0\."):
        read_csv(path, NAMES)


def test_ur_recording_names_the_line_and_column(tmp_path):
    path = _ur_recording(tmp_path / "r.csv")
    for line in (21, 22, 23):
        _set_cell(path, line, "actual_current_2", "1e300", sep=None)
    with pytest.raises(LogError) as exc:
        read_rtde(path, NAMES, Gains(K, np.zeros((6, 6))))
    message = str(exc.value)
    assert f"UR log {path} has {NO_SENSOR} (3), first on line 21 in 'actual_current_2'" in message
    assert "1e+300" in message and "+-1e+06" in message


def test_a_time_in_nanoseconds_is_refused(tmp_path):
    path = _set_cell(_ur_recording(tmp_path / "r.csv"), 2, "timestamp", "1.7e18", sep=None)
    with pytest.raises(LogError, match=r"on line 2 in 'timestamp': 1\.7e\+18.*\+-1e\+10"):
        read_rtde(path, NAMES, Gains(K, np.zeros((6, 6))))


def _wrench_log(n_samples=30, seed=1) -> WrenchLog:
    rng = np.random.default_rng(seed)
    log = _joint_log(n_samples, seed)
    wrench = np.column_stack([rng.normal(0, 20, (n_samples, 3)), rng.normal(0, 2, (n_samples, 3))])
    return WrenchLog(log.time, NAMES, log.position, wrench, "tool0", "synthetic", log.velocity,
                     log.effort)  # fmt: skip


def test_wrench_csv_names_the_line_and_column(tmp_path):
    path = _set_cell(write_wrench_csv(tmp_path / "w.csv", _wrench_log()), 17, "torque_y", "3e5")
    with pytest.raises(LogError) as exc:
        read_wrench_csv(path, NAMES, "tool0")
    message = str(exc.value)
    assert "on line 17 in 'torque_y': 300000" in message
    assert "a torque (N m) lies within +-100000" in message


def test_ur_wrench_names_the_line_and_column(ur5, tmp_path):
    path = _ur_recording(tmp_path / "r.csv", seed=2, extra=("actual_TCP_force",))
    _set_cell(path, 30, "actual_TCP_force_1", "-5e6", sep=None)
    with pytest.raises(LogError, match=r"on line 30 in 'actual_TCP_force_1': -5e\+06.*force"):
        read_rtde_wrench(path, ur5, "tool0")


# --- bags written by the project's writers: the message's time and topic ---------------------


def test_joint_bag_names_the_message_and_joint(tmp_path):
    log = _joint_log()
    effort = log.effort.copy()
    effort[7, 3] = HUGE
    bag = write_bag(dataclasses.replace(log, effort=effort), tmp_path / "bag")
    with pytest.raises(LogError) as exc:
        read_bag(bag, NAMES)
    message = str(exc.value)
    t_ns = T0_NS + 70_000_000  # sample 7 at 0.07 s
    assert f"bag {bag}" in message and NO_SENSOR in message
    assert (f"in the message of topic '/joint_states' at {t_ns // 10**9}.{t_ns % 10**9:09d} s "
            "(0.070 s after its first message) in 'j3 effort': 1e+300") in message  # fmt: skip


def test_wrench_bag_names_the_message_and_field(tmp_path):
    log = _wrench_log()
    wrench = log.wrench.copy()
    wrench[11, 2] = 2e6
    bad = dataclasses.replace(log, wrench=wrench)
    bag = write_wrench_bag(tmp_path / "bag", bad, storage="mcap")
    with pytest.raises(LogError) as exc:
        read_wrench_bag(bag, NAMES)
    message = str(exc.value)
    assert f"topic {DEFAULT_WRENCH_TOPIC!r}" in message
    assert "(0.110 s after its first message)" in message
    assert "in 'force_z': 2e+06" in message and "+-1e+06" in message


# --- just inside the ceilings: read --------------------------------------------------------------


def test_values_just_inside_the_ceilings_are_read(tmp_path):
    inside = 1 - 1e-6
    log = _joint_log()
    position, velocity, effort = (a.copy() for a in (log.position, log.velocity, log.effort))
    position[3, 0] = -inside * MAX_ABS_JOINT_POSITION_RAD
    velocity[4, 1] = inside * MAX_ABS_JOINT_VELOCITY_RAD_S
    effort[5, 2] = -inside * MAX_ABS_JOINT_EFFORT
    edge = dataclasses.replace(log, position=position, velocity=velocity, effort=effort)
    back = read_csv(write_csv(edge, tmp_path / "a.csv"), NAMES)
    assert back.effort[5, 2] == pytest.approx(-inside * MAX_ABS_JOINT_EFFORT)
    assert read_bag(write_bag(edge, tmp_path / "bag"), NAMES).velocity[4, 1] > 9e3
    w = _wrench_log()
    wrench = w.wrench.copy()
    wrench[2, 0], wrench[2, 5] = inside * MAX_ABS_FORCE_N, -inside * MAX_ABS_TORQUE_NM
    w_csv = write_wrench_csv(tmp_path / "w.csv", dataclasses.replace(w, wrench=wrench))
    assert read_wrench_csv(w_csv, NAMES, "tool0").wrench[2, 0] > 9e5
    late = _set_cell(_ur_recording(tmp_path / "r.csv"), 2, "timestamp", "1.7e9", sep=None)
    assert read_rtde(late, NAMES, Gains(K, np.zeros((6, 6)))).duration > 1e9  # Unix time, s


def test_the_ceilings_are_ten_times_what_real_sensors_give():
    """Independent of the code: data-sheet maxima (a 3 m, 1 t industrial arm's shoulder about
    1e5 N m; the largest six-axis sensors about 1e5 N and several 1e3 N m) and clocks."""
    assert MAX_ABS_JOINT_EFFORT >= 10 * 1e5 and MAX_ABS_FORCE_N >= 10 * 1e5
    assert MAX_ABS_TORQUE_NM >= 10 * 6e3 and MAX_ABS_TIME_S > 4e9  # Unix time until 2096
    assert MAX_ABS_JOINT_POSITION_RAD >= 100 * 2 * np.pi and MAX_ABS_JOINT_VELOCITY_RAD_S >= 2100


# --- real logs: read as before; one damaged value refused on the command line ----------------


def test_the_real_logs_read(tmp_path):
    ur_dir = _real(UR_DIR)
    robot = load_robot(ur_dir / "ur10e.urdf", "tool0", None, (0, 0, -9.81))
    for name in ("excitation_loaded_2805g.csv", "excitation_empty.csv"):
        log = read_csv(ur_dir / name, robot.joint_names, parse_gains(GAINS, 6, 0.1))
        assert len(log.time) > 5000 and np.abs(log.effort).max() < 300
    panda = _real(REALDATA / "panda_tauJ" / "excitation_no_payload.csv")
    joints = [f"panda_joint{i}" for i in range(1, 8)]
    assert read_csv(panda, joints).position.shape == (20544, 7)
    # TIAGo's three files (one clock), put into the project's CSV: their values as logged
    tiago = _real(REALDATA / "tiago")
    kinds = {"position": "position", "velocity": "velocity", "effort": "effort"}
    data = {k: np.loadtxt(tiago / f"tiago_{k}.csv", delimiter=",", skiprows=1) for k in kinds}
    arm = [f"arm_{i}_joint" for i in range(1, 8)]
    header = ["time"] + [f"{j}.{k}" for k in kinds for j in ["torso_lift_joint", *arm]]
    table = np.column_stack([data["position"][:, 0], *(data[k][:, 1:] for k in kinds)])
    path = tmp_path / "tiago.csv"
    np.savetxt(path, table, delimiter=",", header=",".join(header), comments="")
    assert read_csv(path, ["torso_lift_joint", *arm]).position.shape == (8022, 8)


def test_cli_refuses_a_real_ur10e_log_with_one_current_damaged(tmp_path, capsys):
    ur_dir = _real(UR_DIR)
    lines = (ur_dir / "excitation_loaded_2805g.csv").read_text().splitlines()
    column = lines[0].split().index("actual_current_3")
    for line in range(2001, 2011):  # ten samples, lines 2001-2010 as an editor numbers them
        cells = lines[line - 1].split()
        cells[column] = "1e300"
        lines[line - 1] = " ".join(cells)
    bad = tmp_path / "BAD.csv"
    bad.write_text("\n".join(lines) + "\n")
    out = tmp_path / "R.json"
    code = main(["estimate", "--dynamic", "--urdf", str(ur_dir / "ur10e.urdf"), "--ee-frame",
                 "tool0", "--csv", str(bad), "--empty-csv", str(ur_dir / "excitation_empty.csv"),
                 "--current-gains", GAINS, "--out", str(out)])  # fmt: skip
    err = capsys.readouterr().err
    assert code == 2 and not out.exists() and "Traceback" not in err
    assert f"UR log {bad} has {NO_SENSOR} (10), first on line 2001 in 'actual_current_3'" in err
    assert "1e+300" in err and "+-1e+06" in err


# --- calibrate-gains: one run given as loaded and as empty -----------------------------------


def _excitation_recording(path: Path, robot, mass: float, seed: int) -> Path:
    """A 12 s, 100 Hz UR recording of a sum-of-sines motion: currents = RNEA torques / K
    (with a payload of ``mass`` kg at the flange, 0: none) plus 0.02 A of noise."""
    rng = np.random.default_rng(seed)
    t = np.arange(0, 12, 0.01)
    mid = np.array([0.3, -1.4, 1.6, -1.7, -1.5, 0.4])
    amp, freq = np.full(6, 0.6), np.array([0.13, 0.17, 0.23, 0.29, 0.31, 0.37]) * 2
    phase = 2 * np.pi * freq * t[:, None]
    q = mid + amp * np.sin(phase)
    qd = amp * 2 * np.pi * freq * np.cos(phase)
    qdd = -amp * (2 * np.pi * freq) ** 2 * np.sin(phase)
    model = payload_model(robot, mass, np.array([0.0, 0.0, 0.05])) if mass else robot.model
    data = model.createData()
    tau = np.array([pin.rnea(model, data, *row) for row in zip(q, qd, qdd)])
    current = tau / K + rng.normal(0, 0.02, tau.shape)
    names = ["timestamp"] + [f"{v}_{i}" for v in ("actual_q", "actual_qd", "actual_current")
                             for i in range(6)]  # fmt: skip
    rows = np.column_stack([1000.0 + t, q, qd, current])
    path.write_text(" ".join(names) + "\n" + "\n".join(" ".join(f"{x:.6f}" for x in r)
                                                       for r in rows) + "\n")  # fmt: skip
    return path


def _calibrate(loaded, empty, out, mass="1.5"):
    return ["calibrate-gains", "--urdf", URDF, "--ee-frame", "eelink", "--csv", str(loaded),
            "--empty-csv", str(empty), "--known-mass", mass, "--current-gains", GAINS,
            "--out", str(out)]  # fmt: skip


def test_calibrate_gains_with_one_run_as_loaded_and_empty_says_no_payload(tmp_path, capsys):
    robot = load_robot(URDF, "eelink")
    loaded = _excitation_recording(tmp_path / "loaded.csv", robot, 1.5, seed=1)
    empty = _excitation_recording(tmp_path / "empty.csv", robot, 0.0, seed=2)
    out = tmp_path / "G.json"
    assert main(_calibrate(loaded, empty, out)) == 0  # a payload shows: calibrated
    capsys.readouterr()
    out.unlink()
    for run in (loaded, empty):
        assert main(_calibrate(run, run, out)) == 2
        err = capsys.readouterr().err
        assert "show no payload" in err and "both are the same file" in err
        assert "--empty-csv the same motion with nothing held" in err
        assert "positive finite" not in err and "Traceback" not in err and not out.exists()
    assert main(_calibrate(empty, loaded, out)) == 2
    assert "negative payload" in capsys.readouterr().err and not out.exists()


def test_calibrate_gains_on_the_real_run_given_twice(tmp_path, capsys):
    run = _real(UR_DIR / "excitation_loaded_2805g.csv")
    out = tmp_path / "G.json"
    args = ["calibrate-gains", "--urdf", str(UR_DIR / "ur10e.urdf"), "--ee-frame", "tool0",
            "--csv", str(run), "--empty-csv", str(run), "--known-mass", "2.805",
            "--known-mass-std", "0.005", "--current-gains", GAINS, "--out", str(out)]  # fmt: skip
    assert main(args) == 2
    err = capsys.readouterr().err
    assert "show no payload" in err and "at the noise level" in err and not out.exists()
