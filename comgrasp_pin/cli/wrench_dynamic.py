"""`comgrasp estimate --wrench --dynamic`: the whole payload from a motion's wrench.

``cli.wrench`` hands the parsed arguments here. The loaded run's log (``--bag``/``--csv``),
an optional run of the same tool without the payload (``--empty-bag``/``--empty-csv``: the
tool's own parameters are fitted from it and subtracted; without it the URDF's links beyond
the sensor stand for the tool), the log's joint torques used as well where it has them
(``--arm-model`` for the arm's own torques, else the URDF's).
"""

from __future__ import annotations

import argparse

from comgrasp_pin.errors import InvalidInputError


def _empty_log(args: argparse.Namespace, robot):
    from comgrasp_pin.robot_io.log_files.wrench_sources import read_wrench_log

    path = args.empty_bag if args.empty_bag is not None else args.empty_csv  # at most one
    if path is None:
        return None
    return read_wrench_log(path, robot, args.sensor_frame, args.wrench_topic, args.topic,
                           args.tcp_frame)  # fmt: skip


def run_wrench_dynamic(args: argparse.Namespace, robot) -> int:
    """Read the logs, identify the payload, write RESULT.json and the payload files."""
    from comgrasp_pin.cli.dynamic import prior, window
    from comgrasp_pin.cli.exports import finish_estimate
    from comgrasp_pin.cli.wrench import read_wrench
    from comgrasp_pin.robot_io.from_motion.arm_model import load_arm_model
    from comgrasp_pin.robot_io.from_motion.wrench_dynamic import estimate_wrench_dynamic

    if args.windows is not None:
        raise InvalidInputError("--windows is for the static estimate; a motion takes --window")
    log = read_wrench(args, robot)
    arm = None if args.arm_model is None else load_arm_model(args.arm_model)
    est = estimate_wrench_dynamic(
        robot, log, window(args.window, "--window"), args.cutoff, prior(args.prior),
        arm_model=arm, empty_log=_empty_log(args, robot),
        empty_window=window(args.empty_window, "--empty-window"),
    )  # fmt: skip
    return finish_estimate(args, robot, est)
