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
    from comgrasp_pin.robot_io.wrench_sources import read_wrench_log

    if args.empty_bag is not None and args.empty_csv is not None:
        raise InvalidInputError("give one of --empty-bag and --empty-csv, not both")
    path = args.empty_bag if args.empty_bag is not None else args.empty_csv
    if path is None:
        return None
    return read_wrench_log(path, robot, args.sensor_frame, args.wrench_topic, args.topic,
                           args.tcp_frame)  # fmt: skip


def run_wrench_dynamic(args: argparse.Namespace, robot, write_json) -> int:
    """Read the logs, identify the payload, write RESULT.json and the payload files."""
    from comgrasp_pin.cli.dynamic import _prior, _window
    from comgrasp_pin.cli.exports import wants_exports, write_exports
    from comgrasp_pin.cli.wrench import read_wrench
    from comgrasp_pin.robot_io.arm_model import load_arm_model
    from comgrasp_pin.robot_io.payload import dynamic_payload_in_flange
    from comgrasp_pin.robot_io.wrench_dynamic import estimate_wrench_dynamic
    from comgrasp_pin.robot_io.wrench_dynamic_report import (
        wrench_dynamic_result_dict,
        wrench_dynamic_summary,
    )

    if args.windows is not None:
        raise InvalidInputError("--windows is for the static estimate; a motion takes --window")
    log = read_wrench(args, robot)
    arm = None if args.arm_model is None else load_arm_model(args.arm_model)
    est = estimate_wrench_dynamic(
        robot, log, _window(args.window, "--window"), args.cutoff, _prior(args.prior),
        arm_model=arm, empty_log=_empty_log(args, robot),
        empty_window=_window(args.empty_window, "--empty-window"),
    )  # fmt: skip
    written = []
    if wants_exports(args):
        payload = dynamic_payload_in_flange(robot, est, args.flange_frame)
        written = write_exports(args, robot, payload)
    write_json(args.out, wrench_dynamic_result_dict(est, robot.ee_frame))
    print(wrench_dynamic_summary(est, robot.ee_frame))
    for path in [*written, args.out]:
        print(f"wrote {path}")
    return 0
