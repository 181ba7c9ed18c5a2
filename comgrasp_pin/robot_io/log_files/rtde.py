"""Universal Robots recordings as they come: the RTDE client's record.py, ur_rtde's CSV.

Two writers, one header vocabulary (RTDE's output names, a vector's entries suffixed ``_i``):

- the official RTDE Python client's ``record.py``: space-separated, e.g. ``timestamp
  actual_q_0 .. actual_q_5 actual_qd_0 .. actual_current_0 .. target_current_0 ..
  target_moment_0 ..``;
- ur_rtde's ``RTDEReceiveInterface.startFileRecording``: comma-separated, the same names.

Read: ``timestamp`` (the controller's clock, s, not zero-based), ``actual_q_i`` (rad),
``actual_qd_i`` (rad/s) where every joint has it, and the efforts: ``actual_current_i``
(motor currents, A) times drive gains (``gains.Gains``, N m per A), or
``actual_current_as_torque_i`` (N m, PolyScope 5.23 and later) where no gains are given.
Joints i = 0..5 are the chain's joints in order. Other columns (``target_current_i``,
``actual_TCP_force_i``...) are ignored; ``target_moment_i`` too: it is the controller's own
model torque, not a measurement, and is never taken for one.
"""

from __future__ import annotations

import csv
import re
from pathlib import Path

import numpy as np

from comgrasp_pin import file_checks
from comgrasp_pin.errors import LogError
from comgrasp_pin.robot_io.log_files.gains import Gains
from comgrasp_pin.robot_io.log_files.log_types import JointLog, assemble_log
from comgrasp_pin.robot_io.log_files.log_values import check_table

TIME = "timestamp"
POSITION = "actual_q"
VELOCITY = "actual_qd"
CURRENT = "actual_current"
TORQUE = "actual_current_as_torque"
"""RTDE's joint torques (N m) from the currents with UR's own constants (PolyScope >= 5.23)."""

NO_GAINS = (
    "this UR log has motor currents, not torques; give --current-gains K1,...,K{n} (N m per "
    "A) or the JSON of `comgrasp calibrate-gains`, and --gain-std R (the gains' relative std, "
    "e.g. 0.1 for nominal gains; the JSON carries its own covariance)"
)


def header_columns(line: str) -> list[str]:
    """The header's names: comma-separated (ur_rtde) or whitespace-separated (record.py)."""
    if "," in line:
        try:
            return [h.strip() for h in next(csv.reader([line]), [])]
        except csv.Error:  # a field past csv's size limit: not a UR header
            return []
    return line.split()


def is_rtde_header(first_line: str) -> bool:
    """Whether ``first_line`` is a UR recording's header: ``timestamp`` and ``actual_q_0``.

    Comma-separated (ur_rtde) or space-separated (the RTDE client's record.py).
    """
    names = header_columns(first_line)
    return TIME in names and f"{POSITION}_0" in names


def vector_columns(header: list[str], name: str, n: int) -> list[int] | None:
    """The column indices of ``name_0`` .. ``name_{n-1}``, or None where one is missing."""
    wanted = [f"{name}_{i}" for i in range(n)]
    return [header.index(w) for w in wanted] if all(w in header for w in wanted) else None


def _n_joints(header: list[str]) -> int:
    pattern = re.compile(rf"{POSITION}_(\d+)")
    found = {int(m.group(1)) for h in header if (m := pattern.fullmatch(h))}
    n = 0
    while n in found:
        n += 1
    return n


def read_rtde(
    path: str | Path, joint_names: list[str] | tuple[str, ...], gains: Gains | None = None
) -> JointLog:
    """Read a UR recording (record.py or ur_rtde), joints 0..n-1 as ``joint_names``.

    Times are the controller's ``timestamp`` minus the first (sorted; repeated timestamps
    kept in the file's order). Efforts: with ``gains``, ``gains.values[i] *
    actual_current_i`` (and the JointLog keeps the gains in ``current_gains``); without,
    ``actual_current_as_torque_i`` where logged. A current log without gains is refused,
    never guessed. ``target_moment_i`` is the controller's model torque, not a measurement:
    it is never read.

    Args:
        path: the recording, comma- or space-separated, with a header row.
        joint_names: the arm's joints in chain order; as many as the log's ``actual_q_i``.
        gains: drive gains (N m per A), one per joint, or None.

    Raises:
        LogError: the file fails ``file_checks.first_line`` (missing, a FIFO, larger than
            ``file_checks.MAX_CSV_BYTES``, not UTF-8), has no RTDE header, another number
            of joints than ``joint_names``, currents without gains (the message says what to
            give), gains without currents or for other joints, a value that is not a
            number, NaN, inf or past any sensor's range (``log_values.check_table``: its line
            and column named), fewer than two samples.
    """
    path = Path(path)
    names = tuple(joint_names)
    header, delimiter = recording_header(path, names)
    n = len(names)
    if gains is not None and gains.joint_names not in (None, names):
        raise LogError(
            f"the drive gains ({gains.source}) belong to the joints {list(gains.joint_names)}, "
            f"the log is read as {list(names)}: calibrate the gains on this arm's URDF"
        )
    velocity = vector_columns(header, VELOCITY, n)
    efforts, current_gains = _effort_columns(header, n, gains, path)
    positions = vector_columns(header, POSITION, n) or []
    cols = [header.index(TIME), *positions, *efforts, *(velocity or [])]
    data = load_columns(path, delimiter, cols)
    check_table(data, [header[c] for c in cols], path, f"UR log {path}")
    t, q = data[:, 0], data[:, 1 : 1 + n]
    effort = data[:, 1 + n : 1 + 2 * n]
    if current_gains is not None:
        effort = effort * current_gains
    qd = data[:, 1 + 2 * n :] if velocity is not None else None
    return assemble_log(t, q, effort, qd, names, str(path), current_gains)


def recording_header(path: Path, names: tuple[str, ...]) -> tuple[list[str], str | None]:
    """(the column names, the delimiter: "," or None for white space) of a UR recording.

    Raises:
        LogError: the file fails ``file_checks.first_line``, has no RTDE header, or another
            number of joints than ``names``.
    """
    line = file_checks.first_line(path, "UR log", file_checks.MAX_CSV_BYTES,
                                  file_checks.MAX_CSV_HEADER_BYTES, LogError)  # fmt: skip
    header = header_columns(line)
    if not is_rtde_header(line):
        raise LogError(
            f"{path} is not a UR RTDE recording: its header lacks {TIME!r} and "
            f"'{POSITION}_0' (record.py or ur_rtde's startFileRecording write them)"
        )
    n = _n_joints(header)
    if n != len(names):
        raise LogError(
            f"UR log {path} has {n} joints ({POSITION}_0..{POSITION}_{n - 1}); the URDF's "
            f"arm has {len(names)} ({list(names)}): give the URDF of the arm that recorded "
            "it, whose chain's joints are the log's 0..n-1"
        )
    return header, "," if "," in line else None


def _effort_columns(header: list[str], n: int, gains: Gains | None, path: Path):
    """(the efforts' column indices, the gains (n,) that make them torques or None)."""
    currents = vector_columns(header, CURRENT, n)
    torques = vector_columns(header, TORQUE, n)
    if gains is None:
        if torques is not None:
            return torques, None
        if currents is not None:
            raise LogError(f"{path}: {NO_GAINS.format(n=n)}")
        raise LogError(
            f"UR log {path} has no joint efforts: neither {CURRENT}_0..{n - 1} (motor "
            f"currents, with --current-gains) nor {TORQUE}_0..{n - 1} (N m); record one of "
            f"them ({TIME}, {POSITION}, {VELOCITY} and {CURRENT} in the RTDE recipe)"
        )
    if currents is None:
        raise LogError(
            f"UR log {path} has no motor currents ({CURRENT}_0..{n - 1}) for the drive gains "
            f"({gains.source}) to turn into torques; leave --current-gains out for a log of "
            f"{TORQUE}, or record {CURRENT}"
        )
    if len(gains.values) != n:
        raise LogError(
            f"{len(gains.values)} drive gains ({gains.source}) for the {n} joints of UR log "
            f"{path}: give {n}, one per joint in chain order"
        )
    return currents, gains.values


def load_columns(
    path: Path, delimiter: str | None, cols: list[int], what: str = "UR log"
) -> np.ndarray:
    """The ``cols`` of a text log below its header row, (N, len(cols)); ``what`` names it."""
    try:
        data = np.loadtxt(path, delimiter=delimiter, skiprows=1, usecols=cols, ndmin=2)
    except ValueError as exc:
        raise LogError(f"{what} {path} has a value that is not a number: {exc}") from None
    except MemoryError:  # within MAX_CSV_BYTES, yet more than this machine holds
        raise LogError(f"{what} {path} is too large to load here") from None
    return data
