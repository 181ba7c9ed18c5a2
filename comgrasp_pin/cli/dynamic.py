"""`comgrasp estimate --dynamic`: the whole payload (mass, CoM, inertia) from a motion's log.

The options are added to `comgrasp estimate` (``add_dynamic_args``); ``cli.robot`` hands the
parsed arguments here when ``--dynamic`` is given (DESIGN.md 4c).
"""

from __future__ import annotations

import argparse

from comgrasp_pin.errors import InvalidInputError


def add_dynamic_args(est: argparse.ArgumentParser) -> None:
    """The options of the dynamic estimate, on the `estimate` parser."""
    from comgrasp_pin.robot_io.from_motion.motion_signals import CUTOFF_HZ

    g = est.add_argument_group(
        "from a motion (--dynamic)",
        "the payload's mass, CoM and inertia from a log of an excitation motion (comgrasp "
        "plan-motion) played holding it; --before/--after are not used",
    )
    g.add_argument("--dynamic", action="store_true",
                   help="identify the inertia too, from a motion (the log's efforts, positions "
                   "and velocities where logged)")  # fmt: skip
    empty = g.add_mutually_exclusive_group()  # the empty run: one of them, or none
    empty.add_argument("--empty-bag", default=None,
                   help="the same motion with the empty arm (ROS 2 bag or ROS 1 .bag); "
                   "subtracted sample by sample. Without it the URDF's model stands for the "
                   "arm")  # fmt: skip
    empty.add_argument("--empty-csv", default=None, help="the empty-arm motion as a CSV")
    g.add_argument("--window", default=None, help="T0:T1, the motion's part of the log (s)")
    g.add_argument("--empty-window", default=None, help="T0:T1 of the empty-arm log (s)")
    g.add_argument("--cutoff", type=float, default=CUTOFF_HZ,
                   help="zero-phase low-pass cutoff for positions and efforts (Hz)")  # fmt: skip
    g.add_argument("--arm-model", default=None,
                   help="ARM.json of comgrasp identify-arm: the arm's own identified dynamics "
                   "stand for it, and the loaded run may be of any motion")  # fmt: skip
    g.add_argument("--validate", default=None, metavar="LOG",
                   help="a second log (CSV, UR recording or bag) of the same payload, any "
                   "motion: the payload found predicts its torques (with --arm-model or "
                   "the URDF's model); the log's held-out folds are checked anyway")  # fmt: skip
    g.add_argument("--plot", default=None,
                   help="PNG: per joint, the payload's measured torque against its held-out "
                   "prediction, and the verdict")  # fmt: skip
    g.add_argument("--prior", default=None,
                   help="a static estimate's RESULT.json (same ee frame): its mass and CoM "
                   "enter as a Gaussian prior")  # fmt: skip


def run_dynamic(args: argparse.Namespace, robot) -> int:
    """Read the logs, identify the payload, write RESULT.json and the payload files."""
    from comgrasp_pin import robot_io as rio
    from comgrasp_pin.cli.exports import finish_estimate
    from comgrasp_pin.cli.gains_args import gains_from_args
    from comgrasp_pin.robot_io.from_motion.arm_model import load_arm_model
    from comgrasp_pin.robot_io.from_motion.dynamic import check_on_log, estimate_payload_dynamic
    from comgrasp_pin.robot_io.results.report import plot_validation

    if args.before or args.after or args.auto:
        raise InvalidInputError("--dynamic uses the whole motion (or --window): leave out "
                                "--before, --after and --auto")  # fmt: skip
    gains = gains_from_args(args, robot)
    if args.arm_model is not None and (args.empty_bag or args.empty_csv):
        raise InvalidInputError("give an empty-arm run (--empty-csv/--empty-bag) or "
                                "--arm-model, not both")  # fmt: skip
    arm = None if args.arm_model is None else load_arm_model(args.arm_model)
    log = one_log(args.bag, args.csv, robot, args.topic, gains)
    empty = one_log(args.empty_bag, args.empty_csv, robot, args.topic, gains)
    est = estimate_payload_dynamic(
        robot, log, empty, window(args.window, "--window"),
        window(args.empty_window, "--empty-window"), args.cutoff, prior(args.prior),
        arm, None if gains is None else gains.cov, None if gains is None else gains.source,
    )  # fmt: skip
    if args.validate is not None:
        if empty is not None:
            raise InvalidInputError(
                "--validate predicts a second log with the arm model or the URDF's model: "
                "with an empty run of the first motion it has no arm torques of its own; "
                "use --arm-model (comgrasp identify-arm)"
            )
        second = rio.read_log(args.validate, robot.joint_names, args.topic, None, gains)
        est = check_on_log(robot, est, second, arm, args.cutoff)

    def plot(est) -> list:
        return [plot_validation(est, robot.joint_names, args.plot)] if args.plot else []

    return finish_estimate(args, robot, est, plot)


def one_log(bag, csv, robot, topic, gains=None):
    """The log of a ``--bag``/``--csv`` pair of options, read with ``gains``; None if neither.

    The parser lets one of the pair at most be given (a mutually exclusive group).
    """
    from comgrasp_pin.robot_io.log_files import read_bag, read_csv

    if bag is not None:
        return read_bag(bag, robot.joint_names, topic, None, gains)
    return None if csv is None else read_csv(csv, robot.joint_names, gains)


def window(text: str | None, option: str):
    """The one window T0:T1 of ``option``, or None."""
    if text is None:
        return None
    from comgrasp_pin.robot_io.at_rest import parse_windows

    windows = parse_windows(text, option)
    if len(windows) != 1:
        raise InvalidInputError(f"{option} takes one window T0:T1, got {len(windows)}")
    return windows[0]


def prior(path: str | None):
    """The static estimate in a RESULT.json as a prior ((m, c), cov), or None."""
    from comgrasp_pin.robot_io.results.result_file import prior_of_result

    return None if path is None else prior_of_result(path)
