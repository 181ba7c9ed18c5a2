"""A wrist sensor's wrench from a wide CSV, and the assembly every wrench reader shares.

The CSV (``read_wrench_csv``; ``record.write_wrench_csv`` writes it): a header row with
``time`` (s), ``J.position`` (rad or m) per arm joint J, and ``force_x, force_y, force_z`` (N),
``torque_x, torque_y, torque_z`` (N m): the wrench the tool side applies to the sensor
(``wrench_log``), in the sensor frame, which the file does not name (the caller does).
``J.velocity`` (rad/s) and ``J.effort`` (N m) are read where every arm joint has them.
Other columns are ignored.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from comgrasp_pin import file_checks
from comgrasp_pin.errors import InvalidInputError, LogError
from comgrasp_pin.robot_io.log_files import rtde
from comgrasp_pin.robot_io.log_files.log_types import WRENCH_COLUMNS, WrenchLog
from comgrasp_pin.robot_io.log_files.log_values import check_table

OPTIONAL_FIELDS = ("velocity", "effort")
"""Per-joint CSV fields read where every arm joint has them (rad/s, N m)."""


def sensor_frame_name(sensor_frame: object) -> str:
    """``sensor_frame`` when it is a non-empty string.

    Raises:
        InvalidInputError: anything else (None, an empty string, not a string).
    """
    if not isinstance(sensor_frame, str) or not sensor_frame:
        raise InvalidInputError(
            f"the sensor frame must be named (a frame of the URDF, the one the wrench is "
            f"measured in: sensor_frame=..., --sensor-frame), got {sensor_frame!r}"
        )
    return sensor_frame


def assemble_wrench_log(
    t: np.ndarray,
    position: np.ndarray,
    wrench: np.ndarray,
    names: tuple[str, ...],
    sensor_frame: str,
    source: str,
    velocity: np.ndarray | None = None,
    effort: np.ndarray | None = None,
) -> WrenchLog:
    """The read-only WrenchLog of a log's (N,) times (s) and (N, k) columns.

    Sorted by time (stable: samples with the same time keep the file's order), time from the
    first sample.

    Raises:
        LogError: fewer than two samples (WrenchLog refuses NaN, inf and wrong shapes).
    """
    if len(t) < 2:
        raise LogError(f"{source} has {len(t)} usable sample(s); a wrench log needs at least two")
    t = np.asarray(t, dtype=float)
    order = np.argsort(t, kind="stable")
    v, e = (None if a is None else _sorted(a, order) for a in (velocity, effort))
    return WrenchLog(_sorted(t - t[order[0]], order), names, _sorted(position, order),
                     _sorted(wrench, order), sensor_frame, source, v, e)  # fmt: skip


def _sorted(a: np.ndarray, order: np.ndarray) -> np.ndarray:
    """A read-only float copy of ``a``'s rows in ``order``."""
    out = np.asarray(a, dtype=float)[order]
    out.flags.writeable = False
    return out


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
            ``wrench_rtde.read_rtde_wrench``, which needs the robot); a column is missing
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
