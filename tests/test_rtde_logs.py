"""robot_io.log_files.rtde / gains: Universal Robots recordings as they come (the RTDE client's
record.py, space-separated; ur_rtde's startFileRecording, comma-separated), motor currents
turned into joint torques by drive gains, the gains' text and JSON; the real UR10e log of
../shared/realdata where present."""

import json
from pathlib import Path

import numpy as np
import pytest
from _logs import rnea_torques, session

from comgrasp_pin._paths import urdf_path
from comgrasp_pin.cli import main
from comgrasp_pin.errors import InvalidInputError, LogError
from comgrasp_pin.robot_io import JointLog, load_robot, parse_gains, read_log, write_bag, write_csv
from comgrasp_pin.robot_io.log_files import Gains, gains_json, read_bag, read_csv, read_rtde
from comgrasp_pin.robot_io.log_files.rtde import is_rtde_header

NAMES = ("j0", "j1", "j2", "j3", "j4", "j5")
K = np.array([10.0, 10.6956, 8.4566, 9.0029, 9.48, 10.1232])  # UR10e, N m per A
REAL = Path(__file__).resolve().parents[2] / "shared" / "realdata" / "ur10e_rtde"
T0 = 838.465  # the controller's clock: not zero-based
NO_GAINS = "this UR log has motor currents, not torques"


def _signals(n_samples=40, seed=0):
    rng = np.random.default_rng(seed)
    t = np.round(T0 + 0.008 * np.arange(n_samples) + 0.003 * rng.random(n_samples), 3)
    t[0] = T0
    return {
        "timestamp": t,
        "actual_q": rng.uniform(-3, 3, (n_samples, 6)),
        "actual_qd": rng.uniform(-1, 1, (n_samples, 6)),
        "actual_current": rng.uniform(-4, 4, (n_samples, 6)),
        "target_current": rng.uniform(-4, 4, (n_samples, 6)),
        "target_moment": rng.uniform(-50, 50, (n_samples, 6)),
    }


def _write(path, signals, sep=" ", order=None, extra=None):
    """A UR recording: a header row of RTDE names (a vector's entries _0.._5), then rows."""
    columns = {}
    for name in order or signals:
        value = signals[name]
        if value.ndim == 1:
            columns[name] = value
        else:
            columns.update({f"{name}_{i}": value[:, i] for i in range(value.shape[1])})
    columns.update(extra or {})
    rows = np.column_stack(list(columns.values()))
    lines = [sep.join(columns)] + [sep.join(f"{x:.6f}" for x in row) for row in rows]
    Path(path).write_text("\n".join(lines) + "\n")
    return Path(path)


def _check(log, s, gains=K):
    np.testing.assert_allclose(log.time, s["timestamp"] - T0, atol=1e-9)  # ms clock
    assert log.time[0] == 0.0 and log.joint_names == NAMES
    np.testing.assert_allclose(log.position, s["actual_q"], atol=1e-6)
    np.testing.assert_allclose(log.velocity, s["actual_qd"], atol=1e-6)
    np.testing.assert_allclose(log.effort, s["actual_current"] * gains, atol=1e-5)
    np.testing.assert_array_equal(log.current_gains, gains)


def test_record_py_log_space_separated(tmp_path):
    """record.py's full header; target_moment (the controller's model) is not the effort."""
    s = _signals()
    path = _write(tmp_path / "record.csv", s)
    assert is_rtde_header(path.read_text().splitlines()[0])
    log = read_rtde(path, NAMES, Gains(K, np.zeros((6, 6))))
    _check(log, s)
    assert not np.allclose(log.effort, s["target_moment"], atol=1.0)
    _check(read_csv(path, NAMES, Gains(K, np.zeros((6, 6)))), s)  # --csv takes it as it is
    _check(read_log(path, NAMES, gains=Gains(K, np.zeros((6, 6)))), s)


def test_ur_rtde_log_comma_separated_with_other_columns(tmp_path):
    """ur_rtde's CSV: a subset of the columns, in another order, and one more."""
    s = _signals(seed=1)
    extra = {"runtime_state": np.full(len(s["timestamp"]), 2.0)}
    order = ["actual_current", "timestamp", "actual_qd", "actual_q"]
    path = _write(tmp_path / "ur_rtde.csv", s, ",", order, extra)
    gains = parse_gains(",".join(map(str, K)), 6, 0.1)
    _check(read_csv(path, NAMES, gains), s)


def test_torque_columns_are_read_without_gains(tmp_path):
    s = _signals(seed=2)
    tau = np.random.default_rng(3).uniform(-20, 20, s["actual_q"].shape)
    extra = {f"actual_current_as_torque_{i}": tau[:, i] for i in range(6)}
    path = _write(tmp_path / "torques.csv", s, ",", ["timestamp", "actual_q"], extra)
    log = read_csv(path, NAMES)
    np.testing.assert_allclose(log.effort, tau, atol=1e-5)
    assert log.velocity is None and log.current_gains is None


def test_unsorted_and_repeated_timestamps_are_sorted(tmp_path):
    s = _signals(seed=4)
    s["timestamp"][[5, 6]] = s["timestamp"][[6, 5]]
    s["timestamp"][10] = s["timestamp"][9]
    log = read_rtde(_write(tmp_path / "r.csv", s), NAMES, Gains(K, np.zeros((6, 6))))
    assert np.all(np.diff(log.time) >= 0) and log.time[0] == 0.0
    np.testing.assert_allclose(log.position[5], s["actual_q"][6], atol=1e-6)


def test_current_log_without_gains_is_refused(tmp_path):
    path = _write(tmp_path / "record.csv", _signals())
    with pytest.raises(LogError, match=NO_GAINS) as exc:
        read_csv(path, NAMES)
    assert "--current-gains K1,...,K6" in str(exc.value) and "--gain-std" in str(exc.value)
    assert "calibrate-gains" in str(exc.value)


@pytest.mark.parametrize(
    "case, match",
    [
        ("five joints", "has 6 joints"),
        ("five gains", "5 drive gains"),
        ("nan", "NaN or inf"),
        ("no efforts", "no joint efforts"),
        ("gains, no currents", "no motor currents"),
        ("not a UR log", "not a UR RTDE recording"),
        ("text", "not a number"),
    ],
)
def test_bad_ur_logs_are_refused(tmp_path, case, match):
    s = _signals(seed=5)
    gains = Gains(K, np.zeros((6, 6)))
    names = NAMES
    path = tmp_path / "r.csv"
    if case == "five joints":
        names = NAMES[:5]
    if case == "five gains":
        gains = Gains(K[:5], np.zeros((5, 5)))
    if case == "nan":
        s["actual_current"][7, 2] = np.nan
    _write(path, s, order=["timestamp", "actual_q"] if "efforts" in case else None)
    if case == "gains, no currents":
        _write(path, s, order=["timestamp", "actual_q", "target_moment"])
    if case == "not a UR log":
        path.write_text("time,j0.position\n0,1\n")
    if case == "text":
        lines = path.read_text().splitlines()
        lines[3] = "abc" + lines[3][lines[3].index(" ") :]
        path.write_text("\n".join(lines) + "\n")
    with pytest.raises(LogError, match=match):
        read_rtde(path, names, None if case == "no efforts" else gains)


def test_nan_message_names_the_line_and_column(tmp_path):
    s = _signals(seed=6)
    s["actual_q"][3, 4] = np.inf
    with pytest.raises(LogError, match=r"line 5 in 'actual_q_4'"):
        read_rtde(_write(tmp_path / "r.csv", s), NAMES, Gains(K, np.zeros((6, 6))))


def test_the_project_csv_and_a_bag_take_gains_for_current_efforts(tmp_path):
    """A driver that publishes currents as JointState efforts: gains * efforts."""
    t = np.arange(20) * 0.01
    rng = np.random.default_rng(7)
    log = JointLog(t, NAMES, rng.normal(size=(20, 6)), rng.normal(size=(20, 6)))
    gains = Gains(K, np.zeros((6, 6)))
    csv_log = read_csv(write_csv(log, tmp_path / "log.csv"), NAMES, gains)
    bag_log = read_bag(write_bag(log, tmp_path / "bag"), NAMES, gains=gains)
    for back in (csv_log, bag_log):
        np.testing.assert_allclose(back.effort, log.effort * K)
        np.testing.assert_array_equal(back.current_gains, K)
    assert read_csv(tmp_path / "log.csv", NAMES).current_gains is None


def test_parse_gains_from_text():
    g = parse_gains(" 10, 10.6956,8.4566,9.0029,9.48,10.1232", 6, 0.1, correlation=0.0)
    np.testing.assert_array_equal(g.values, K)
    np.testing.assert_allclose(g.cov, np.diag((0.1 * K) ** 2))
    np.testing.assert_allclose(g.std, 0.1 * K)
    shared = parse_gains(",".join(map(str, K)), 6, 0.1)  # default: half the variance common
    np.testing.assert_allclose(shared.std, 0.1 * K)
    np.testing.assert_allclose(shared.cov[0, 1], 0.5 * 0.01 * K[0] * K[1])
    one = parse_gains(",".join(map(str, K)), 6, 0.1, correlation=1.0)  # one common error
    assert np.linalg.matrix_rank(one.cov) == 1
    with pytest.raises(InvalidInputError, match="between 0"):
        parse_gains(",".join(map(str, K)), 6, 0.1, correlation=1.5)
    assert "10 %" in g.source and g.joint_names is None
    exact = parse_gains(",".join(map(str, K)), 6, None)
    assert np.all(exact.cov == 0) and "not given" in exact.source


@pytest.mark.parametrize(
    "text, gain_std, match",
    [
        ("10,10,10,10,10", 0.1, "6 gains expected"),
        ("10,10,10,10,10,-1", 0.1, "positive finite"),
        ("10,10,10,10,10,nan", 0.1, "positive finite"),
        ("10,10,10,10,10,10", -0.1, "finite number >= 0"),
        ("10,10,10,10,10,10", float("inf"), "finite number >= 0"),
        ("10,10,x,10,10,10", 0.1, "comma-separated numbers"),
        ("nonsense", None, "comma-separated numbers"),
        ("missing.json", None, "not found"),
    ],
)
def test_parse_gains_refuses(text, gain_std, match):
    with pytest.raises(InvalidInputError, match=match):
        parse_gains(text, 6, gain_std)


def test_gains_json_round_trip(tmp_path):
    cov = np.diag((0.02 * K) ** 2)
    cov[1, 2] = cov[2, 1] = 0.5 * np.sqrt(cov[1, 1] * cov[2, 2])
    data = gains_json(K, cov, NAMES, known_mass_kg=2.805)
    path = tmp_path / "gains.json"
    path.write_text(json.dumps(data))
    g = parse_gains(str(path), 6, None, NAMES)
    np.testing.assert_array_equal(g.values, K)
    np.testing.assert_allclose(g.cov, cov, rtol=1e-15)
    assert g.joint_names == NAMES and g.source == str(path)
    assert json.loads(path.read_text())["known_mass_kg"] == 2.805
    replaced = parse_gains(str(path), 6, 0.1, NAMES, 0.0)  # --gain-std replaces the JSON's cov
    np.testing.assert_allclose(replaced.cov, np.diag((0.1 * K) ** 2))
    assert "replaced" in replaced.source
    with pytest.raises(InvalidInputError, match="format's own keys"):
        gains_json(K, cov, NAMES, gains_Nm_per_A=[1.0] * 6)


@pytest.mark.parametrize(
    "change, match",
    [
        ({"cov": None}, "lacks the keys"),
        ({"gains_Nm_per_A": [10.0] * 5}, "6 gains expected"),
        ({"cov": np.eye(5).tolist()}, "6 x 6"),
        ({"cov": np.triu(np.ones((6, 6))).tolist()}, "not symmetric"),
        ({"cov": (-np.eye(6)).tolist()}, "not positive semi-definite"),
        ({"joint_names": [f"ur_{n}" for n in NAMES]}, "ur_j0.*'j0'"),
        ({"gains_Nm_per_A": "ten"}, "list of 6 numbers"),
    ],
)
def test_bad_gains_json_is_refused(tmp_path, change, match):
    data = {**gains_json(K, np.eye(6) * 0.01, NAMES), **change}
    data = {k: v for k, v in data.items() if v is not None}
    path = tmp_path / "gains.json"
    path.write_text(json.dumps(data))
    with pytest.raises(InvalidInputError, match=match):
        parse_gains(str(path), 6, None, NAMES)


def test_gains_json_for_other_joints_is_refused_by_the_reader(tmp_path):
    path = _write(tmp_path / "r.csv", _signals())
    gains = Gains(K, np.zeros((6, 6)), "g.json", tuple(f"ur_{n}" for n in NAMES))
    with pytest.raises(LogError, match="belong to the joints"):
        read_rtde(path, NAMES, gains)


# --- the command line -----------------------------------------------------------------------

URDF = str(urdf_path("ur5_gripper.urdf"))
UR_Q = np.array(
    [[0.0, -1.6, 1.6, -1.57, -1.57, 0.0], [0.4, -1.2, 1.2, -0.4, 0.8, 1.0],
     [-0.5, -1.9, 1.5, -2.5, -0.6, -1.2]]
)  # fmt: skip
MASS, COM = 0.8, np.array([0.02, -0.01, 0.05])


@pytest.fixture(scope="module")
def ur_current_log(tmp_path_factory):
    """A static before/after session of the project's UR5, written as record.py writes it:
    currents = torques / K, the controller's clock."""
    robot = load_robot(URDF, "eelink")
    log, before, after, _ = session(UR_Q, rnea_torques(robot, MASS, COM), robot.joint_names,
                                    100.0, 0.05, seed=3)  # fmt: skip
    s = {"timestamp": log.time + T0, "actual_q": log.position, "actual_qd": 0 * log.position,
         "actual_current": log.effort / K, "target_moment": log.effort}  # fmt: skip
    path = _write(tmp_path_factory.mktemp("ur") / "record.csv", s)
    return path, before, after


def _estimate(path, before, after, out, *more):
    w = lambda ws: ",".join(f"{a:.3f}:{b:.3f}" for a, b in ws)  # noqa: E731
    return ["estimate", "--urdf", URDF, "--ee-frame", "eelink", "--csv", str(path),
            "--before", w(before), "--after", w(after), "--out", str(out), *more]  # fmt: skip


def test_cli_refuses_a_current_log_without_gains(ur_current_log, tmp_path, capsys):
    path, before, after = ur_current_log
    out = tmp_path / "R.json"
    assert main(_estimate(path, before, after, out)) == 2
    err = capsys.readouterr().err
    assert NO_GAINS in err and "--current-gains" in err and "Traceback" not in err
    assert main(_estimate(path, before, after, out, "--gain-std", "0.1")) == 2
    assert "give them too" in capsys.readouterr().err
    assert main(_estimate(path, before, after, out, "--current-gains", "1,2,3")) == 2
    assert "6 gains expected" in capsys.readouterr().err
    assert not out.exists()


def test_cli_estimates_from_a_current_log_with_gains(ur_current_log, tmp_path, capsys):
    path, before, after = ur_current_log
    out = tmp_path / "R.json"
    gains = ",".join(f"{k:.6f}" for k in K)
    assert main(_estimate(path, before, after, out, "--current-gains", gains,
                          "--gain-std", "0.05")) == 0  # fmt: skip
    r = json.loads(out.read_text())
    std = np.sqrt(np.diag(r["cov"]))
    assert abs(r["mass_kg"] - MASS) < 4 * std[0] + 1e-3
    np.testing.assert_allclose(r["com_m"], COM, atol=4 * std[1:].max() + 1e-3)


# --- the real UR10e ---------------------------------------------------------------------------


def test_real_ur10e_recording():
    """The UR10e's excitation without load (record.py, space-separated, .csv): 6 joints at
    ~100 Hz for ~56 s. Gains times currents against the URDF's gravity torques on
    shoulder_lift and elbow, where the arm is far from upright (|g| > 30 N m): the same
    sign and size. Still, the arm only rests upright (gravity torques 7 and 2 N m), where
    static friction decides the current's sign: those samples test nothing."""
    path = REAL / "excitation_empty.csv"
    if not path.exists():
        pytest.skip(f"the real data is not here: {REAL} (../shared/realdata/ur10e_rtde)")
    robot = load_robot(REAL / "ur10e.urdf", "tool0", None, (0, 0, -9.81))
    log = read_csv(path, robot.joint_names, parse_gains(",".join(map(str, K)), 6, 0.1))
    assert log.position.shape[1] == 6 and log.time[0] == 0.0
    assert 55 < log.duration < 58
    assert abs(np.median(np.diff(log.time)) - 0.01) < 1e-3
    g = np.array([robot.gravity_torques(q) for q in log.position[::5]])
    tau = log.effort[::5]
    for j in (1, 2):  # shoulder_lift, elbow
        far = np.abs(g[:, j]) > 30
        assert far.sum() > 100
        assert np.mean(np.sign(tau[far, j]) == np.sign(g[far, j])) > 0.95
        ratio = np.median(tau[far, j] / g[far, j])
        assert 0.5 < ratio < 2, (j, ratio)
