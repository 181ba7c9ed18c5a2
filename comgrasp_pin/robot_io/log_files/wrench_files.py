"""A wrist sensor's wrench from a ROS 2 bag or a wide CSV (``record`` writes both).

ROS 2 bags (``read_wrench_bag``): WrenchStamped messages, joints from JointState.

- The wrench: ``geometry_msgs/msg/WrenchStamped`` on one topic, found by its type where the
  bag has exactly one such topic (else it must be named). The messages' ``header.frame_id``
  is the sensor frame; all of them must name the same one. The force (N) and torque (N m)
  are taken as the wrench the tool side applies to the sensor (``wrench_log``: a hanging
  mass reads its weight), as ATI's and Robotiq's sensors report it; ROS does not fix the
  sign of a WrenchStamped, and a driver that publishes the opposite shows as a negative
  mass.
- The joints: ``sensor_msgs/msg/JointState`` (``logs``: matched by name, messages lacking an
  arm joint skipped), positions and, where every message has them, velocities and efforts.
- Times: header stamps, or the bag's receive times where any stamp of the two topics is zero
  (one clock for both). The wrench's samples are the log's times, seconds from the first
  one kept; the joint readings are interpolated to them (linear).
- A wrench sample is kept where joint states bracket it within ``MAX_JOINT_GAP_S``: samples
  before the first or after the last joint state (a sensor's topic often starts or ends
  a little apart from the arm's), or in a gap of the joint states, are left out.

The CSV (``read_wrench_csv``; ``record.write_wrench_csv`` writes it): a header row with
``time`` (s), ``J.position`` (rad or m) per arm joint J, and ``force_x, force_y, force_z`` (N),
``torque_x, torque_y, torque_z`` (N m): the wrench the tool side applies to the sensor
(``log_types.WrenchLog``), in the sensor frame, which the file does not name (the caller
does). ``J.velocity`` (rad/s) and ``J.effort`` (N m) are read where every arm joint has them.
Other columns are ignored.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from comgrasp_pin import file_checks
from comgrasp_pin.errors import LogError
from comgrasp_pin.robot_io.log_files import joint_readers as logs
from comgrasp_pin.robot_io.log_files import rtde
from comgrasp_pin.robot_io.log_files.log_types import (
    WRENCH_COLUMNS,
    WrenchLog,
    assemble_wrench_log,
    sensor_frame_name,
)
from comgrasp_pin.robot_io.log_files.log_values import check_joint_rows, check_messages, check_table

WRENCH_STAMPED = "geometry_msgs/msg/WrenchStamped"
OPTIONAL_FIELDS = ("velocity", "effort")
"""Per-joint CSV fields read where every arm joint has them (rad/s, N m)."""
MAX_JOINT_GAP_S = 0.1
"""Longest time between two joint states that a wrench sample is interpolated across (s).

Linear interpolation across a gap h errs by at most qdd_max h^2 / 8: 3.8 mrad (0.2 deg) for
h = 0.1 s at 3 rad/s^2, a tilt of the sensor that moves 0.4 % of the weight into its
other axes (4 mN for 100 g), below a strain-gauge sensor's resolution (~0.1 N). Drivers
publish joint states at 100-1000 Hz, so 0.1 s is 10 or more lost messages: an outage, not
jitter."""


def read_wrench_bag(
    path: str | Path,
    joint_names: list[str] | tuple[str, ...],
    wrench_topic: str | None = None,
    joint_topic: str = logs.DEFAULT_TOPIC,
    sensor_frame: str | None = None,
) -> WrenchLog:
    """Read a bag's WrenchStamped topic with the arm's joint positions at its times.

    Args:
        path: the bag's folder, its .db3 / .mcap file, or a ROS 1 .bag file.
        joint_names: the arm's joints (JointState names).
        wrench_topic: the WrenchStamped topic; None: the bag's only one.
        joint_topic: the JointState topic.
        sensor_frame: None: the messages' frame_id. Named: where the frame_id is empty (a
            driver that leaves it out), the frame the wrench is in; where it is set, it
            must be the same.

    Raises:
        LogError: the bag cannot be opened or fails ``file_checks.ros_bag``; no
            WrenchStamped topic, or several and none named (listed); no such topic or
            another type; no JointState message holds all the joints; the messages name
            different frames, an empty one (and ``sensor_frame`` is None), or another one
            than ``sensor_frame``; a value that is NaN, inf or past any sensor's range
            (``log_values``: its message's time, topic and field named); fewer than two
            joint states, or no wrench sample within the joint states' span and gaps.
    """
    from rosbags.highlevel import AnyReader

    bag = file_checks.ros_bag(path, LogError)
    names = tuple(joint_names)
    try:
        with AnyReader([bag]) as reader:
            w_conns = _wrench_connections(reader, wrench_topic, bag)
            j_conns = logs.topic_connections(reader, joint_topic, logs.JOINT_STATE, bag)
            wrenches = [_wrench_row(reader.deserialize(raw, c.msgtype), t)
                        for c, t, raw in reader.messages(connections=w_conns)]  # fmt: skip
            joints = logs.joint_rows(reader, j_conns, names, need_effort=False)
            check_joint_rows(joints, names, joint_topic, f"bag {bag}")
            _check_wrenches(wrenches, w_conns[0].topic, f"bag {bag}")
    except LogError:
        raise
    except Exception as exc:  # rosbags raises its own error types for broken bags
        raise LogError(f"cannot read the bag {bag}: {type(exc).__name__}: {exc}") from None
    if not wrenches:
        raise LogError(f"bag {bag}: the WrenchStamped topic has no messages")
    frame = _sensor_frame({r[2] for r in wrenches}, sensor_frame, bag)
    return _on_wrench_times(wrenches, joints, names, frame, str(bag))


def _wrench_connections(reader, topic: str | None, bag: Path) -> list:
    """The connections of the wrench topic: ``topic``, or the bag's only WrenchStamped one."""
    if topic is None:
        found = sorted({c.topic for c in reader.connections if c.msgtype == WRENCH_STAMPED})
        if len(found) != 1:
            topics = sorted({f"{c.topic} ({c.msgtype})" for c in reader.connections})
            raise LogError(
                f"bag {bag} has {len(found)} {WRENCH_STAMPED} topics {found}: name the "
                f"sensor's (wrench_topic=..., --wrench-topic); its topics are {topics}"
                if found
                else f"bag {bag} has no {WRENCH_STAMPED} topic; its topics are {topics}"
            )
        topic = found[0]
    return logs.topic_connections(reader, topic, WRENCH_STAMPED, bag)


def _wrench_row(msg, t_bag: int) -> tuple[int, int, str, np.ndarray]:
    """(stamp (ns), receive time (ns), frame_id, (6,) force and torque) of a WrenchStamped."""
    stamp = int(msg.header.stamp.sec) * 10**9 + int(msg.header.stamp.nanosec)
    f, tau = msg.wrench.force, msg.wrench.torque
    return (
        stamp,
        int(t_bag),
        str(msg.header.frame_id),
        np.array([f.x, f.y, f.z, tau.x, tau.y, tau.z]),
    )


def _check_wrenches(rows: list[tuple], topic: str, source: str) -> None:
    """``log_values.check_messages`` on ``_wrench_row``s: forces (N) and torques (N m)."""
    stamps = np.array([r[0] for r in rows], dtype=np.int64)
    times = stamps if np.all(stamps > 0) else np.array([r[1] for r in rows], dtype=np.int64)
    kinds = ["force"] * 3 + ["torque"] * 3
    check_messages(np.array([r[3] for r in rows]), kinds, list(WRENCH_COLUMNS), times, topic,
                   source)  # fmt: skip


def _sensor_frame(frames: set[str], named: str | None, bag: Path) -> str:
    """The one frame the wrench messages are in (see ``read_wrench_bag``'s sensor_frame)."""
    if len(frames) > 1:
        raise LogError(
            f"the WrenchStamped messages of bag {bag} are in {len(frames)} frames "
            f"{sorted(frames)}: one sensor's messages name one frame (frame_id); a log "
            "must hold one sensor's readings in one frame"
        )
    (frame,) = frames
    if named is not None:
        named = sensor_frame_name(named)
        if frame not in ("", named):
            raise LogError(
                f"the WrenchStamped messages of bag {bag} are in frame {frame!r} (their "
                f"frame_id), not {named!r}: leave the sensor frame out to use theirs"
            )
        return named
    if not frame:
        raise LogError(
            f"the WrenchStamped messages of bag {bag} have an empty frame_id: name the frame "
            "they are measured in (sensor_frame=..., --sensor-frame), a frame of the URDF"
        )
    return frame


def _on_wrench_times(wrenches: list, joints: list, names: tuple[str, ...], frame: str,
                     source: str) -> WrenchLog:  # fmt: skip
    """The WrenchLog of wrench rows and joint rows (``logs.joint_rows``), on one clock."""
    if len(joints) < 2:
        raise LogError(f"{source} has {len(joints)} joint state(s) with all the arm's joints; "
                       "interpolating them to the wrench's times needs at least two")  # fmt: skip
    stamped = all(r[0] > 0 for r in wrenches) and all(r[0] > 0 for r in joints)
    k = 0 if stamped else 1  # header stamps, or receive times for both topics
    w_ns = np.array([r[k] for r in wrenches], dtype=np.int64)
    j_ns = np.array([r[k] for r in joints], dtype=np.int64)
    t0 = min(w_ns.min(), j_ns.min())  # integer ns: float seconds since 1970 keep only 0.2 us
    order = np.argsort(j_ns, kind="stable")
    t_j = (j_ns[order] - t0) * 1e-9
    t_w = (w_ns - t0) * 1e-9
    keep = _bracketed(t_w, t_j)
    if not np.any(keep):
        raise LogError(
            f"{source}: no wrench sample lies within the joint states' span and within "
            f"{MAX_JOINT_GAP_S} s of joint states on both sides (wrench {t_w.min():.3f} to "
            f"{t_w.max():.3f} s, joint states {t_j[0]:.3f} to {t_j[-1]:.3f} s, from the first "
            f"of both; the longest joint-state gap {np.diff(t_j).max():.3f} s)"
        )
    t = t_w[keep]
    columns = {}
    for field, at in (("position", 2), ("effort", 3), ("velocity", 4)):
        if all(r[at] is not None for r in joints):
            values = np.array([joints[i][at] for i in order], dtype=float)
            columns[field] = np.column_stack([np.interp(t, t_j, v) for v in values.T])
    wrench = np.array([r[3] for r in wrenches])[keep]
    return assemble_wrench_log(t, columns["position"], wrench, names, frame, source,
                               columns.get("velocity"), columns.get("effort"))  # fmt: skip


def _bracketed(t_w: np.ndarray, t_j: np.ndarray) -> np.ndarray:
    """(N,) bool: the times ``t_w`` within the sorted ``t_j``, in gaps of MAX_JOINT_GAP_S."""
    hi = np.clip(np.searchsorted(t_j, t_w, side="left"), 1, len(t_j) - 1)
    gap = t_j[hi] - t_j[hi - 1]
    return (t_w >= t_j[0]) & (t_w <= t_j[-1]) & (gap <= MAX_JOINT_GAP_S)


def read_wrench_csv(
    path: str | Path, joint_names: list[str] | tuple[str, ...], sensor_frame: str
) -> WrenchLog:
    """Read a wide CSV of joint positions and a wrench measured in ``sensor_frame``.

    Args:
        path: the CSV (comma-separated, a header row; see the module docstring).
        joint_names: the arm's joints, as the ``J`` of the ``J.position`` columns.
        sensor_frame: the URDF frame the ``force_*``, ``torque_*`` columns are in.

    Raises:
        InvalidInputError: no sensor frame named.
        LogError: the file fails ``file_checks.first_line`` (missing, a FIFO, larger than
            ``file_checks.MAX_CSV_BYTES``, not UTF-8); it is a UR recording (read by
            ``wrench_sources.read_rtde_wrench``, which needs the robot); a column is missing
            (named, with what a wrench log needs); a value is not a number, NaN, inf or past
            any sensor's range (``log_values.check_table``: its line and column named);
            fewer than two rows.
    """
    path = Path(path)
    frame = sensor_frame_name(sensor_frame)
    line = file_checks.first_line(path, "CSV wrench log", file_checks.MAX_CSV_BYTES,
                                  file_checks.MAX_CSV_HEADER_BYTES, LogError)  # fmt: skip
    if rtde.is_rtde_header(line):
        raise LogError(
            f"{path} is a UR recording (timestamp, actual_q_0, ...): its actual_TCP_force is "
            "at the TCP in base axes; read it with read_rtde_wrench (or read_wrench_log with "
            "the robot model), which moves it into the sensor frame by the URDF's kinematics"
        )
    header = rtde.header_columns(line)
    names = tuple(joint_names)
    wanted = ["time", *(f"{n}.position" for n in names), *WRENCH_COLUMNS]
    missing = [w for w in wanted if w not in header]
    if missing:
        raise LogError(
            f"CSV {path} lacks the columns {missing}; a wrench log needs 'time' (s), "
            f"'J.position' per arm joint J of the URDF ({list(names)}) and "
            f"{list(WRENCH_COLUMNS)} (N, N m, in the sensor frame); 'J.velocity' and "
            "'J.effort' are read where every joint has them"
        )
    fields = [f for f in OPTIONAL_FIELDS if all(f"{n}.{f}" in header for n in names)]
    wanted += [f"{n}.{f}" for f in fields for n in names]
    data = rtde.load_columns(path, ",", [header.index(w) for w in wanted], "CSV wrench log")
    check_table(data, wanted, path, f"CSV {path}")
    n = len(names)
    extra = {f: data[:, 7 + n * (i + 1) : 7 + n * (i + 2)] for i, f in enumerate(fields)}
    q, wrench = data[:, 1 : 1 + n], data[:, 1 + n : 7 + n]
    return assemble_wrench_log(data[:, 0], q, wrench, names, frame, str(path),
                               extra.get("velocity"), extra.get("effort"))  # fmt: skip
