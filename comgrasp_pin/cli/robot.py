"""The real-arm subcommands: `estimate` (logs in, payload out), `plan-poses`, `plan-motion`.

Registered by ``comgrasp_pin.cli`` through ``add_subcommands`` (``dynamic``: estimate
--dynamic; ``motion``: plan-motion); errors are ComGraspError
(exit status 2 with the message, no traceback), argparse's own errors exit 2 as well.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from comgrasp_pin.cli.dynamic import add_dynamic_args, run_dynamic
from comgrasp_pin.cli.exports import add_export_args, finish_estimate
from comgrasp_pin.cli.gains_args import add_gains_args, gains_from_args
from comgrasp_pin.cli.motion import add_plan_motion, run_plan_motion
from comgrasp_pin.cli.wrench import add_wrench_args, run_wrench
from comgrasp_pin.cli.wrench_dynamic import run_wrench_dynamic
from comgrasp_pin.errors import InvalidInputError, OutputError

_DEFAULTS = argparse.ArgumentDefaultsHelpFormatter


def _vector(text: str, option: str, n: int | None = None) -> np.ndarray:
    try:
        v = np.array([float(x) for x in text.split(",")])
    except ValueError:
        raise InvalidInputError(f"{option} {text!r}: comma-separated numbers expected") from None
    if n is not None and len(v) != n:
        raise InvalidInputError(f"{option} {text!r}: {n} numbers expected, got {len(v)}")
    return v


def robot_of(args: argparse.Namespace):
    from comgrasp_pin.robot_io import load_robot

    gravity = _vector(args.gravity, "--gravity", 3)
    return load_robot(args.urdf, args.ee_frame, args.package_dir, gravity)


def write_json(path: str, data: dict) -> None:
    try:
        Path(path).write_text(json.dumps(data, indent=2) + "\n")
    except OSError as exc:
        raise OutputError(f"cannot write {path}: {exc}") from None


def _log_and_windows(args: argparse.Namespace, robot):
    """The log, its paired windows and the drive gains (or None), as the options ask."""
    from comgrasp_pin.robot_io.at_rest import pair_by_configuration, parse_windows, spans
    from comgrasp_pin.robot_io.log_files import read_bag, read_csv

    if args.auto and args.grasp_time is None:
        raise InvalidInputError("--auto needs --grasp-time T (s from the log's start)")
    if not args.auto and (args.before is None or args.after is None):
        raise InvalidInputError("give --before and --after windows, or --auto --grasp-time T")
    before = after = []
    if not args.auto:
        before = parse_windows(args.before, "--before", joined=True)
        after = parse_windows(args.after, "--after", joined=True)
    gains = gains_from_args(args, robot)  # None: the log's efforts are torques
    if args.bag is not None:  # with windows, only the messages near them are decoded
        wanted = None if args.auto else [s for w in before + after for s in spans(w)]
        log = read_bag(args.bag, robot.joint_names, args.topic, wanted, gains)
    else:
        log = read_csv(args.csv, robot.joint_names, gains)
    if args.auto:
        before, after = pair_by_configuration(log, args.grasp_time, args.max_speed)
    return log, before, after, gains


def _cmd_estimate(args: argparse.Namespace) -> int:
    from comgrasp_pin import robot_io as rio

    robot = robot_of(args)
    if args.wrench:
        return (run_wrench_dynamic if args.dynamic else run_wrench)(args, robot)
    if args.dynamic:
        return run_dynamic(args, robot)
    log, before, after, gains = _log_and_windows(args, robot)
    gain_cov = None if gains is None else gains.cov  # the gains' error enters the covariance
    est = rio.estimate_from_log(robot, log, before, after, args.torque_std, args.method,
                                args.max_speed, args.drift_std, gain_cov,
                                pose_errors=args.pose_errors)  # fmt: skip
    return finish_estimate(args, robot, est)


def _cmd_plan(args: argparse.Namespace) -> int:
    from comgrasp_pin.planning import measurement_poses as planning

    robot = robot_of(args)
    if args.urscript and robot.nq != planning.UR_JOINTS:
        raise InvalidInputError(
            f"--urscript writes a movej program for a {planning.UR_JOINTS}-joint UR arm; "
            f"this one has {robot.nq} joints (leave --urscript out, or use the JSON)"
        )
    start = None if args.start is None else _vector(args.start, "--start", robot.nq)
    plan = planning.plan_measurement_poses(
        robot,
        args.k,
        start=start,
        torque_std=args.torque_std,
        mass=args.mass,
        srdf=args.srdf,
        n_candidates=args.candidates,
        seed=args.seed,
        sensor_frame=args.sensor_frame,
        wrench_std=tuple(_vector(args.wrench_std, "--wrench-std", 2)),
    )
    write_json(args.out, planning.plan_dict(plan))
    s = plan.predicted_std
    noise = (f"{args.torque_std:g} N m per averaged reading" if args.sensor_frame is None else
             f"the wrist sensor at {args.sensor_frame}, {args.wrench_std} N, N m per averaged "
             "reading")  # fmt: skip
    print(f"{args.k} poses for {robot.ee_frame}, collision-free and within the joint limits")
    print(f"  predicted std for a {args.mass:g} kg payload with {noise}: mass {s[0]:.4g} kg, "
          f"CoM {np.array2string(1e3 * s[1:], precision=2)} mm")  # fmt: skip
    if args.urscript:
        path = Path(args.urscript)
        try:
            path.write_text(planning.urscript_program(plan))
        except OSError as exc:
            raise OutputError(f"cannot write {path}: {exc}") from None
        print(f"wrote {path}")
    print(f"wrote {args.out}")
    return 0


def _cmd_plan_motion(args: argparse.Namespace) -> int:

    robot = robot_of(args)
    start = None if args.start is None else _vector(args.start, "--start", robot.nq)
    return run_plan_motion(args, robot, start)


def add_robot_args(
    p: argparse.ArgumentParser,
    ee_help: str = "the frame the CoM is estimated in",
    ee_required: bool = True,
) -> None:
    """--urdf, --ee-frame (None when optional and not given), --package-dir, --gravity."""
    p.add_argument("--urdf", required=True, help="the robot's URDF file")
    p.add_argument("--ee-frame", required=ee_required, default=None, help=ee_help)
    p.add_argument("--package-dir", action="append", default=None,
                   help="folder where package:// mesh URIs resolve (repeatable)")  # fmt: skip
    p.add_argument("--gravity", default="0,0,-9.81",
                   help="gravity GX,GY,GZ in the robot's base frame, m/s^2 (a wall, ceiling or "
                   "tilted mount)")  # fmt: skip


def add_subcommands(sub: argparse._SubParsersAction) -> None:
    """Add `estimate`, `plan-poses` and `plan-motion` to the `comgrasp` subparsers ``sub``."""
    _add_estimate(sub)
    _add_plan_poses(sub)
    add_plan_motion(sub, add_robot_args, _cmd_plan_motion)


def _add_estimate(sub: argparse._SubParsersAction) -> None:
    """`estimate`: the log, its windows, the noise, the result and the payload files."""
    from comgrasp_pin.robot_io.at_rest.windows import MAX_SPEED
    from comgrasp_pin.robot_io.log_files.joint_readers import DEFAULT_TOPIC
    from comgrasp_pin.robot_io.payload_files.payload import INERTIA_HELP

    est = sub.add_parser(
        "estimate",
        help="payload mass and CoM from a robot log (ROS 2 bag or CSV) before/after a grasp; "
        "--dynamic: the inertia too, from a motion",
        description="Estimate the held payload's mass and centre of mass from a robot log (a "
        "ROS 2 bag or a CSV of joint positions and efforts): static windows before and after "
        "the grasp, paired per pose; RESULT.json, a summary, and payload files in the flange "
        "frame for UR, Franka (libfranka, Desk), ROS 2, KUKA, ABB, MoveIt, the URDF and MJCF. "
        "With --dynamic: mass, CoM and inertia from a log of a "
        "motion (comgrasp plan-motion) played holding the payload, with their covariance.",
        formatter_class=_DEFAULTS,
    )
    add_robot_args(est)
    log = est.add_mutually_exclusive_group(required=True)  # the log: one of them
    log.add_argument("--bag", default=None, help="ROS 2 bag (folder, .db3 or .mcap) or ROS 1 .bag")
    log.add_argument("--csv", default=None,
                     help="CSV with time, J.position, J.effort columns, or a UR recording as "
                     "RTDE's record.py or ur_rtde writes it (timestamp, actual_q_i, "
                     "actual_current_i...)")  # fmt: skip
    est.add_argument("--topic", default=DEFAULT_TOPIC, help="sensor_msgs/msg/JointState topic")
    add_gains_args(est)
    est.add_argument("--before", default=None,
                     help="empty-arm windows T0:T1[,T0:T1...] (s from the log's start); one "
                     "pose's window may join spans, T0:T1+T2:T3 (the pose approached from both "
                     "sides: the mean of the spans' means cancels stuck friction, their spread "
                     "measures it, and what the mean leaves weighs the fit and widens the "
                     "interval)")  # fmt: skip
    est.add_argument("--after", default=None, help="holding windows, paired with --before")
    est.add_argument("--pose-errors", action="store_true",
                     help="errors that stay over a pose, vary between poses and are shared by "
                     "its joints (a servo's sag, a cable): the interval from the poses' spread "
                     "(block sandwich, Student's t of its dof; 2 poses or more)")  # fmt: skip
    est.add_argument("--auto", action="store_true",
                     help="find static windows and pair them by configuration")  # fmt: skip
    est.add_argument("--grasp-time", type=float, default=None,
                     help="with --auto: the grasp time (s) that splits the windows")  # fmt: skip
    est.add_argument("--max-speed", type=float, default=MAX_SPEED,
                     help="static threshold on every joint's speed (rad/s)")  # fmt: skip
    est.add_argument("--torque-std", type=float, default=None,
                     help="std of one AVERAGED torque reading, N m (per-sample std / sqrt(n "
                     "samples)); default: from the samples' spread")  # fmt: skip
    est.add_argument("--drift-std", type=float, default=0.0,
                     help="the torque sensor's drift, a random walk, N m/sqrt(s) (its data "
                     "sheet, or measured on a still arm); the drift between and across the "
                     "windows then enters the estimate's covariance (default 0: none)")  # fmt: skip
    est.add_argument("--method", default="lstsq", choices=("lstsq", "ipopt"),
                     help="closed-form least squares or CasADi + IPOPT")  # fmt: skip
    est.add_argument("--out", default="RESULT.json", help="the result JSON")
    est.add_argument(
        "--inertia",
        default="point",
        help=f"the inertia written where no motion determined it: {INERTIA_HELP}",
    )
    add_export_args(est)
    add_dynamic_args(est)
    add_wrench_args(est)
    est.set_defaults(func=_cmd_estimate)


def _add_plan_poses(sub: argparse._SubParsersAction) -> None:
    """`plan-poses`: K static measurement poses."""
    plan = sub.add_parser(
        "plan-poses",
        help="K static poses (limits, no self-collision) that best determine mass and 3-D CoM",
        description="Plan K static measurement poses for any arm from its URDF: within the "
        "joint limits, free of self-collision (Pinocchio with coal), chosen D-optimally so that "
        "mass and the full 3-D CoM are best determined; JSON, and a URScript movej program for "
        "a UR arm, with the CoM std they predict.",
        formatter_class=_DEFAULTS,
    )
    add_robot_args(plan)
    plan.add_argument("--k", type=int, default=3, help="number of poses")
    plan.add_argument("--start", default=None,
                      help="Q1,...,Qn: first pose; others are searched near it (rad)")  # fmt: skip
    plan.add_argument("--torque-std", type=float, default=0.005,
                      help="std of one averaged torque reading, predicted (N m)")  # fmt: skip
    plan.add_argument(
        "--mass", type=float, default=1.0, help="payload mass for the prediction (kg)"
    )
    plan.add_argument("--srdf", default=None,
                      help="SRDF whose disabled collisions are removed (default: the one "
                      "beside an example-robot-data URDF, else adjacent links)")  # fmt: skip
    plan.add_argument("--candidates", type=int, default=3000, help="random candidates searched")
    plan.add_argument("--sensor-frame", default=None,
                      help="plan for a wrist force/torque sensor at this URDF frame (comgrasp "
                      "estimate --wrench): the poses that best determine the mass, the CoM "
                      "and the sensor's six offsets (k >= 3)")  # fmt: skip
    plan.add_argument("--wrench-std", default="0.01,0.0005", metavar="F,T",
                      help="with --sensor-frame: std of one averaged wrench reading, N and "
                      "N m, for the prediction")  # fmt: skip
    plan.add_argument("--seed", type=int, default=0, help="random seed")
    plan.add_argument("--out", default="poses.json", help="the poses JSON")
    plan.add_argument("--urscript", default=None, help="also write a URScript movej program")
    plan.set_defaults(func=_cmd_plan)
