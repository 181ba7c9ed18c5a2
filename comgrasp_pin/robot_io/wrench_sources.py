"""Wrist force/torque logs in, whatever wrote them: one entry point, ``read_wrench_log``.

    robot = load_robot(urdf, ee_frame)
    log = read_wrench_log("run.mcap", robot)  # WrenchStamped; its frame_id is the sensor frame
    log = read_wrench_log("run.csv", robot, sensor_frame="ft_sensor")  # force_x ... torque_z
    log = read_wrench_log("robot_data.csv", robot, sensor_frame="tool0")  # a UR recording

Each source becomes a ``WrenchLog``: the wrench the tool side applies to the sensor, in the
sensor frame, with the arm's joint positions at the wrench's times:

- a ROS 2 bag (a folder, a .db3 or .mcap file): ``wrench_bag.read_wrench_bag``;
- a CSV with ``time``, ``J.position`` and ``force_x`` ... ``torque_z``:
  ``wrench_csv.read_wrench_csv``;
- a Universal Robots recording (recognised by its header, ``timestamp`` and ``actual_q_0``,
  as ``rtde`` does): its ``actual_TCP_force`` by ``wrench_rtde.read_rtde_wrench``, which
  needs the robot model to move it into the sensor frame.

``record.write_wrench_bag`` and ``record.write_wrench_csv`` write the first two.
"""

from __future__ import annotations

from pathlib import Path

from comgrasp_pin import file_checks
from comgrasp_pin.errors import LogError
from comgrasp_pin.robot import RobotModel, check_frame
from comgrasp_pin.robot_io import logs, rtde
from comgrasp_pin.robot_io.wrench_bag import read_wrench_bag
from comgrasp_pin.robot_io.wrench_csv import read_wrench_csv, sensor_frame_name
from comgrasp_pin.robot_io.wrench_log import WrenchLog
from comgrasp_pin.robot_io.wrench_rtde import read_rtde_wrench

BAG_SUFFIXES = (".db3", ".mcap")


def read_wrench_log(
    path: str | Path,
    robot_or_joint_names: RobotModel | list[str] | tuple[str, ...],
    sensor_frame: str | None = None,
    wrench_topic: str | None = None,
    joint_topic: str = logs.DEFAULT_TOPIC,
    tcp_frame: str | None = None,
    base_frame: str | None = None,
) -> WrenchLog:
    """Read a wrench log by its kind: a bag, a UR recording, or the project's CSV.

    Args:
        path: a bag's folder or its .db3 / .mcap file; else a text file, a UR recording
            when its first line is RTDE's header, the project's CSV otherwise.
        robot_or_joint_names: the robot model, or only its arm joint names (enough for a
            bag or a CSV). With the model, the sensor frame must be one of its frames.
        sensor_frame: the frame the wrench is in. A CSV's and a UR recording's must be
            named; a bag's is its messages' frame_id (named only to fill an empty one).
        wrench_topic: a bag's WrenchStamped topic; None: its only one.
        joint_topic: a bag's JointState topic.
        tcp_frame: a UR recording's torque point (``read_rtde_wrench``; default ``tool0``).
        base_frame: a UR recording's base axes (``read_rtde_wrench``).

    Raises:
        InvalidInputError: no sensor frame named for a CSV or a UR recording; a frame that
            is not the robot's (its frames listed).
        LogError: a UR recording without the robot model; what each reader raises.
    """
    path = Path(path)
    robot: RobotModel | None = None
    if isinstance(robot_or_joint_names, RobotModel):
        robot, names = robot_or_joint_names, tuple(robot_or_joint_names.joint_names)
    else:
        names = tuple(robot_or_joint_names)
    if path.is_dir() or path.suffix.lower() in BAG_SUFFIXES:
        log = read_wrench_bag(path, names, wrench_topic, joint_topic, sensor_frame)
    elif rtde.is_rtde_header(_first_line(path)):
        if robot is None:
            raise LogError(
                f"{path} is a UR recording: its actual_TCP_force is at the TCP in base axes, "
                "and moving it into the sensor frame needs the robot model (the URDF), not "
                "only its joint names"
            )
        frame = sensor_frame_name(sensor_frame)
        return read_rtde_wrench(path, robot, frame, tcp_frame, base_frame)
    else:
        log = read_wrench_csv(path, names, sensor_frame_name(sensor_frame))
    if robot is not None:
        check_frame(robot.model, log.sensor_frame, "the wrench's sensor frame")
    return log


def _first_line(path: Path) -> str:
    return file_checks.first_line(path, "wrench log", file_checks.MAX_CSV_BYTES,
                                  file_checks.MAX_CSV_HEADER_BYTES, LogError)  # fmt: skip
