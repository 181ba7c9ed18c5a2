"""The `comgrasp` command line: `comgrasp --help` lists the subcommands."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path


def _cmd_check(args: argparse.Namespace) -> int:
    from comgrasp_pin.simulation.checks import run_checks

    report = run_checks(Path(args.out))
    print(json.dumps(report, indent=2))
    worst = report["pinocchio_vs_mujoco_worst"]
    ok = (
        worst["gravity_torque_Nm"] < 1e-6
        and worst["ee_position_m"] < 1e-9
        and report["torque_reading_vs_model_Nm"] < 1e-3
    )
    print(f"\nimages and check.json written to {args.out}; physics {'OK' if ok else 'MISMATCH'}")
    return 0 if ok else 1


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="comgrasp",
        description="Centre-of-mass-based grasp adaptation (UR5 + parallel gripper in MuJoCo).",
    )
    sub = parser.add_subparsers(dest="command", required=True)
    check = sub.add_parser(
        "check", help="render the scene from every camera and check Pinocchio against MuJoCo"
    )
    check.add_argument(
        "--out", default="results/check", help="output folder (default: %(default)s)"
    )
    check.set_defaults(func=_cmd_check)
    return parser


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    return args.func(args)


if __name__ == "__main__":
    sys.exit(main())
