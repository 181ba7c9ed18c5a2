"""Payload out: the payload in the flange frame, and the files that take it.

Robot controllers (UR, Franka, ROS 2, KUKA, ABB, MoveIt) and robot models (URDF,
MJCF).
"""

from comgrasp_pin.robot_io.payload_files.controller_files import (
    franka_desk,
    franka_load,
    krl_load,
    moveit_yaml,
    principal_axes,
    rapid_loaddata,
    ros2_yaml,
    sunrise_load_data,
    urscript,
    write_franka,
    write_ros2,
    write_urscript,
)
from comgrasp_pin.robot_io.payload_files.model_exports import (
    mjcf_payload_body,
    urdf_link_of,
    urdf_with_payload,
)
from comgrasp_pin.robot_io.payload_files.payload import Payload, T_flange_ee, payload_in_flange

__all__ = [
    "Payload",
    "T_flange_ee",
    "payload_in_flange",
    "urscript",
    "write_urscript",
    "franka_load",
    "write_franka",
    "ros2_yaml",
    "write_ros2",
    "franka_desk",
    "krl_load",
    "moveit_yaml",
    "rapid_loaddata",
    "sunrise_load_data",
    "principal_axes",
    "urdf_with_payload",
    "urdf_link_of",
    "mjcf_payload_body",
]
