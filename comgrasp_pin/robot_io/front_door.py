"""My log, my payload: one reader for any log and one estimate call that picks the mode.

    robot = load_robot("ur10e.urdf", "tool0")
    log = read_any_log("run.csv", robot, gains=gains)  # joint states, a wrench, a UR recording
    est = estimate_payload(robot, log, motion=True, empty=read_any_log("empty.csv", robot))
    print(summary(est))  # est.verdict, est.reasons; payload_in_flange(robot, est, "tool0")

``read_any_log`` reads a wrench (a ``WrenchLog``, with the joints' efforts where the log has
them) where the file holds one: a bag with a ``geometry_msgs/msg/WrenchStamped`` topic, a
CSV with ``force_x`` ... ``torque_z`` columns, or any log with ``sensor_frame`` named (a UR
recording's ``actual_TCP_force``); the joints' positions and efforts (a ``JointLog``)
otherwise. ``estimate_payload`` picks the mode from what it is given:

========================================  ===========================  ======================
given                                     joint torques (JointLog)     wrench (WrenchLog)
========================================  ===========================  ======================
``before`` and ``after`` windows          ``estimate_from_log``        ``estimate_wrench_pairs``
``motion=True`` (or ``empty``/``arm``)    ``estimate_payload_dynamic`` ``estimate_wrench_dynamic``
neither                                   refused: say which           ``estimate_wrench_static``
========================================  ===========================  ======================

``options`` go to the chosen function by name (its docstring lists them).

``load_robot``: a robot read from its URDF and mounted under any gravity (floor, wall,
ceiling or a tilt). Every model of the package takes gravity from ``model.gravity``
(Pinocchio), in any direction and of any magnitude. The planners measure heights along world
z (``planning.floor_heights``), so for a base mounted otherwise than on a floor,
``gravity_base`` being gravity in the URDF's base (root) frame, the model's world frame is
turned by the smallest rotation R_world_base that takes gravity to -z, and the model's
gravity is (0, 0, -|g|) in it. Joint torques, ee-frame quantities and the CoM in the ee or
flange frame do not depend on that choice of world frame; only ``T_world_ee`` is in the
turned frame.
"""

from __future__ import annotations

import inspect
from collections.abc import Callable
from pathlib import Path
from typing import cast

import numpy as np
import pinocchio as pin

from comgrasp_pin import validate
from comgrasp_pin.errors import InvalidInputError
from comgrasp_pin.robot import RobotModel, urdf_model
from comgrasp_pin.robot_io.at_rest.joint_torques import estimate_from_log
from comgrasp_pin.robot_io.at_rest.wrench_static import (
    estimate_wrench_pairs,
    estimate_wrench_static,
)
from comgrasp_pin.robot_io.from_motion.dynamic import estimate_payload_dynamic
from comgrasp_pin.robot_io.from_motion.wrench_dynamic import estimate_wrench_dynamic
from comgrasp_pin.robot_io.log_files.gains import Gains
from comgrasp_pin.robot_io.log_files.joint_readers import DEFAULT_TOPIC, read_log
from comgrasp_pin.robot_io.log_files.log_types import WRENCH_COLUMNS, JointLog, WrenchLog
from comgrasp_pin.robot_io.log_files.wrench_files import WRENCH_STAMPED
from comgrasp_pin.robot_io.log_files.wrench_sources import BAG_SUFFIXES, read_wrench_log
from comgrasp_pin.robot_io.results.estimate_result import PayloadEstimate

GRAVITY_FLOOR = (0.0, 0.0, -9.81)
"""Gravity in the base frame of a floor-mounted arm (m/s^2)."""


def load_robot(
    urdf_path: str | Path,
    ee_frame: str,
    package_dirs: list[str | Path] | None = None,
    gravity_base: tuple[float, float, float] | np.ndarray = GRAVITY_FLOOR,
) -> RobotModel:
    """The arm of ``urdf_path`` up to ``ee_frame``, with gravity ``gravity_base`` (m/s^2)."""
    g = validate.real_array(gravity_base, "gravity_base")
    if g.shape != (3,) or not np.all(np.isfinite(g)) or not np.linalg.norm(g) > 0.1:
        raise InvalidInputError(
            f"gravity must be 3 finite numbers GX,GY,GZ in the robot's base frame (m/s^2) with "
            f"a magnitude above 0.1, e.g. 0,0,-9.81 on a floor or 9.81,0,0 on a wall; got {g}"
        )
    path = Path(urdf_path)
    full = urdf_model(path, package_dirs)
    R_world_base = rotation_to_down(g)
    if not np.allclose(R_world_base, np.eye(3)):
        _turn_root(full, pin.SE3(R_world_base, np.zeros(3)))
    robot = RobotModel(full, ee_frame, path)
    robot.package_dirs = [str(p) for p in package_dirs or []]  # as from_urdf
    robot.model.gravity = pin.Motion(np.array([0.0, 0.0, -np.linalg.norm(g), 0.0, 0.0, 0.0]))
    return robot


def rotation_to_down(gravity_base: np.ndarray) -> np.ndarray:
    """(3, 3) R_world_base, the smallest rotation taking ``gravity_base`` to (0, 0, -|g|)."""
    quat = pin.Quaternion.FromTwoVectors(np.asarray(gravity_base, float), np.array([0, 0, -1.0]))
    return quat.toRotationMatrix()


def _turn_root(model: pin.Model, M_world_base: pin.SE3) -> None:
    """Place the root of ``model`` at ``M_world_base``: every joint and frame on the universe."""
    for j in range(1, model.njoints):
        if model.parents[j] == 0:
            model.jointPlacements[j] = M_world_base * model.jointPlacements[j]
    for i, frame in enumerate(model.frames):
        if frame.parentJoint == 0 and i > 0:
            frame.placement = M_world_base * frame.placement
            model.frames[i] = frame


def _holds_wrench(path: Path) -> bool:
    """True where the file is a bag with a WrenchStamped topic or a CSV with wrench columns."""
    if path.is_dir() or path.suffix.lower() in BAG_SUFFIXES:
        from rosbags.highlevel import AnyReader

        try:
            with AnyReader([path]) as reader:
                return any(c.msgtype == WRENCH_STAMPED for c in reader.connections)
        except Exception:  # noqa: BLE001 - the joint reader says what is wrong with the bag
            return False
    try:
        with open(path, encoding="utf-8", errors="replace") as f:
            header = f.readline(1 << 16)
    except OSError:
        return False
    columns = {c.strip() for c in header.split(",")}
    return set(WRENCH_COLUMNS) <= columns


def read_any_log(
    path: str | Path,
    robot: RobotModel,
    sensor_frame: str | None = None,
    gains: Gains | None = None,
    topic: str = DEFAULT_TOPIC,
    wrench_topic: str | None = None,
    tcp_frame: str | None = None,
) -> JointLog | WrenchLog:
    """Any log a robot wrote, read by what it holds (the module docstring).

    Args:
        path: a bag (a folder, .db3 or .mcap), the project's CSV or a UR recording.
        robot: the arm (``load_robot``).
        sensor_frame: the URDF frame of a wrench (a CSV's, a UR recording's); naming it
            reads the wrench.
        gains: drive gains turning a joint log's motor currents into torques, or None.
        topic: a bag's JointState topic.
        wrench_topic: a bag's WrenchStamped topic (None: its only one).
        tcp_frame: a UR recording's TCP frame (``read_rtde_wrench``).
    """
    path = Path(path)
    if sensor_frame is not None or wrench_topic is not None or _holds_wrench(path):
        return read_wrench_log(path, robot, sensor_frame, wrench_topic, topic, tcp_frame)
    return read_log(path, robot.joint_names, topic, None, gains)


def estimate_payload(
    robot: RobotModel,
    log: JointLog | WrenchLog,
    before: list[tuple[float, float]] | None = None,
    after: list[tuple[float, float]] | None = None,
    motion: bool = False,
    empty: JointLog | WrenchLog | None = None,
    **options,
) -> PayloadEstimate:
    """The payload from ``log``, the mode picked from what is given (module docstring).

    Args:
        robot: the arm the log is of.
        log: ``read_any_log``'s.
        before: still windows (t0, t1) s with the gripper empty, one per pose.
        after: still windows holding the payload, paired with ``before``.
        motion: the log is a motion (``comgrasp plan-motion``): the inertia too.
        empty: the same arm (or tool) without the payload, along a motion.
        **options (Any): the chosen function's own (``arm_model``, ``gain_cov``, ``windows``...).

    Raises:
        InvalidInputError: a mode the inputs do not make (joint torques at rest without
            their empty windows), or an option the chosen function does not take.
    """
    wrench = isinstance(log, WrenchLog)
    chosen: Callable[..., PayloadEstimate]
    args: tuple
    if (before is None) != (after is None):
        raise InvalidInputError("give both before= and after= windows (one pair per pose)")
    if before is not None:
        if motion or empty is not None:
            raise InvalidInputError("before/after windows are readings at rest, not a motion")
        chosen, args = (estimate_wrench_pairs if wrench else estimate_from_log), (before, after)
    elif motion or empty is not None or "arm_model" in options:
        chosen = estimate_wrench_dynamic if wrench else estimate_payload_dynamic
        args, options = (), {**options, "empty_log": empty}
    elif wrench:
        chosen, args = estimate_wrench_static, ()
    else:
        raise InvalidInputError(
            "joint torques at rest need the empty arm at the same poses: give before= and "
            "after= windows (pair_by_configuration finds them), or motion=True for a motion"
        )
    valid = list(inspect.signature(chosen).parameters)[2 + len(args) :]
    unknown = sorted(set(options) - set(valid))
    if unknown:
        raise InvalidInputError(f"{chosen.__name__} takes no {unknown}; valid options: {valid}")
    return cast(Callable[..., PayloadEstimate], chosen)(robot, log, *args, **options)
