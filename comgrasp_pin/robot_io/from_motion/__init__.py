"""The payload from a motion: mass, CoM and inertia, and the empty arm's own model.

A log's signals filtered without phase lag, the linear systems of the joint torques
and of the wrench in the payload's ten parameters, their fit, reports and plot.
"""

from comgrasp_pin.robot_io.from_motion.arm_model import ArmModel, identify_arm, load_arm_model
from comgrasp_pin.robot_io.from_motion.dynamic import check_on_log, estimate_payload_dynamic
from comgrasp_pin.robot_io.from_motion.gain_calibration import GainCalibration, calibrate_gains
from comgrasp_pin.robot_io.from_motion.wrench_dynamic import estimate_wrench_dynamic

__all__ = [
    "ArmModel",
    "identify_arm",
    "load_arm_model",
    "GainCalibration",
    "calibrate_gains",
    "estimate_payload_dynamic",
    "check_on_log",
    "estimate_wrench_dynamic",
]
