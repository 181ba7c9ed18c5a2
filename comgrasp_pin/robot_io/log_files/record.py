"""Writing logs: a ROS 2 bag (rosbags; sqlite3 or mcap) or the wide CSV the readers take.

For tests, benchmarks, the simulation and users who record on a robot without ROS: the same
JointLog or WrenchLog the readers return, written back as a file.

- ``write_bag`` / ``write_csv``: a JointLog as ``sensor_msgs/msg/JointState`` messages, or as
  ``time``, ``J.position``, ``J.effort`` (and ``J.velocity``) columns (``logs``).
- ``write_wrench_bag`` / ``write_wrench_csv``: a WrenchLog as JointState plus
  ``geometry_msgs/msg/WrenchStamped`` messages (frame_id the sensor frame), or as ``time``,
  ``J.position`` (``J.velocity``, ``J.effort``) and ``force_x`` ... ``torque_z`` columns
  (``wrench_files``).
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import numpy as np

from comgrasp_pin.errors import InvalidInputError, OutputError
from comgrasp_pin.robot_io.log_files.joint_readers import DEFAULT_TOPIC, JOINT_STATE, JointLog
from comgrasp_pin.robot_io.log_files.log_types import WRENCH_COLUMNS, WrenchLog
from comgrasp_pin.robot_io.log_files.wrench_files import WRENCH_STAMPED

STORAGES = ("sqlite3", "mcap")
DEFAULT_WRENCH_TOPIC = "/wrench"
"""The topic ``write_wrench_bag`` writes to by default (the name UR's ROS driver uses)."""
T0_NS = 1_700_000_000_000_000_000
"""Header stamp and receive time of a written log's first message (ns since the epoch)."""


def _save_columns(path: Path, header: list[str], columns: list[np.ndarray]) -> Path:
    """Write (N,) and (N, k) ``columns`` side by side as a CSV under ``header``."""
    try:
        np.savetxt(path, np.column_stack(columns), delimiter=",", header=",".join(header),
                   comments="", fmt="%.10g")  # fmt: skip
    except OSError as exc:
        raise OutputError(f"cannot write the CSV {path}: {exc}") from None
    return path


def write_csv(log: JointLog, path: str | Path) -> Path:
    """Write ``log`` as a CSV with ``time`` and ``J.position``, ``J.effort`` per joint J.

    ``J.velocity`` too where the log has velocities.
    """
    fields = ("position", "effort") + (() if log.velocity is None else ("velocity",))
    header = ["time"] + [f"{n}.{f}" for f in fields for n in log.joint_names]
    return _save_columns(Path(path), header, [log.time, *(getattr(log, f) for f in fields)])


def write_wrench_csv(path: str | Path, wrench_log: WrenchLog) -> Path:
    """Write ``wrench_log`` as the CSV ``wrench_files.read_wrench_csv`` reads.

    Columns ``time`` (s), ``J.position`` per joint J, ``J.velocity`` and ``J.effort`` where
    the log has them, then ``force_x`` ... ``torque_z`` (N, N m) in its sensor frame, which
    the file does not name: the reader is told it.
    """
    log = wrench_log
    fields = [f for f in ("position", "velocity", "effort") if getattr(log, f) is not None]
    header = ["time"] + [f"{n}.{f}" for f in fields for n in log.joint_names]
    columns = [log.time, *(getattr(log, f) for f in fields), log.wrench]
    return _save_columns(Path(path), header + list(WRENCH_COLUMNS), columns)


@contextmanager
def _bag(path: Path, storage: str) -> Iterator[tuple]:
    """(an open rosbags Writer, the ROS 2 Humble typestore) for the new bag folder ``path``.

    Raises:
        InvalidInputError: an unknown storage; OutputError: ``path`` exists or cannot be
            written.
    """
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_typestore

    if storage not in STORAGES:
        raise InvalidInputError(f"unknown bag storage {storage!r}; valid are {STORAGES}")
    if path.exists():
        raise OutputError(f"the bag {path} exists already; choose a new folder or remove it")
    plugin = StoragePlugin.MCAP if storage == "mcap" else StoragePlugin.SQLITE3
    try:
        with Writer(path, version=9, storage_plugin=plugin) as writer:
            yield writer, get_typestore(Stores.ROS2_HUMBLE)
    except OSError as exc:
        raise OutputError(f"cannot write the bag {path}: {exc}") from None


def _header(store, ns: int, frame_id: str = ""):
    """A ``std_msgs/msg/Header`` stamped ``ns`` (ns since the epoch)."""
    Time = store.types["builtin_interfaces/msg/Time"]
    return store.types["std_msgs/msg/Header"](
        stamp=Time(sec=ns // 10**9, nanosec=ns % 10**9), frame_id=frame_id
    )


def _joint_state(store, ns: int, names: list[str], position, velocity, effort) -> bytes:
    """A serialized JointState; velocity or effort None: written empty."""
    msg = store.types[JOINT_STATE](
        header=_header(store, ns),
        name=names,
        position=np.asarray(position, dtype=float),
        velocity=np.empty(0) if velocity is None else np.asarray(velocity, dtype=float),
        effort=np.empty(0) if effort is None else np.asarray(effort, dtype=float),
    )
    return store.serialize_cdr(msg, JOINT_STATE)


def write_bag(
    log: JointLog,
    path: str | Path,
    storage: str = "sqlite3",
    topic: str = DEFAULT_TOPIC,
    extra_joints: dict[str, float] | None = None,
    t0_ns: int = T0_NS,
) -> Path:
    """Write ``log`` as a ROS 2 bag folder of ``sensor_msgs/msg/JointState`` messages.

    Args:
        log: the readings; velocities written where the log has them, else empty.
        path: the bag folder to create (must not exist).
        storage: "sqlite3" or "mcap".
        topic: the topic name.
        extra_joints: joints appended to every message with a fixed position and zero effort
            (a gripper's fingers), or None.
        t0_ns: header stamp and receive time of the first message (ns since the epoch).
    """
    extra = extra_joints or {}
    names = [*log.joint_names, *extra]
    extra_pos = np.array(list(extra.values()), dtype=float)
    extra_eff = np.zeros(len(extra))
    path = Path(path)
    with _bag(path, storage) as (writer, store):
        conn = writer.add_connection(topic, JOINT_STATE, typestore=store)
        velocities = log.velocity if log.velocity is not None else [None] * len(log.time)
        for t, q, tau, qd in zip(log.time, log.position, log.effort, velocities):
            ns = t0_ns + round(float(t) * 1e9)
            qd = None if qd is None else np.concatenate([qd, extra_eff])
            msg = _joint_state(store, ns, names, np.concatenate([q, extra_pos]), qd,
                               np.concatenate([tau, extra_eff]))  # fmt: skip
            writer.write(conn, ns, msg)
    return path


def write_wrench_bag(
    path: str | Path,
    wrench_log: WrenchLog,
    joint_topic: str = DEFAULT_TOPIC,
    wrench_topic: str = DEFAULT_WRENCH_TOPIC,
    storage: str = "sqlite3",
    t0_ns: int = T0_NS,
) -> Path:
    """Write ``wrench_log`` as a ROS 2 bag: a JointState and a WrenchStamped per sample.

    Both messages of a sample carry its time as header stamp and receive time; the
    WrenchStamped's ``header.frame_id`` is the log's sensor frame. Velocities and efforts are
    written where the log has them, else empty.

    Args:
        path: the bag folder to create (must not exist).
        wrench_log: the readings.
        joint_topic: the JointState topic.
        wrench_topic: the WrenchStamped topic.
        storage: "sqlite3" or "mcap".
        t0_ns: the first sample's time (ns since the epoch).
    """
    log, path = wrench_log, Path(path)
    none = [None] * len(log.time)
    with _bag(path, storage) as (writer, store):
        joints = writer.add_connection(joint_topic, JOINT_STATE, typestore=store)
        wrenches = writer.add_connection(wrench_topic, WRENCH_STAMPED, typestore=store)
        rows = zip(log.time, log.position, none if log.velocity is None else log.velocity,
                   none if log.effort is None else log.effort, log.wrench)  # fmt: skip
        for t, q, qd, tau, w in rows:
            ns = t0_ns + round(float(t) * 1e9)
            writer.write(joints, ns, _joint_state(store, ns, list(log.joint_names), q, qd, tau))
            writer.write(wrenches, ns, _wrench_stamped(store, ns, log.sensor_frame, w))
    return path


def _wrench_stamped(store, ns: int, frame_id: str, wrench: np.ndarray) -> bytes:
    """A serialized WrenchStamped of the (6,) force (N) and torque (N m) in ``frame_id``."""
    Vector3 = store.types["geometry_msgs/msg/Vector3"]
    msg = store.types[WRENCH_STAMPED](
        header=_header(store, ns, frame_id),
        wrench=store.types["geometry_msgs/msg/Wrench"](
            force=Vector3(*map(float, wrench[:3])), torque=Vector3(*map(float, wrench[3:]))
        ),
    )
    return store.serialize_cdr(msg, WRENCH_STAMPED)
