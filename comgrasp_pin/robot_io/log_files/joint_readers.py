"""Robot logs in: joint positions and efforts from a ROS 2 bag or a wide CSV, as a JointLog.

- ROS 2 bag (sqlite3 or mcap storage, read by ``rosbags``): ``sensor_msgs/msg/JointState``
  messages (their velocities too, where every message carries them) on one topic (default
  ``/joint_states``). Joints are matched by name; messages
  that lack one of the wanted joints (a gripper publishing its own JointState on the same
  topic) are skipped, other joints (fingers) ignored. A message's time is its header stamp,
  or the bag's receive time where the stamps are zero.
- CSV: a header row with ``time`` (s) and, per joint J, ``J.position`` (rad or m) and
  ``J.effort`` (N m or N), and ``J.velocity`` (rad/s or m/s) where the log has it for
  every joint; extra columns ignored.
- A Universal Robots recording as it comes (the RTDE client's ``record.py``, space-separated,
  or ur_rtde's ``startFileRecording``, comma-separated), recognised by its header
  (``timestamp``, ``actual_q_0``...): read by ``rtde.read_rtde``.

Drive gains (``Gains``, N m per A) turn motor currents into joint torques: a UR recording's
``actual_current_i``, or a bag's or CSV's efforts where the driver logged currents there
(``ur_robot_driver`` publishes ``actual_current`` as JointState effort unless told
otherwise). The JointLog keeps them (``current_gains``).

Times are seconds from the log's first message.
"""

from __future__ import annotations

import csv
import dataclasses
from pathlib import Path

import numpy as np

from comgrasp_pin import file_checks
from comgrasp_pin.errors import LogError
from comgrasp_pin.robot_io.log_files import rtde
from comgrasp_pin.robot_io.log_files.gains import Gains
from comgrasp_pin.robot_io.log_files.log_types import JointLog, assemble_log
from comgrasp_pin.robot_io.log_files.log_values import check_joint_rows, check_table

JOINT_STATE = "sensor_msgs/msg/JointState"
DEFAULT_TOPIC = "/joint_states"


def read_log(
    path: str | Path,
    joint_names: list[str] | tuple[str, ...],
    topic: str = DEFAULT_TOPIC,
    windows: list[tuple[float, float]] | None = None,
    gains: Gains | None = None,
) -> JointLog:
    """A bag (a ROS 2 folder, ``.db3`` or ``.mcap``; a ROS 1 ``.bag``) or a ``.csv``, by its name.

    ``gains``: the drive gains that turn the log's motor currents into joint torques (see
    ``read_csv`` and ``read_bag``), or None where it logs torques.
    """
    path = Path(path)
    if path.suffix.lower() == ".csv":
        return read_csv(path, joint_names, gains)
    return read_bag(path, joint_names, topic, windows, gains)


def read_bag(
    path: str | Path,
    joint_names: list[str] | tuple[str, ...],
    topic: str = DEFAULT_TOPIC,
    windows: list[tuple[float, float]] | None = None,
    gains: Gains | None = None,
) -> JointLog:
    """Read the ``joint_names`` columns of a ROS 2 or ROS 1 bag's JointState topic.

    ``windows`` ((t0, t1), s from the first message): read only the messages within a second
    of them (and the last, so the log's length stays known); deserializing every message of
    a long bag costs about 20 us each. None reads every message.
    ``gains``: the messages' efforts are motor currents (A), the torques are gains times
    them (``apply_gains``); None: the efforts are the joint torques.

    Raises:
        LogError: the bag cannot be opened or fails ``file_checks.ros_bag`` (a FIFO, a
            compressed bag), has no such topic or type, no message holds all
            the joints (the missing ones are named), the messages carry no efforts, or a
            value that is NaN, inf or past any sensor's range (``log_values``: its message's
            time, joint and field named).
    """
    from rosbags.highlevel import AnyReader

    path = Path(path)
    bag = file_checks.ros_bag(path, LogError)  # a FIFO, a compressed bag: refused
    names = tuple(joint_names)
    try:
        with AnyReader([bag]) as reader:
            conns = topic_connections(reader, topic, JOINT_STATE, bag)
            raw = joint_rows(reader, conns, names, windows)
            check_joint_rows(raw, names, topic, f"bag {bag}")
            rows = _seconds(raw)
    except LogError:
        raise
    except Exception as exc:  # rosbags raises its own error types for broken bags
        raise LogError(f"cannot read the bag {bag}: {type(exc).__name__}: {exc}") from None
    log = _assemble(rows, names, str(bag))
    return log if gains is None else apply_gains(log, gains)


def topic_connections(reader, topic: str, msgtype: str, bag: Path) -> list:
    """The connections of an open bag's ``topic``, which must carry ``msgtype`` messages.

    Raises:
        LogError: no such topic (the bag's topics listed), or another message type.
    """
    conns = [c for c in reader.connections if c.topic == topic]
    if not conns:
        topics = sorted({f"{c.topic} ({c.msgtype})" for c in reader.connections})
        raise LogError(f"bag {bag} has no topic {topic!r}; its topics are {topics}")
    if any(c.msgtype != msgtype for c in conns):
        raise LogError(f"topic {topic!r} is {conns[0].msgtype}, not {msgtype}")
    return conns


def joint_rows(
    reader, conns, names: tuple[str, ...], windows=None, margin: float = 1.0, need_effort=True
) -> list[tuple]:
    """(stamp (ns), receive time (ns), position, effort, velocity) per message with all names.

    ``_row`` reads each; ``need_effort=False``: effort None where a message has none.
    Columns in the names' order.
    With ``windows`` ((t0, t1) in s from the first usable message, by receive time), only
    the messages within ``margin`` s of a window and the last one are deserialized.
    """
    rows: list = []
    seen: set[str] = set()
    cache: dict[tuple[str, ...], np.ndarray | None] = {}
    t_first, skipped = None, None
    for conn, t_bag, raw in reader.messages(connections=conns):
        if t_first is not None and windows is not None:
            rel = (t_bag - t_first) * 1e-9
            if not any(a - margin <= rel <= b + margin for a, b in windows):
                skipped = (conn, t_bag, raw)
                continue
        skipped = None
        row = _row(reader, conn, t_bag, raw, names, cache, seen, need_effort)
        if row is not None:
            rows.append(row)
            t_first = row[1] if t_first is None else t_first
    if skipped is not None:  # the log's end: the last message
        row = _row(reader, *skipped, names, cache, seen, need_effort)
        rows += [] if row is None else [row]
    if not rows:
        missing = sorted(set(names) - seen)
        raise LogError(
            f"no JointState message holds all the arm's joints: {missing} never appear "
            f"(joints in the log: {sorted(seen)}; the URDF's arm joints: {list(names)})"
        )
    return rows


def _seconds(rows: list[tuple]) -> list[tuple]:
    """``joint_rows``' rows as (t (s) from the first, position, effort, velocity).

    Times are the header stamps, or the receive times where a stamp is zero.
    """
    # integer ns from the first message: float seconds since 1970 keep only 0.2 us
    stamps = np.array([r[0] for r in rows], dtype=np.int64)
    ns = stamps if np.all(stamps > 0) else np.array([r[1] for r in rows], dtype=np.int64)
    times = (ns - ns[0]) * 1e-9
    return [(t, *r[2:]) for t, r in zip(times, rows)]


def _row(reader, conn, t_bag, raw, names, cache, seen, need_effort=True):
    """(stamp (ns), receive time (ns), position, effort, velocity or None) of one message.

    The row is None when the message lacks an arm joint; ``cache`` maps a message's name list to the
    arm joints' indices. A message without efforts is refused, or with ``need_effort=False``
    gives effort None.
    """
    msg = reader.deserialize(raw, conn.msgtype)
    key = tuple(msg.name)
    if key not in cache:
        seen.update(key)
        pos = {n: i for i, n in enumerate(key)}
        cache[key] = np.array([pos[n] for n in names]) if all(n in pos for n in names) else None
    idx = cache[key]
    if idx is None:
        return None
    has_effort = len(msg.effort) == len(key)
    if need_effort and not has_effort:
        raise LogError(
            f"the JointState messages carry {len(msg.effort)} efforts for {len(key)} "
            "joints: the log has no joint efforts (torques); record them (e.g. the "
            "driver's effort field) to estimate a payload"
        )
    stamp = int(msg.header.stamp.sec) * 10**9 + int(msg.header.stamp.nanosec)
    velocity = msg.velocity[idx] if len(msg.velocity) == len(key) else None
    effort = msg.effort[idx] if has_effort else None
    return stamp, int(t_bag), msg.position[idx], effort, velocity


def read_csv(
    path: str | Path, joint_names: list[str] | tuple[str, ...], gains: Gains | None = None
) -> JointLog:
    """Read a wide CSV: ``time`` and ``J.position``, ``J.effort`` per joint J.

    ``J.velocity`` is read too where every joint has it. A Universal Robots recording
    (``rtde.is_rtde_header``: ``timestamp`` and ``actual_q_0`` in its first line, comma- or
    space-separated) is read by ``rtde.read_rtde`` instead. ``gains``: the drive gains
    (N m per A) that turn motor currents into joint torques: a UR recording's
    ``actual_current_i``, or here the ``J.effort`` columns where they hold currents (A).

    Raises:
        LogError: the file is missing, not a regular file (a FIFO, a device), larger than
            ``file_checks.MAX_CSV_BYTES``, not UTF-8; a column is missing (named), or a
            value is not a number, NaN, inf or past any sensor's range
            (``log_values.check_table``: its line and column named); see
            ``rtde.read_rtde`` for a UR recording.
    """
    path = Path(path)
    line = file_checks.first_line(path, "CSV log", file_checks.MAX_CSV_BYTES,
                                  file_checks.MAX_CSV_HEADER_BYTES, LogError)  # fmt: skip
    if rtde.is_rtde_header(line):
        return rtde.read_rtde(path, joint_names, gains)
    try:
        header = [h.strip() for h in next(csv.reader([line]), [])]
    except csv.Error as exc:  # a field past csv's size limit (128 kB)
        raise LogError(f"CSV {path} has no readable header: {exc}") from None
    names = tuple(joint_names)
    wanted = ["time"] + [f"{n}.{field}" for field in ("position", "effort") for n in names]
    missing = [w for w in wanted if w not in header]
    if missing:
        raise LogError(
            f"CSV {path} lacks the columns {missing}; it needs 'time' and, per arm joint J of "
            f"the URDF ({list(names)}), 'J.position' and 'J.effort' (or, a UR recording, "
            "'timestamp' and 'actual_q_0'... as RTDE's record.py and ur_rtde write them)"
        )
    velocity = [f"{n}.velocity" for n in names]
    if all(v in header for v in velocity):
        wanted += velocity
    cols = [header.index(w) for w in wanted]
    data = rtde.load_columns(path, ",", cols, "CSV")
    check_table(data, wanted, path, f"CSV {path}")
    n = len(names)
    has_velocity = data.shape[1] > 1 + 2 * n
    rows = [
        (r[0], r[1 : 1 + n], r[1 + n : 1 + 2 * n], r[1 + 2 * n :] if has_velocity else None)
        for r in data
    ]
    log = _assemble(rows, names, str(path))
    return log if gains is None else apply_gains(log, gains)


def _assemble(rows, names: tuple[str, ...], source: str) -> JointLog:
    """The JointLog of (t, position, effort, velocity or None) rows (``assemble_log``).

    Velocities only where every row has them.
    """
    if len(rows) < 2:
        raise LogError(f"{source} has {len(rows)} usable sample(s); a log needs at least two")
    velocity = None
    if all(r[3] is not None for r in rows):
        velocity = np.array([r[3] for r in rows], dtype=float)
    return assemble_log(
        np.array([r[0] for r in rows], dtype=float),
        np.array([r[1] for r in rows], dtype=float),
        np.array([r[2] for r in rows], dtype=float),
        velocity,
        names,
        source,
    )


def apply_gains(log: JointLog, gains: Gains) -> JointLog:
    """``log`` whose efforts, motor currents (A), become joint torques: gains * currents.

    Raises:
        LogError: the log has another number of joints than gains, other joint names than
            the gains' JSON, or its efforts were made from currents already.
    """
    names = tuple(log.joint_names)
    if len(gains.values) != len(names):
        raise LogError(
            f"{len(gains.values)} drive gains ({gains.source}) for the "
            f"{len(names)} joints of {log.source}; give one per joint {list(names)}"
        )
    if gains.joint_names is not None and gains.joint_names != names:
        raise LogError(
            f"the drive gains ({gains.source}) belong to the joints "
            f"{list(gains.joint_names)}, the log to {list(names)}"
        )
    if log.current_gains is not None:
        raise LogError(
            f"{log.source}: its efforts are torques made from currents already; give the gains once"
        )
    effort = log.effort * gains.values
    effort.flags.writeable = False
    values = gains.values.copy()
    values.flags.writeable = False
    return dataclasses.replace(log, effort=effort, current_gains=values)
