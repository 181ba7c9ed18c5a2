"""Logs in and out: joint readings and a wrist sensor's wrench, and the drive gains.

ROS 2 bags, wide CSV files and UR recordings are read into a ``JointLog`` or a
``WrenchLog``, checked, and written back; the drive gains turn motor currents into
joint torques.
"""

from comgrasp_pin.robot_io.log_files.gains import Gains, gains_json, parse_gains
from comgrasp_pin.robot_io.log_files.joint_readers import read_bag, read_csv, read_log
from comgrasp_pin.robot_io.log_files.log_types import JointLog, WrenchLog
from comgrasp_pin.robot_io.log_files.record import (
    write_bag,
    write_csv,
    write_wrench_bag,
    write_wrench_csv,
)
from comgrasp_pin.robot_io.log_files.rtde import read_rtde
from comgrasp_pin.robot_io.log_files.wrench_files import read_wrench_bag, read_wrench_csv
from comgrasp_pin.robot_io.log_files.wrench_sources import read_rtde_wrench, read_wrench_log

__all__ = [
    "JointLog",
    "read_log",
    "read_bag",
    "read_csv",
    "read_rtde",
    "Gains",
    "parse_gains",
    "gains_json",
    "WrenchLog",
    "read_wrench_log",
    "read_wrench_bag",
    "read_wrench_csv",
    "read_rtde_wrench",
    "write_bag",
    "write_csv",
    "write_wrench_bag",
    "write_wrench_csv",
]
