"""robot_io.log_files.joint_readers / record / windows: real bags (rosbags, sqlite3 and mcap), CSV,
windows."""

import numpy as np
import pytest
from _logs import rnea_torques, session
from _payload import panda

from comgrasp_pin.errors import InvalidInputError, LogError, NotStaticError
from comgrasp_pin.robot_io import JointLog, read_log, write_bag, write_csv
from comgrasp_pin.robot_io.at_rest import (
    find_static_windows,
    pair_by_configuration,
    parse_windows,
    read_window,
)
from comgrasp_pin.robot_io.at_rest.windows import joint_speed
from comgrasp_pin.robot_io.log_files import read_bag, read_csv

Q3 = np.array(
    [
        [0.0, -0.3, 0.0, -2.2, 0.0, 2.0, 0.8],
        [0.5, -0.6, 0.3, -1.8, 1.2, 1.2, -0.6],
        [-0.4, 0.2, -0.2, -2.4, -1.0, 2.6, 1.5],
    ]
)


@pytest.fixture(scope="module")
def robot():
    return panda()


@pytest.fixture(scope="module")
def synthetic(robot):
    return session(Q3, rnea_torques(robot, 0.8, np.array([0.02, -0.01, 0.05])), robot.joint_names)


@pytest.mark.parametrize("storage", ["sqlite3", "mcap"])
def test_bag_round_trip_keeps_every_sample(robot, synthetic, tmp_path, storage):
    log = synthetic[0]
    path = write_bag(log, tmp_path / "bag", storage, extra_joints={"panda_finger_joint1": 0.04})
    back = read_bag(path, robot.joint_names)
    assert back.joint_names == tuple(robot.joint_names)
    np.testing.assert_array_equal(back.position, log.position)
    np.testing.assert_array_equal(back.effort, log.effort)
    np.testing.assert_allclose(back.time, log.time, atol=1e-6)  # ns stamps


def test_bag_other_topics_and_joint_order_are_handled(robot, synthetic, tmp_path):
    """Joints in another order than the URDF's, and a second JointState topic: matched by name."""
    from rosbags.rosbag2 import Writer
    from rosbags.typesys import Stores, get_typestore

    log = synthetic[0]
    store = get_typestore(Stores.ROS2_HUMBLE)
    JS, H, T = (store.types[t] for t in ("sensor_msgs/msg/JointState", "std_msgs/msg/Header",
                                         "builtin_interfaces/msg/Time"))  # fmt: skip
    order = np.arange(robot.nq)[::-1]
    names = [robot.joint_names[i] for i in order]
    with Writer(tmp_path / "bag", version=9) as w:
        arm = w.add_connection("/joint_states", JS.__msgtype__, typestore=store)
        other = w.add_connection("/gripper/joint_states", JS.__msgtype__, typestore=store)
        for i in range(50):
            ns = 10**9 + i * 5_000_000
            hdr = H(stamp=T(sec=ns // 10**9, nanosec=ns % 10**9), frame_id="")
            msg = JS(header=hdr, name=names, position=log.position[i, order],
                     velocity=np.empty(0), effort=log.effort[i, order])  # fmt: skip
            w.write(arm, ns, store.serialize_cdr(msg, JS.__msgtype__))
            finger = JS(header=hdr, name=["finger"], position=np.ones(1), velocity=np.empty(0),
                        effort=np.zeros(1))  # fmt: skip
            w.write(other, ns, store.serialize_cdr(finger, JS.__msgtype__))
    back = read_log(tmp_path / "bag", robot.joint_names)
    np.testing.assert_array_equal(back.effort, log.effort[:50])
    np.testing.assert_allclose(back.time, np.arange(50) * 0.005, atol=1e-9)


def test_csv_round_trip(robot, synthetic, tmp_path):
    log = synthetic[0]
    back = read_csv(write_csv(log, tmp_path / "log.csv"), robot.joint_names)
    np.testing.assert_allclose(back.effort, log.effort, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(back.time, log.time, atol=1e-9)


def _with_velocity(log):
    """The log with velocities: the positions' central differences (any known array)."""
    from dataclasses import replace

    return replace(log, velocity=np.gradient(log.position, log.time, axis=0))


@pytest.mark.parametrize("storage", ["sqlite3", "mcap", "csv"])
def test_velocities_round_trip_and_are_none_when_absent(robot, synthetic, tmp_path, storage):
    log = _with_velocity(synthetic[0])
    if storage == "csv":
        back = read_csv(write_csv(log, tmp_path / "log.csv"), robot.joint_names)
        bare = read_csv(write_csv(synthetic[0], tmp_path / "bare.csv"), robot.joint_names)
    else:
        extra = {"panda_finger_joint1": 0.04}
        back = read_bag(
            write_bag(log, tmp_path / "b", storage, extra_joints=extra), robot.joint_names
        )
        bare = read_bag(write_bag(synthetic[0], tmp_path / "c", storage), robot.joint_names)
    np.testing.assert_allclose(back.velocity, log.velocity, rtol=1e-9, atol=1e-12)
    assert back.velocity.shape == back.position.shape
    assert bare.velocity is None


def test_csv_missing_column_is_named(robot, tmp_path):
    path = tmp_path / "log.csv"
    header = ["time"] + [f"{n}.position" for n in robot.joint_names]
    path.write_text(",".join(header) + "\n" + ",".join(["0"] * len(header)) + "\n")
    with pytest.raises(LogError, match=r"panda_joint1\.effort"):
        read_csv(path, robot.joint_names)


def test_bag_without_efforts_is_refused(robot, synthetic, tmp_path):
    log = synthetic[0]
    empty = JointLog(log.time[:20], log.joint_names, log.position[:20], np.empty((20, 0)))
    from comgrasp_pin.robot_io.log_files import record

    # write_bag concatenates efforts: give a log whose effort field is empty
    path = record.write_bag(empty, tmp_path / "bag")
    with pytest.raises(LogError, match="no joint efforts"):
        read_bag(path, robot.joint_names)


def test_bag_missing_joint_is_named(robot, synthetic, tmp_path):
    path = write_bag(synthetic[0], tmp_path / "bag")
    with pytest.raises(LogError, match="wrist_9"):
        read_bag(path, [*robot.joint_names[:-1], "wrist_9"])


def test_parse_windows():
    assert parse_windows("1:2, 3.5:4") == [(1.0, 2.0), (3.5, 4.0)]
    for bad in ("1-2", "2:1", "a:b", "1:2:3"):
        with pytest.raises(InvalidInputError):
            parse_windows(bad)


def test_window_mean_and_spread(synthetic):
    log, before, _, _ = synthetic
    r = read_window(log, *before[0])
    sel = (log.time >= before[0][0]) & (log.time <= before[0][1])
    np.testing.assert_allclose(r.tau, log.effort[sel].mean(axis=0))
    assert r.n_samples == sel.sum() == 201  # 1 s at 200 Hz, both ends included
    np.testing.assert_allclose(r.tau_std, 0.05, rtol=0.2)  # the injected per-sample noise
    np.testing.assert_allclose(r.tau_mean_std, r.tau_std / np.sqrt(201))


def test_window_during_motion_is_not_static(synthetic):
    log, before, _, _ = synthetic
    with pytest.raises(NotStaticError, match="not static"):
        read_window(log, before[0][1] + 0.3, before[1][0])  # spans the move to pose 1


def test_window_outside_the_log(synthetic):
    log = synthetic[0]
    with pytest.raises(LogError, match="outside the log"):
        read_window(log, log.duration + 1, log.duration + 2)


def test_joint_speed_of_a_ramp():
    t = np.arange(0, 2, 0.002)
    q = np.column_stack([0.3 * t, np.zeros_like(t)])
    np.testing.assert_allclose(joint_speed(t, q), 0.3, rtol=1e-6)


def test_auto_windows_pair_the_same_poses(synthetic):
    log, before, after, grasp = synthetic
    windows = find_static_windows(log)
    assert len(windows) >= 2 * len(Q3)
    b, a = pair_by_configuration(log, grasp)
    assert len(b) == len(a) == len(Q3)
    for (wb, wa), tb, ta in zip(zip(b, a), before, after):
        assert wb[0] <= tb[0] + 0.2 and wb[1] >= tb[1] - 0.2  # covers the hold
        assert wa[0] <= ta[0] + 0.2 and wa[1] >= ta[1] - 0.2


@pytest.mark.parametrize("storage", ["sqlite3", "mcap"])
def test_reading_only_near_the_windows_gives_the_same_windows(robot, synthetic, tmp_path, storage):
    log, before, after, _ = synthetic
    path = write_bag(log, tmp_path / "bag", storage)
    full = read_bag(path, robot.joint_names)
    part = read_bag(path, robot.joint_names, windows=before[:1] + after[:1])
    assert len(part.time) < len(full.time) / 2
    assert part.duration == pytest.approx(full.duration)  # the last message is kept
    for w in (before[0], after[0]):
        a, b = read_window(full, *w), read_window(part, *w)
        np.testing.assert_array_equal(a.tau, b.tau)
        assert a.n_samples == b.n_samples
    with pytest.raises(LogError, match="outside the log"):
        read_window(part, full.duration + 1, full.duration + 2)
