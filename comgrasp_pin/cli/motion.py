"""`comgrasp plan-motion`: an excitation motion for a real arm (``planning.excitation``).

Registered by ``cli.robot.add_subcommands``, which loads the robot (``--urdf``,
``--ee-frame``, ``--package-dir``, ``--gravity``) and parses ``--start``.
"""

from __future__ import annotations

import argparse
import sys
import time

import numpy as np

from comgrasp_pin.errors import InvalidInputError

_DEFAULTS = argparse.ArgumentDefaultsHelpFormatter


_DESCRIPTION = (
    "Plan an excitation motion for any arm from its URDF: a rest-to-rest finite Fourier "
    "series about a start configuration, the wrist joints doing most of the work, within the "
    "joint position, velocity and acceleration limits, free of self-collision (Pinocchio with "
    "coal) and of the floor, chosen (random search, then CasADi + IPOPT) so that the stacked "
    "payload regressor's condition number is small: all ten inertial parameters of a held "
    "payload observable. Record the robot playing it empty and holding the payload, then "
    "`comgrasp estimate --dynamic`. Writes the motion as JSON, and on request as a CSV, a "
    "URScript servoj program and a ROS 2 JointTrajectory (YAML)."
)


def add_plan_motion(sub: argparse._SubParsersAction, add_robot_args, func) -> None:
    """Add `plan-motion` to the subparsers ``sub``; ``func`` runs it."""
    from comgrasp_pin.planning.excitation import ExcitationSettings

    d = ExcitationSettings()
    p = sub.add_parser(
        "plan-motion",
        help="an excitation motion (<= 20 s) that makes the payload's mass, CoM and inertia "
        "observable",
        description=_DESCRIPTION,
        formatter_class=_DEFAULTS,
    )
    add_robot_args(p)
    _add_motion_args(p, d)
    _add_search_args(p, d)
    _add_output_args(p)
    p.set_defaults(func=func)


def _add_motion_args(p: argparse.ArgumentParser, d) -> None:
    """The motion's length, start and limits (``d``: the default ``ExcitationSettings``)."""
    from comgrasp_pin.planning.excitation import MAX_DURATION_S, MIN_DURATION_S

    p.add_argument(
        "--duration",
        type=float,
        default=MAX_DURATION_S,
        help=f"length of the motion (s), {MIN_DURATION_S:g} to {MAX_DURATION_S:g}",
    )
    p.add_argument(
        "--start",
        default=None,
        help="Q1,...,Qn: start and end configuration (rad); default: the SRDF's "
        "home/default state, a UR arm's home, else the URDF's neutral",
    )
    limits = (  # (flag, default, help): the motion's limits, all floats
        ("--velocity-scale", d.velocity_scale,
         "share of the URDF's velocity limits the motion may use"),
        ("--acceleration", d.acceleration_limit,
         "acceleration limit of every joint (rad/s^2; URDFs carry none)"),
        ("--wrist-range", d.wrist_range_rad,
         "largest excursion of the last three joints from the start (rad)"),
        ("--arm-range", d.arm_range_rad,
         "largest excursion of the other joints from the start (rad)"),
        ("--min-height", d.min_height_m,
         "floor clearance of the wrist joints and the ee (m, above the base)"),
    )  # fmt: skip
    for flag, default, text in limits:
        p.add_argument(flag, type=float, default=default, help=text)
    p.add_argument(
        "--srdf",
        default=None,
        help="SRDF whose disabled collisions are removed (default: the one beside "
        "an example-robot-data URDF, else adjacent links)",
    )


def _add_search_args(p: argparse.ArgumentParser, d) -> None:
    """The random search and its IPOPT refinement (``d``: the default settings)."""
    p.add_argument("--candidates", type=int, default=d.n_random, help="random motions searched")
    p.add_argument(
        "--starts", type=int, default=d.n_starts, help="best random motions refined by IPOPT"
    )
    p.add_argument(
        "--iterations", type=int, default=d.max_iter, help="IPOPT iterations per refinement"
    )
    p.add_argument("--seed", type=int, default=0, help="random seed of the search")


def _add_output_args(p: argparse.ArgumentParser) -> None:
    """The files written: the JSON, and on request a CSV, URScript and a ROS 2 trajectory."""
    p.add_argument("--out", default="motion.json", help="the motion JSON")
    p.add_argument("--csv", default=None, help="also write time, J.position/velocity/acceleration")
    p.add_argument(
        "--urscript",
        default=None,
        help="also write a URScript program: movej to the start, servoj stream",
    )
    p.add_argument(
        "--servoj-period",
        type=float,
        default=0.008,
        help="servoj period t (s): 0.008 on CB3, 0.002 on e-Series",
    )
    p.add_argument(
        "--ros2",
        default=None,
        help="also write a trajectory_msgs/JointTrajectory YAML for a ROS 2 "
        "joint_trajectory_controller",
    )
    p.add_argument(
        "--ros2-period", type=float, default=0.02, help="time between the trajectory's points (s)"
    )


def run_plan_motion(args: argparse.Namespace, robot, start: np.ndarray | None) -> int:
    """Plan, write the files asked for, print a summary; 0 on success."""
    from comgrasp_pin.planning.excitation import ExcitationSettings, plan_excitation
    from comgrasp_pin.planning.measurement_poses import UR_JOINTS
    from comgrasp_pin.robot_io.payload_files import motion_files

    if args.urscript and robot.nq != UR_JOINTS:
        raise InvalidInputError(
            f"--urscript writes a servoj program for a {UR_JOINTS}-joint UR arm; this one has "
            f"{robot.nq} joints (use --ros2 or --csv)"
        )
    settings = ExcitationSettings(
        velocity_scale=args.velocity_scale, acceleration_limit=args.acceleration,
        wrist_range_rad=args.wrist_range, arm_range_rad=args.arm_range,
        min_height_m=args.min_height, n_random=args.candidates, n_starts=args.starts,
        max_iter=args.iterations,
    )  # fmt: skip
    t0 = time.perf_counter()

    def progress(text: str) -> None:
        print(f"  [{time.perf_counter() - t0:5.1f} s] {text}", file=sys.stderr, flush=True)

    m = plan_excitation(robot, args.duration, start, settings, args.seed, args.srdf, progress)
    written = [motion_files.write_json(m, args.out)]
    if args.csv:
        written.append(motion_files.write_csv(m, args.csv))
    if args.urscript:
        written.append(motion_files.write_urscript(m, args.urscript, period_s=args.servoj_period))
    if args.ros2:
        written.append(motion_files.write_ros2(m, args.ros2, period_s=args.ros2_period))
    print(summary(m))
    for path in written:
        print(f"wrote {path}")
    return 0


def summary(m) -> str:
    """A few lines on the motion: length, condition numbers, limits used, floor clearance."""
    names = m.joint_names
    iv, ia = int(np.argmax(m.peak_velocity_share)), int(np.argmax(m.peak_acceleration_share))
    return "\n".join([
        f"excitation motion for {m.ee_frame}: {m.duration_s:g} s ({m.settings.periods} periods "
        f"of {m.series.period_s:g} s, {m.series.harmonics} harmonics), planned in "
        f"{m.plan_time_s:.1f} s",
        f"  condition number of the payload regressor: {m.condition_number:.1f} (columns "
        f"scaled by a 1 kg payload {m.settings.typical_length_m:g} m out), "
        f"{m.condition_number_si:.1f} in SI units",
        f"  peak velocity {100 * m.peak_velocity_share[iv]:.0f} % of its limit ({names[iv]}), "
        f"peak acceleration {100 * m.peak_acceleration_share[ia]:.0f} % ({names[ia]})",
        f"  lowest wrist/ee point {m.min_height_m:.3f} m above the base (floor limit "
        f"{m.settings.min_height_m:g} m); no self-collision",
    ])  # fmt: skip
