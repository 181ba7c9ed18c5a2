"""robot_io wrench sources: real bags (rosbags, sqlite3 and mcap), CSV, UR recordings.

The bags of the interpolation, clock and refusal tests are written here with rosbags itself,
not with ``record.write_wrench_bag``; the UR recordings' wrenches are a payload's gravity
wrench computed here from the law (F = m g at the CoM, torque about the TCP = (p_c - p_tcp)
x F) and compared with m g and c x m g in the sensor frame, both from Pinocchio's frame poses.
"""

from dataclasses import replace

import numpy as np
import pytest

from comgrasp_pin._paths import example_robot_data_dir, urdf_path
from comgrasp_pin.errors import InvalidInputError, LogError
from comgrasp_pin.robot_io import WrenchLog, load_robot, read_wrench_log
from comgrasp_pin.robot_io.log_files import (
    read_rtde_wrench,
    read_wrench_bag,
    read_wrench_csv,
    write_wrench_bag,
    write_wrench_csv,
)
from comgrasp_pin.robot_io.log_files.wrench_files import MAX_JOINT_GAP_S

Q0 = np.array([0.0, -1.2, 1.5, -1.9, -1.57, 0.0])
RATE_Q = np.array([0.3, -0.2, 0.1, 0.4, -0.5, 0.6])  # rad/s: positions linear in time
JS, WS = "sensor_msgs/msg/JointState", "geometry_msgs/msg/WrenchStamped"
T0_NS = 1_700_000_000_000_000_000


@pytest.fixture(scope="module")
def names(ur5):
    return tuple(ur5.joint_names)


def _log(names, n=80, velocity=True, effort=True, frame="gripper_base"):
    rng = np.random.default_rng(3)
    t = np.arange(n) * 0.002
    q = Q0 + t[:, None] * RATE_Q
    return WrenchLog(t, names, q, rng.normal(size=(n, 6)) * [5, 5, 5, 0.3, 0.3, 0.3], frame,
                     velocity=np.tile(RATE_Q, (n, 1)) if velocity else None,
                     effort=rng.normal(size=(n, 6)) if effort else None)  # fmt: skip


# --- round trips through real files -------------------------------------------------------


@pytest.mark.parametrize("storage", ["sqlite3", "mcap"])
def test_bag_round_trip(names, tmp_path, storage):
    log = _log(names)
    back = read_wrench_bag(write_wrench_bag(tmp_path / "bag", log, storage=storage), names)
    assert back.sensor_frame == "gripper_base" and back.joint_names == names
    np.testing.assert_array_equal(back.wrench, log.wrench)
    np.testing.assert_array_equal(back.position, log.position)
    np.testing.assert_array_equal(back.velocity, log.velocity)
    np.testing.assert_array_equal(back.effort, log.effort)
    np.testing.assert_allclose(back.time, log.time, atol=1e-9)


@pytest.mark.parametrize("storage", ["sqlite3", "mcap", "csv"])
def test_velocity_and_effort_are_none_where_not_logged(names, tmp_path, storage):
    log = _log(names, velocity=False, effort=False)
    if storage == "csv":
        back = read_wrench_csv(write_wrench_csv(tmp_path / "w.csv", log), names, "gripper_base")
    else:
        back = read_wrench_bag(write_wrench_bag(tmp_path / "b", log, storage=storage), names)
    assert back.velocity is None and back.effort is None
    np.testing.assert_allclose(back.wrench, log.wrench, rtol=1e-9)


def test_csv_round_trip(names, tmp_path):
    log = _log(names)
    back = read_wrench_csv(write_wrench_csv(tmp_path / "w.csv", log), list(names), "ft")
    assert back.sensor_frame == "ft"
    for field in ("time", "position", "wrench", "velocity", "effort"):
        np.testing.assert_allclose(getattr(back, field), getattr(log, field), rtol=1e-9,
                                   atol=1e-12, err_msg=field)  # fmt: skip


def test_read_wrench_log_dispatches_and_checks_the_frame(ur5, names, tmp_path):
    log = _log(names)
    bag = write_wrench_bag(tmp_path / "bag", log, storage="mcap")
    (mcap,) = bag.glob("*.mcap")
    assert read_wrench_log(mcap, ur5).sensor_frame == "gripper_base"
    csv = write_wrench_csv(tmp_path / "w.csv", log)
    assert read_wrench_log(csv, names, sensor_frame="eelink").sensor_frame == "eelink"
    with pytest.raises(InvalidInputError, match="not a frame of the model.*'eelink'"):
        read_wrench_log(csv, ur5, sensor_frame="ft_sensr")
    with pytest.raises(InvalidInputError, match="sensor frame must be named"):
        read_wrench_log(csv, ur5)
    other = write_wrench_bag(tmp_path / "other", replace(log, sensor_frame="ati_link"))
    with pytest.raises(InvalidInputError, match="'ati_link' is not a frame"):
        read_wrench_log(other, ur5)


# --- bags written with rosbags here: clocks, interpolation, refusals ----------------------


def _write(path, joints, wrenches, storage="sqlite3"):
    """A bag of (topic, t_ns, stamp_ns, names, q, qd, tau) JointStates and (topic, t_ns,
    stamp_ns, frame_id, wrench) WrenchStampeds."""
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS2_HUMBLE)
    kinds = ("builtin_interfaces/msg/Time", "std_msgs/msg/Header", "geometry_msgs/msg/Vector3",
             "geometry_msgs/msg/Wrench")  # fmt: skip
    T, H, V3, W = (store.types[k] for k in kinds)

    def header(ns, frame=""):
        return H(stamp=T(sec=ns // 10**9, nanosec=ns % 10**9), frame_id=frame)

    plugin = StoragePlugin.MCAP if storage == "mcap" else StoragePlugin.SQLITE3
    msgs = []
    for topic, t_ns, stamp, jn, q, qd, tau in joints:
        q, qd, tau = (np.asarray(a, dtype=float) for a in (q, qd, tau))
        m = store.types[JS](header=header(stamp), name=list(jn), position=q, velocity=qd,
                            effort=tau)  # fmt: skip
        msgs.append((t_ns, topic, JS, store.serialize_cdr(m, JS)))
    for topic, t_ns, stamp, frame, wr in wrenches:
        m = store.types[WS](header=header(stamp, frame),
                            wrench=W(force=V3(*wr[:3]), torque=V3(*wr[3:])))  # fmt: skip
        msgs.append((t_ns, topic, WS, store.serialize_cdr(m, WS)))
    with Writer(path, version=9, storage_plugin=plugin) as w:
        conns = {(topic, kind): w.add_connection(topic, kind, typestore=store)
                 for topic, kind in sorted({(m[1], m[2]) for m in msgs})}  # fmt: skip
        for t_ns, topic, kind, raw in sorted(msgs, key=lambda m: m[0]):
            w.write(conns[topic, kind], t_ns, raw)
    return path


def _joint_msgs(names, times, stamped=True, topic="/joint_states", effort=False):
    out = []
    for t in times:
        ns = T0_NS + round(t * 1e9)
        q = Q0 + t * RATE_Q
        out.append((topic, ns, ns if stamped else 0, names, q, RATE_Q, q * 2 if effort else []))
        out.append((topic, ns, ns if stamped else 0, ["finger"], [0.01], [], []))  # skipped
    return out


def _wrench_msgs(times, frame="ft_sensor", topic="/ft/wrench", stamped=True, latency_ns=0):
    ns = [T0_NS + round(t * 1e9) for t in times]
    return [(topic, n + latency_ns, n if stamped else 0, frame, [float(i), 1.0, 2.0, 0.1, 0.2, t])
            for i, (n, t) in enumerate(zip(ns, times))]  # fmt: skip


@pytest.mark.parametrize("storage", ["sqlite3", "mcap"])
def test_joints_are_interpolated_to_the_wrench_times(names, tmp_path, storage):
    """Joint states at 100 Hz with a 0.2 s outage, the wrench at 500 Hz starting before and
    ending after them: the samples outside and in the outage are left out, the positions
    (linear in time) are exact at the others."""
    t_j = np.array([t for t in np.arange(0.0, 1.0001, 0.01) if not 0.405 < t < 0.595])
    t_w = np.arange(-0.049, 1.05, 0.002)  # odd milliseconds: never on a joint state
    bag = _write(tmp_path / "bag", _joint_msgs(names, t_j), _wrench_msgs(t_w), storage)
    log = read_wrench_bag(bag, names)
    inside = (t_w > 0) & (t_w < 1.0) & ~((t_w > 0.40) & (t_w < 0.60))
    expected_t = t_w[inside]
    assert len(log.time) == inside.sum()
    np.testing.assert_allclose(log.time, expected_t - expected_t[0], atol=1e-9)
    np.testing.assert_allclose(log.wrench[:, 5], expected_t, atol=1e-12)  # samples kept whole
    np.testing.assert_allclose(log.position, Q0 + expected_t[:, None] * RATE_Q, atol=1e-9)
    np.testing.assert_allclose(log.velocity, np.tile(RATE_Q, (len(expected_t), 1)))
    assert log.effort is None and log.sensor_frame == "ft_sensor"


def test_zero_stamps_use_the_receive_times_for_both_topics(names, tmp_path):
    """The wrench unstamped, received 3 ms late: both topics on the receive clock."""
    t_j = np.arange(0.0, 0.5, 0.01)
    late = _wrench_msgs(np.arange(0.1, 0.4, 0.004), stamped=False, latency_ns=3_000_000)
    bag = _write(tmp_path / "bag", _joint_msgs(names, t_j, effort=True), late)
    log = read_wrench_bag(bag, names)
    t_received = np.arange(0.1, 0.4, 0.004) + 0.003
    np.testing.assert_allclose(log.position, Q0 + t_received[:, None] * RATE_Q, atol=1e-9)
    np.testing.assert_allclose(log.effort, 2 * log.position, atol=1e-9)


def test_two_wrench_topics_need_a_name(names, tmp_path):
    t = np.arange(0.0, 0.3, 0.01)
    two = _wrench_msgs(t, topic="/left/wrench") + _wrench_msgs(t, topic="/right/wrench")
    bag = _write(tmp_path / "bag", _joint_msgs(names, t), two)
    with pytest.raises(LogError, match=r"2 geometry_msgs/msg/WrenchStamped topics.*'/left/wrench'"
                                       r".*'/right/wrench'.*wrench-topic"):  # fmt: skip
        read_wrench_bag(bag, names)
    assert len(read_wrench_log(bag, names, wrench_topic="/right/wrench").time) == len(t)
    with pytest.raises(LogError, match="no topic '/wrench'"):
        read_wrench_bag(bag, names, wrench_topic="/wrench")


def test_a_bag_without_wrench_is_refused(names, tmp_path):
    bag = _write(tmp_path / "bag", _joint_msgs(names, np.arange(0.0, 0.1, 0.01)), [])
    with pytest.raises(LogError, match="no geometry_msgs/msg/WrenchStamped topic.*joint_states"):
        read_wrench_bag(bag, names)


def test_frame_ids_must_agree_and_name_a_frame(names, tmp_path):
    t = np.arange(0.0, 0.3, 0.01)
    joints = _joint_msgs(names, t)
    mixed = _wrench_msgs(t[:10], frame="ft_sensor") + _wrench_msgs(t[10:], frame="tool0")
    with pytest.raises(LogError, match=r"2 frames \['ft_sensor', 'tool0'\]"):
        read_wrench_bag(_write(tmp_path / "a", joints, mixed), names)
    empty = _write(tmp_path / "b", joints, _wrench_msgs(t, frame=""))
    with pytest.raises(LogError, match="empty frame_id.*sensor-frame"):
        read_wrench_bag(empty, names)
    assert read_wrench_bag(empty, names, sensor_frame="tool0").sensor_frame == "tool0"
    named = _write(tmp_path / "c", joints, _wrench_msgs(t, frame="ft_sensor"))
    with pytest.raises(LogError, match="in frame 'ft_sensor'.*not 'tool0'"):
        read_wrench_bag(named, names, sensor_frame="tool0")


def test_wrench_outside_the_joint_states_is_refused(names, tmp_path):
    joints = _joint_msgs(names, np.arange(0.0, 1.0, 0.01))
    after = _write(tmp_path / "a", joints, _wrench_msgs(np.arange(1.5, 2.0, 0.01)))
    with pytest.raises(LogError, match="no wrench sample lies within the joint states' span"):
        read_wrench_bag(after, names)
    outage = [m for m in joints if not 0.2 < (m[1] - T0_NS) * 1e-9 < 0.2 + 2 * MAX_JOINT_GAP_S]
    inside = _write(tmp_path / "b", outage, _wrench_msgs(np.arange(0.25, 0.35, 0.002)))
    with pytest.raises(LogError, match="joint-state gap 0.2"):
        read_wrench_bag(inside, names)


def test_missing_arm_joint_is_named(names, tmp_path):
    t = np.arange(0.0, 0.3, 0.01)
    bag = _write(tmp_path / "bag", _joint_msgs(names, t), _wrench_msgs(t))
    with pytest.raises(LogError, match="wrist_9"):
        read_wrench_bag(bag, [*names[:-1], "wrist_9"])


# --- CSV refusals ---------------------------------------------------------------------------


def _csv(path, header, rows):
    path.write_text(",".join(header) + "\n" + "".join(",".join(r) + "\n" for r in rows))
    return path


def test_csv_missing_columns_are_named(names, tmp_path):
    header = ["time", *(f"{n}.position" for n in names), "force_x", "force_y", "torque_x",
              "torque_y", "torque_z"]  # fmt: skip
    path = _csv(tmp_path / "a.csv", header, [["0"] * len(header)] * 3)
    with pytest.raises(LogError, match=r"lacks the columns \['force_z'\].*'J.position'"):
        read_wrench_csv(path, names, "tool0")
    with pytest.raises(LogError, match=r"lacks the columns \['wrist_9.position', 'force_z'\]"):
        read_wrench_csv(path, [*names[:-1], "wrist_9"], "tool0")


def test_csv_nan_and_bad_values_are_refused(names, tmp_path):
    path = write_wrench_csv(tmp_path / "w.csv", _log(names, velocity=False, effort=False))
    lines = path.read_text().splitlines()
    cells = lines[4].split(",")
    cells[-4] = "nan"  # force_z on line 5
    path.write_text("\n".join([*lines[:4], ",".join(cells), *lines[5:]]) + "\n")
    with pytest.raises(LogError, match=r"NaN or inf values \(1\), first on line 5 in 'force_z'"):
        read_wrench_csv(path, names, "tool0")
    cells[-4] = "heavy"
    path.write_text("\n".join([*lines[:4], ",".join(cells), *lines[5:]]) + "\n")
    with pytest.raises(LogError, match="not a number"):
        read_wrench_csv(path, names, "tool0")
    path.write_text("\n".join(lines[:2]) + "\n")
    with pytest.raises(LogError, match="1 usable sample"):
        read_wrench_csv(path, names, "tool0")


def test_a_ur_recording_is_not_read_as_the_project_csv(names, tmp_path):
    header = ["timestamp", *(f"actual_q_{i}" for i in range(6))]
    path = _csv(tmp_path / "ur.csv", header, [["0"] * 7] * 3)
    with pytest.raises(LogError, match="UR recording.*read_rtde_wrench"):
        read_wrench_csv(path, names, "tool0")
    with pytest.raises(LogError, match="needs the robot model"):
        read_wrench_log(path, names, sensor_frame="tool0")


# --- UR recordings: actual_TCP_force (base axes, about the TCP) into the sensor frame -------


MASS, COM_S = 1.3, np.array([0.02, -0.03, 0.11])  # kg; m, in the sensor frame


def _recording(robot, Q, g_base, tcp, base, path, sep=" "):
    """A UR recording of a payload (MASS at COM_S in the sensor frame gripper_base) held at
    ``Q``: its weight's wrench about ``tcp``'s origin in ``base``'s axes (the law, here)."""
    rows = []
    for i, q in enumerate(Q):
        T_w_b, T_w_s, T_w_p = (robot.frame_pose(q, f) for f in (base, "gripper_base", tcp))
        R_w_b = T_w_b[:3, :3]
        F_w = MASS * (R_w_b @ g_base)
        p_c = T_w_s[:3, :3] @ COM_S + T_w_s[:3, 3]
        tau_w = np.cross(p_c - T_w_p[:3, 3], F_w)
        w_base = np.r_[R_w_b.T @ F_w, R_w_b.T @ tau_w]
        rows.append([12345.6 + 0.002 * i, *q, *(0.1 * q), *np.full(6, 0.7), *w_base])
    vectors = ("actual_q", "actual_qd", "actual_current", "actual_TCP_force")
    header = ["timestamp", *(f"{v}_{i}" for v in vectors for i in range(6))]
    np.savetxt(path, rows, delimiter=sep, header=sep.join(header), comments="", fmt="%.17g")
    return path


def _expected(robot, Q, g_base, base):
    """m g and c x m g in the sensor frame, gravity rotated from the base by the poses."""
    F = np.array([robot.frame_pose(q, "gripper_base")[:3, :3].T
                  @ robot.frame_pose(q, base)[:3, :3] @ (MASS * g_base) for q in Q])  # fmt: skip
    return np.c_[F, np.cross(COM_S, F)]


@pytest.fixture(scope="module")
def poses(ur5):
    return np.array([ur5.random_configuration(np.random.default_rng(s)) for s in range(12)])


@pytest.mark.parametrize("tcp", [None, "eelink"])
def test_rtde_wrench_is_the_payload_in_the_sensor_frame(ur5, poses, tmp_path, tcp):
    """Floor mounted, the torques about the flange (e-Series) or a TCP 13 cm out (CB3)."""
    g = np.array([0.0, 0.0, -9.81])
    path = _recording(ur5, poses, g, tcp or "tool0", "base_link", tmp_path / "rec.txt")
    log = read_rtde_wrench(path, ur5, "gripper_base", tcp_frame=tcp)
    np.testing.assert_allclose(log.wrench, _expected(ur5, poses, g, "base_link"), atol=1e-9)
    np.testing.assert_allclose(log.position, poses, atol=1e-12)
    np.testing.assert_allclose(log.velocity, 0.1 * poses, atol=1e-12)
    np.testing.assert_allclose(log.time, 0.002 * np.arange(len(poses)), atol=1e-9)
    assert log.effort is None and log.sensor_frame == "gripper_base"
    assert np.allclose(np.linalg.norm(log.wrench[:, :3], axis=1), MASS * 9.81)


def test_rtde_wrench_on_a_wall_through_read_wrench_log(poses, tmp_path):
    """A wall-mounted arm (gravity along base -x): the base axes are the URDF root's, not the
    model's turned world; a ur_rtde CSV (comma-separated) found by its header."""
    g = np.array([-9.81, 0.0, 0.0])
    wall = load_robot(urdf_path(), "eelink", [example_robot_data_dir().parent], g)
    R_world_root = wall.frame_pose(poses[0], "world")[:3, :3]
    np.testing.assert_allclose(R_world_root @ g, wall.model.gravity.linear, atol=1e-12)
    path = _recording(wall, poses, g, "tool0", "world", tmp_path / "rec.csv", sep=",")
    log = read_wrench_log(path, wall, sensor_frame="gripper_base")
    np.testing.assert_allclose(log.wrench, _expected(wall, poses, g, "world"), atol=1e-9)


def test_rtde_base_is_ur_descriptions_base_frame_where_the_urdf_has_it(poses, tmp_path):
    """ur_description's ``base`` is ``base_link`` turned 180 deg about z: the controller's
    base axes; taking base_link instead would flip the horizontal forces."""
    text = urdf_path().read_text().replace("</robot>", (
        '<link name="base"/><joint name="base_link-base_fixed_joint" type="fixed"><parent '
        'link="base_link"/><child link="base"/><origin xyz="0 0 0" rpy="0 0 3.14159265359"/>'
        "</joint></robot>"))  # fmt: skip
    (tmp_path / "ur5_base.urdf").write_text(text)
    robot = load_robot(tmp_path / "ur5_base.urdf", "eelink", [example_robot_data_dir().parent])
    g = np.array([0.0, 0.0, -9.81])
    path = _recording(robot, poses, g, "tool0", "base", tmp_path / "rec.txt")
    expected = _expected(robot, poses, g, "base")
    np.testing.assert_allclose(read_rtde_wrench(path, robot, "gripper_base").wrench, expected,
                               atol=1e-9)  # fmt: skip
    wrong = read_rtde_wrench(path, robot, "gripper_base", base_frame="base_link").wrench
    assert np.abs(wrong - expected).max() > 1.0


def test_rtde_refusals(ur5, poses, tmp_path):
    g = np.array([0.0, 0.0, -9.81])
    path = _recording(ur5, poses, g, "tool0", "base_link", tmp_path / "rec.txt")
    with pytest.raises(InvalidInputError, match="tcp_frame .*'tcp'.*not a frame.*'tool0'"):
        read_rtde_wrench(path, ur5, "gripper_base", tcp_frame="tcp")
    with pytest.raises(InvalidInputError, match="sensor frame must be named"):
        read_rtde_wrench(path, ur5, "")
    lines = path.read_text().splitlines()
    cut = " ".join(lines[0].split()[:-6])
    (tmp_path / "no_force.txt").write_text(
        "\n".join([cut, *(" ".join(r.split()[:-6]) for r in lines[1:])]) + "\n"
    )
    with pytest.raises(LogError, match="no actual_TCP_force_0..actual_TCP_force_5"):
        read_rtde_wrench(tmp_path / "no_force.txt", ur5, "gripper_base")
    cells = lines[3].split()
    cells[-1] = "nan"
    (tmp_path / "nan.txt").write_text("\n".join([*lines[:3], " ".join(cells), *lines[4:]]))
    with pytest.raises(LogError, match="first on line 4 in 'actual_TCP_force_5'"):
        read_rtde_wrench(tmp_path / "nan.txt", ur5, "gripper_base")
