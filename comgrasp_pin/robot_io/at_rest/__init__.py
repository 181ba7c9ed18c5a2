"""The payload from readings at rest: static windows, joint torques, a wrist sensor.

A log's static windows, paired before and after the grasp, give the payload's mass
and CoM from the joint torques or from a wrist sensor's wrench.
"""

from comgrasp_pin.robot_io.at_rest.joint_torques import estimate_from_log
from comgrasp_pin.robot_io.at_rest.windows import (
    StaticReading,
    find_static_windows,
    pair_by_configuration,
    parse_windows,
    read_window,
    spans,
)
from comgrasp_pin.robot_io.at_rest.wrench_static import (
    estimate_wrench_pairs,
    estimate_wrench_static,
)

__all__ = [
    "StaticReading",
    "find_static_windows",
    "pair_by_configuration",
    "parse_windows",
    "read_window",
    "spans",
    "estimate_from_log",
    "estimate_wrench_static",
    "estimate_wrench_pairs",
]
