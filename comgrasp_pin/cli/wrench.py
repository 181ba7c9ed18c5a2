"""`comgrasp estimate --wrench`: the payload from a wrist force/torque sensor (DESIGN.md 4e).

The options are added to `comgrasp estimate` (``add_wrench_args``); ``cli.robot`` hands the
parsed arguments here when ``--wrench`` is given. Without ``--dynamic``: mass, CoM and the
sensor's six offsets from the arm at rest in three or more orientations
(``robot_io.at_rest.wrench_static``). With ``--dynamic``: the ten inertial parameters from a motion
(``robot_io.from_motion.wrench_dynamic``), the log's joint torques used as well where it has them.
"""

from __future__ import annotations

import argparse

from comgrasp_pin.errors import InvalidInputError


def add_wrench_args(est: argparse.ArgumentParser) -> None:
    """The options of the wrench path, on the `estimate` parser."""
    g = est.add_argument_group(
        "from a wrist force/torque sensor (--wrench)",
        "the payload from the wrench a wrist sensor measured: at rest in three or more "
        "orientations (mass, CoM and the sensor's bias; no empty-arm run needed), or along a "
        "motion with --dynamic (the inertia too). --before/--after are not used",
    )
    g.add_argument("--wrench", action="store_true",
                   help="estimate from the wrench: a bag's geometry_msgs/msg/WrenchStamped, a "
                   "CSV's force_x..torque_z, or a UR recording's actual_TCP_force")  # fmt: skip
    g.add_argument("--sensor-frame", default=None,
                   help="the URDF frame the wrench is measured in (a CSV's or a UR "
                   "recording's; a bag's comes from its frame_id)")  # fmt: skip
    g.add_argument("--wrench-topic", default=None,
                   help="the WrenchStamped topic (default: the bag's only one)")  # fmt: skip
    g.add_argument("--tcp-frame", default=None,
                   help="UR recording: the URDF frame of the controller's TCP, where "
                   "actual_TCP_force is given (default tool0)")  # fmt: skip
    g.add_argument("--windows", default=None,
                   help="still windows T0:T1[,T0:T1...] (s), one per orientation (default: "
                   "found in the log, as --auto does)")  # fmt: skip
    g.add_argument("--wrench-std", default=None, metavar="F,T",
                   help="the sensor's repeatability between windows: force N, torque N m "
                   "(drift, hysteresis; its data sheet), added to each window's own "
                   "noise")  # fmt: skip
    g.add_argument("--wrench-drift", default=None, metavar="F,T[,RF,RT]",
                   help="the sensor's drift from its data sheet: random walk, N/sqrt(s) and "
                   "N m/sqrt(s), and optionally a rate fixed over the log, N/s and N m/s; "
                   "the windows then share it in their covariance (default: none)")  # fmt: skip
    g.add_argument("--keep-tool", action="store_true",
                   help="do not subtract the URDF's links beyond the sensor: estimate "
                   "everything the sensor carries (with nothing held: the tool itself, "
                   "for --tool)")  # fmt: skip
    g.add_argument("--tool", default=None, metavar="TOOL.json",
                   help="the RESULT.json of a --keep-tool run with nothing held: that tool, "
                   "with its covariance, is subtracted instead of the URDF's")  # fmt: skip


def _wrench_std(text: str | None) -> tuple[float, float] | None:
    if text is None:
        return None
    try:
        f, t = (float(v) for v in text.split(","))
    except ValueError:
        raise InvalidInputError(
            f"--wrench-std {text!r}: two numbers F,T expected (N, N m)"
        ) from None
    return f, t


def _drift(text: str | None) -> tuple[tuple[float, float], tuple[float, float]]:
    """((walk F, walk T), (rate F, rate T)) of ``--wrench-drift``; zeros without it."""
    if text is None:
        return (0.0, 0.0), (0.0, 0.0)
    try:
        v = [float(x) for x in text.split(",")]
    except ValueError:
        v = []
    if len(v) not in (2, 4) or not all(x >= 0 and x < float("inf") for x in v):
        raise InvalidInputError(
            f"--wrench-drift {text!r}: F,T or F,T,RF,RT expected, numbers >= 0 (N/sqrt(s), "
            "N m/sqrt(s), N/s, N m/s)"
        )
    rate = (v[2], v[3]) if len(v) == 4 else (0.0, 0.0)
    return (v[0], v[1]), rate


def read_wrench(args: argparse.Namespace, robot):
    """The WrenchLog of ``--bag`` or ``--csv`` (a project CSV or a UR recording)."""
    from comgrasp_pin.robot_io.log_files.wrench_sources import read_wrench_log

    if args.grasp_time is not None:
        raise InvalidInputError(
            "--wrench pairs no windows by a grasp time: give --before and --after, or the "
            "still windows at rest (--auto, --windows)"
        )
    if (args.before or args.after) and (args.auto or args.windows or args.dynamic):
        raise InvalidInputError(
            "--before/--after (the same poses empty and holding) or --auto/--windows (one "
            "log of orientations at rest) or --dynamic: one of them"
        )
    if args.auto and args.windows is not None:
        raise InvalidInputError("give --auto (find the still windows) or --windows, not both")
    path = args.bag if args.bag is not None else args.csv  # the parser: one of them
    return read_wrench_log(path, robot, args.sensor_frame, args.wrench_topic, args.topic,
                           args.tcp_frame)  # fmt: skip


def run_wrench(args: argparse.Namespace, robot) -> int:
    """Read the log, estimate at rest, write RESULT.json and the payload files (``--dynamic``
    is ``cli.wrench_dynamic``'s; ``--before``/``--after``: the wrench's change at the same
    poses, with the log's efforts where it has them, ``robot_io.at_rest.wrench_static``)."""
    from comgrasp_pin.cli.exports import finish_estimate
    from comgrasp_pin.robot_io.at_rest import parse_windows
    from comgrasp_pin.robot_io.at_rest.wrench_static import (
        estimate_wrench_pairs,
        estimate_wrench_static,
    )
    from comgrasp_pin.robot_io.results.result_file import tool_of_result

    log = read_wrench(args, robot)
    if args.before or args.after:
        if not (args.before and args.after):
            raise InvalidInputError("give both --before and --after windows (one pair per pose)")
        est = estimate_wrench_pairs(robot, log, parse_windows(args.before, "--before"),
                                    parse_windows(args.after, "--after"), args.max_speed,
                                    method=args.method)  # fmt: skip
        return finish_estimate(args, robot, est)
    windows = None if args.windows is None else parse_windows(args.windows, "--windows")
    walk, rate = _drift(args.wrench_drift)
    tool = None if args.tool is None else tool_of_result(args.tool, log.sensor_frame)
    est = estimate_wrench_static(robot, log, windows, args.max_speed,
                                 wrench_std=_wrench_std(args.wrench_std),
                                 subtract_tool=not args.keep_tool, tool=tool, drift_std=walk,
                                 drift_rate_std=rate)  # fmt: skip
    return finish_estimate(args, robot, est)
