"""Writing joint logs: a ROS 2 bag (rosbags; sqlite3 or mcap) or the wide CSV ``logs`` reads.

For tests, benchmarks and users who record on a robot without ROS: the same JointLog the
readers return, written back as a file.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from comgrasp_pin.errors import InvalidInputError, OutputError
from comgrasp_pin.robot_io.logs import DEFAULT_TOPIC, JOINT_STATE, JointLog

STORAGES = ("sqlite3", "mcap")


def write_csv(log: JointLog, path: str | Path) -> Path:
    """Write ``log`` as a CSV with ``time`` and ``J.position``, ``J.effort`` per joint J.

    ``J.velocity`` too where the log has velocities.
    """
    path = Path(path)
    fields = ("position", "effort") + (() if log.velocity is None else ("velocity",))
    header = ["time"] + [f"{n}.{f}" for f in fields for n in log.joint_names]
    data = np.column_stack([log.time, *(getattr(log, f) for f in fields)])
    try:
        np.savetxt(path, data, delimiter=",", header=",".join(header), comments="", fmt="%.10g")
    except OSError as exc:
        raise OutputError(f"cannot write the CSV {path}: {exc}") from None
    return path


def write_bag(
    log: JointLog,
    path: str | Path,
    storage: str = "sqlite3",
    topic: str = DEFAULT_TOPIC,
    extra_joints: dict[str, float] | None = None,
    t0_ns: int = 1_700_000_000_000_000_000,
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
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_typestore

    if storage not in STORAGES:
        raise InvalidInputError(f"unknown bag storage {storage!r}; valid are {STORAGES}")
    store = get_typestore(Stores.ROS2_HUMBLE)
    JointState = store.types[JOINT_STATE]
    Header = store.types["std_msgs/msg/Header"]
    Time = store.types["builtin_interfaces/msg/Time"]
    extra = extra_joints or {}
    names = [*log.joint_names, *extra]
    extra_pos = np.array(list(extra.values()), dtype=float)
    extra_eff = np.zeros(len(extra))
    plugin = StoragePlugin.MCAP if storage == "mcap" else StoragePlugin.SQLITE3
    path = Path(path)
    if path.exists():
        raise OutputError(f"the bag {path} exists already; choose a new folder or remove it")
    try:
        with Writer(path, version=9, storage_plugin=plugin) as writer:
            conn = writer.add_connection(topic, JOINT_STATE, typestore=store)
            velocities = log.velocity if log.velocity is not None else [None] * len(log.time)
            for t, q, tau, qd in zip(log.time, log.position, log.effort, velocities):
                ns = t0_ns + round(float(t) * 1e9)
                msg = JointState(
                    header=Header(stamp=Time(sec=ns // 10**9, nanosec=ns % 10**9), frame_id=""),
                    name=names,
                    position=np.concatenate([q, extra_pos]),
                    velocity=np.empty(0) if qd is None else np.concatenate([qd, extra_eff]),
                    effort=np.concatenate([tau, extra_eff]),
                )
                writer.write(conn, ns, store.serialize_cdr(msg, JOINT_STATE))
    except OSError as exc:
        raise OutputError(f"cannot write the bag {path}: {exc}") from None
    return path
