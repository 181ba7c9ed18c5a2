"""On a real arm: joint and wrench logs in (ROS 2 bags, CSV, UR recordings), payloads out.

    robot = load_robot(urdf, ee_frame, gravity_base=(0, 0, -9.81))
    log = read_log("run.mcap" or "run.csv", robot.joint_names)
    gains = parse_gains("10,10.7,8.46,9.0,9.48,10.1", robot.nq, gain_std=0.1)  # N m per A
    ur_log = read_log("record.csv", robot.joint_names, gains=gains)  # a UR's motor currents
    est = estimate_from_log(robot, log, before=[(1, 2), (5, 6), (9, 10)],
                            after=[(21, 22), (25, 26), (29, 30)])  # a PayloadEstimate
    payload = payload_in_flange(robot, est, "tool0", inertia="point")  # identified only
    write_urscript(payload, "payload.script")
    plan = plan_measurement_poses(robot, k=3)  # limits, no self-collision, D-optimal
    motion = plan_excitation(robot, duration_s=20)  # the inertia too: a motion to record
    arm = identify_arm(robot, empty_log)  # the empty arm's own model, from any motion
    est = estimate_payload_dynamic(robot, loaded_log, arm_model=arm)  # est.verdict, .reasons
    cal = calibrate_gains(robot, loaded_log, empty_log, known_mass_kg=2.805)  # weigh it once
    ft = read_wrench_log("ft.mcap", robot)  # a wrist sensor's WrenchStamped (or CSV, UR)
    est = estimate_wrench_static(robot, ft)  # mass, CoM, the sensor's bias from >= 3 poses
    est = estimate_wrench_dynamic(robot, ft_motion, empty_log=ft_tool_only)  # the inertia too
    text = krl_load(payload)  # KUKA $LOAD; rapid_loaddata, urdf_with_payload, moveit_yaml...

Layer: beside ``procedures``; imports ``estimation``, ``motion.fourier``, ``robot`` and the
shared modules, never ``simulation`` (no MuJoCo here): it runs on a real robot's logs.
"""

from comgrasp_pin.robot_io.arm_model import ArmModel, identify_arm, load_arm_model
from comgrasp_pin.robot_io.dynamic import check_on_log, estimate_payload_dynamic
from comgrasp_pin.robot_io.estimate import estimate_from_log
from comgrasp_pin.robot_io.estimate_result import PayloadEstimate
from comgrasp_pin.robot_io.excitation import (
    ExcitationMotion,
    ExcitationSettings,
    plan_excitation,
)
from comgrasp_pin.robot_io.exports import (
    franka_load,
    ros2_yaml,
    urscript,
    write_franka,
    write_ros2,
    write_urscript,
)
from comgrasp_pin.robot_io.gain_calibration import GainCalibration, calibrate_gains
from comgrasp_pin.robot_io.gains import Gains, gains_json, parse_gains
from comgrasp_pin.robot_io.logs import JointLog, read_bag, read_csv, read_log
from comgrasp_pin.robot_io.model_exports import mjcf_payload_body, urdf_link_of, urdf_with_payload
from comgrasp_pin.robot_io.mount import load_robot
from comgrasp_pin.robot_io.payload import Payload, T_flange_ee, payload_in_flange
from comgrasp_pin.robot_io.planning import PosePlan, plan_measurement_poses
from comgrasp_pin.robot_io.record import write_bag, write_csv, write_wrench_bag, write_wrench_csv
from comgrasp_pin.robot_io.result_file import read_result, result_dict, write_result
from comgrasp_pin.robot_io.rtde import read_rtde
from comgrasp_pin.robot_io.summary import summary
from comgrasp_pin.robot_io.vendor_exports import (
    franka_desk,
    krl_load,
    moveit_yaml,
    principal_axes,
    rapid_loaddata,
    sunrise_load_data,
)
from comgrasp_pin.robot_io.windows import (
    StaticReading,
    find_static_windows,
    pair_by_configuration,
    parse_windows,
    read_window,
)
from comgrasp_pin.robot_io.wrench_dynamic import estimate_wrench_dynamic
from comgrasp_pin.robot_io.wrench_log import WrenchLog
from comgrasp_pin.robot_io.wrench_sources import (
    read_rtde_wrench,
    read_wrench_bag,
    read_wrench_csv,
    read_wrench_log,
)
from comgrasp_pin.robot_io.wrench_static import estimate_wrench_static

__all__ = [
    "ArmModel",
    "ExcitationMotion",
    "ExcitationSettings",
    "GainCalibration",
    "Gains",
    "JointLog",
    "Payload",
    "PayloadEstimate",
    "PosePlan",
    "StaticReading",
    "T_flange_ee",
    "WrenchLog",
    "calibrate_gains",
    "check_on_log",
    "estimate_from_log",
    "estimate_payload_dynamic",
    "estimate_wrench_dynamic",
    "estimate_wrench_static",
    "find_static_windows",
    "franka_desk",
    "franka_load",
    "gains_json",
    "identify_arm",
    "krl_load",
    "load_arm_model",
    "load_robot",
    "mjcf_payload_body",
    "moveit_yaml",
    "pair_by_configuration",
    "parse_gains",
    "parse_windows",
    "payload_in_flange",
    "plan_excitation",
    "plan_measurement_poses",
    "principal_axes",
    "rapid_loaddata",
    "read_bag",
    "read_csv",
    "read_log",
    "read_result",
    "read_rtde",
    "read_rtde_wrench",
    "read_window",
    "read_wrench_bag",
    "read_wrench_csv",
    "read_wrench_log",
    "result_dict",
    "ros2_yaml",
    "summary",
    "sunrise_load_data",
    "urdf_link_of",
    "urdf_with_payload",
    "urscript",
    "write_bag",
    "write_csv",
    "write_franka",
    "write_result",
    "write_ros2",
    "write_urscript",
    "write_wrench_bag",
    "write_wrench_csv",
]
