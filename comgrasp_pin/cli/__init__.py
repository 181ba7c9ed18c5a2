"""The `comgrasp` command line: `comgrasp --help` lists the subcommands.

One module a command group, each adding its subcommands to the parser:

    world.py         check, scene: the simulated world
    experiments.py   accuracy, regrasp, reproduce: the paper's experiments
    sweep.py         sweep: an experiment over a grid of config values
    demo.py          demo, views (camera_files.py: views on the user's own camera's frames)
    robot.py         estimate, plan-poses, plan-motion: the real arm (dynamic.py: estimate
                     --dynamic; motion.py: plan-motion)
    args.py          the argument types and the options several commands share

Layer: the top. It may import every other part of the package; nothing in the package
imports it. Inside, the command modules import ``args`` (and ``sweep`` imports
``experiments``); none imports this ``__init__``. The heavy imports (MuJoCo, the solvers)
happen inside the commands, so ``comgrasp --help`` stays quick.

The robot side stands alone: building the parser imports neither MuJoCo, nor OpenCV, nor
matplotlib (``args.OBJECTS`` reads the rods' names from ``sim/objects.json``), and the
real-arm commands (``ROBOT_COMMANDS``) never do; ``estimate --dynamic --plot`` alone loads
matplotlib. For those, ``main`` builds the real-arm part of the parser only, so the
simulator's command modules are not even imported. ``tests/test_import_layers.py`` runs
each in a fresh process and checks.
"""

from __future__ import annotations

import argparse
import sys

from comgrasp_pin import __version__
from comgrasp_pin.cli import arm, live, robot
from comgrasp_pin.errors import ComGraspError

__all__ = ["ROBOT_COMMANDS", "build_parser", "main"]

ROBOT_COMMANDS = (
    "estimate",
    "plan-poses",
    "plan-motion",
    "identify-arm",
    "calibrate-gains",
    "live",
)
"""The real-arm commands (``robot``, ``arm``): logs and URDFs in, no simulator."""


def build_parser(robot_only: bool = False) -> argparse.ArgumentParser:
    """The `comgrasp` parser with every subcommand, or with ROBOT_COMMANDS only
    (``robot_only``: the simulator's command modules are then not imported)."""
    parser = argparse.ArgumentParser(
        prog="comgrasp",
        description="Centre-of-mass-based grasp adaptation (UR5 + parallel gripper in MuJoCo).",
    )
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    sub = parser.add_subparsers(dest="command", required=True)
    if not robot_only:
        from comgrasp_pin.cli import demo, experiments, sweep, world

        world.add_check(sub)
        experiments.add_subcommands(sub)  # accuracy, regrasp, reproduce
        demo.add_subcommands(sub)  # demo, views
        world.add_scene(sub)
        sweep.add_subcommand(sub)
    robot.add_subcommands(sub)  # estimate, plan-poses, plan-motion: the real-arm path
    arm.add_arm_subcommands(sub)  # identify-arm, calibrate-gains: an arm's own model, once
    live.add_subcommand(sub)  # live: a connected Franka, measured and told its load
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run `comgrasp` with ``argv`` (default: the process's); the exit status."""
    argv = sys.argv[1:] if argv is None else list(argv)
    robot_only = bool(argv) and argv[0] in ROBOT_COMMANDS  # `comgrasp -h ...`: every command
    args = build_parser(robot_only).parse_args(argv)
    try:
        return args.func(args)
    except ComGraspError as exc:
        print(f"comgrasp {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except OSError as exc:  # a file that cannot be written (full disk, no permission)
        print(f"comgrasp {args.command}: error: {exc}", file=sys.stderr)
        return 2
