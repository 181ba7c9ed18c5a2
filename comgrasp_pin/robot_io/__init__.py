"""On a real arm: joint and wrench logs in (ROS 2 bags, CSV, UR recordings), payloads out.

    robot = load_robot(urdf, ee_frame, gravity_base=(0, 0, -9.81))
    log = read_any_log("run.mcap" or "run.csv", robot)  # joints, or a wrench where it has one
    gains = parse_gains("10,10.7,8.46,9.0,9.48,10.1", robot.nq, gain_std=0.1)  # N m per A
    ur_log = read_any_log("record.csv", robot, gains=gains)  # a UR's motor currents
    est = estimate_payload(robot, log, before=[(1, 2), (5, 6), (9, 10)],
                           after=[(21, 22), (25, 26), (29, 30)])  # the mode picked for you
    print(summary(est))  # est.verdict, est.reasons; write_result(est, "RESULT.json")
    payload = payload_in_flange(robot, est, "tool0", inertia="point")  # identified only
    payload_files.write_urscript(payload, "payload.script")
    plan = plan_measurement_poses(robot, k=3)  # limits, no self-collision, D-optimal
    motion = plan_excitation(robot, duration_s=20)  # the inertia too: a motion to record
    arm = identify_arm(robot, empty_log)  # the empty arm's own model, from any motion
    est = estimate_payload_dynamic(robot, loaded_log, arm_model=arm)  # est.verdict, .reasons
    cal = calibrate_gains(robot, loaded_log, empty_log, known_mass_kg=2.805)  # weigh it once
    ft = read_wrench_log("ft.mcap", robot)  # a wrist sensor's WrenchStamped (or CSV, UR)
    est = estimate_wrench_static(robot, ft)  # mass, CoM, the sensor's bias from >= 3 poses
    est = estimate_wrench_dynamic(robot, ft_motion, empty_log=ft_tool_only)  # the inertia too
    text = payload_files.krl_load(payload)  # KUKA $LOAD; rapid_loaddata, moveit_yaml...

Where the arm goes to measure (poses, excitation motions) is planned in
``comgrasp_pin.planning``; the two planners are re-exported here.

Layer: beside ``procedures``; imports ``planning``, ``estimation``, ``robot`` and the
shared modules, never ``simulation`` (no MuJoCo here): it runs on a real robot's logs.

This front door lists the 25 names most users need; each folder's ``__init__`` lists its own
(``from comgrasp_pin.robot_io.payload_files import krl_load``):

- ``log_files/``: logs in and out (ROS 2 bags, CSV, UR recordings), drive gains.
- ``at_rest/``: the payload from static windows (joint torques, wrist sensor).
- ``from_motion/``: the payload from a motion, and the empty arm's own model.
- ``results/``: what an estimate gives back and whether to trust it.
- ``payload_files/``: the payload in the flange frame and the files controllers take.
- ``payload_files/motion_files.py``: a planned motion out as JSON, CSV, URScript, ROS 2.
- ``mount.py``: ``load_robot``; the maths without I/O is in ``comgrasp_pin.estimation``.
"""

from comgrasp_pin.planning import plan_excitation, plan_measurement_poses
from comgrasp_pin.robot_io.at_rest import (
    estimate_from_log,
    estimate_wrench_pairs,
    estimate_wrench_static,
)
from comgrasp_pin.robot_io.from_motion import (
    calibrate_gains,
    estimate_payload_dynamic,
    estimate_wrench_dynamic,
    identify_arm,
)
from comgrasp_pin.robot_io.front_door import estimate_payload, load_robot, read_any_log
from comgrasp_pin.robot_io.log_files import (
    JointLog,
    WrenchLog,
    parse_gains,
    read_log,
    read_wrench_log,
    write_bag,
    write_csv,
)
from comgrasp_pin.robot_io.payload_files import Payload, payload_in_flange
from comgrasp_pin.robot_io.results import PayloadEstimate, read_result, summary, write_result

__all__ = [
    # read any log
    "load_robot",
    "read_any_log",
    "read_log",
    "read_wrench_log",
    "JointLog",
    "WrenchLog",
    "parse_gains",
    "write_csv",
    "write_bag",
    # estimate: the mode picked for you, or by name
    "estimate_payload",
    "estimate_from_log",
    "estimate_wrench_pairs",
    "estimate_wrench_static",
    "estimate_payload_dynamic",
    "estimate_wrench_dynamic",
    "identify_arm",
    "calibrate_gains",
    # the result, its file, its summary
    "PayloadEstimate",
    "summary",
    "write_result",
    "read_result",
    # payload files (more in payload_files)
    "Payload",
    "payload_in_flange",
    # plan what the arm plays
    "plan_measurement_poses",
    "plan_excitation",
]
