"""`comgrasp check` and `comgrasp scene`: the simulated world, checked and written out."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from comgrasp_pin.cli.args import OBJECTS, SEED, out_dir, sentence


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


def _cmd_scene(args: argparse.Namespace) -> int:
    from comgrasp_pin.simulation.scene import save_world_xml

    path = save_world_xml(Path(args.out) / "world.xml", args.object, args.seed)
    print(f"wrote {path}: the workcell, the robot and {args.object} as one MJCF file")
    print(f"open it in MuJoCo's viewer:  python -m mujoco.viewer --mjcf={path}")
    return 0


def add_check(sub: argparse._SubParsersAction) -> None:
    """Add ``check`` to the subparsers ``sub``."""
    check_help = "render the scene from every camera and check Pinocchio against MuJoCo"
    check = sub.add_parser("check", help=check_help, description=sentence(check_help))
    check.add_argument(
        "--out", type=out_dir, default="results/check", help="output folder (%(default)s)"
    )
    check.set_defaults(func=_cmd_check)


def add_scene(sub: argparse._SubParsersAction) -> None:
    """Add ``scene`` to the subparsers ``sub``."""
    scene = sub.add_parser(
        "scene",
        help="write the assembled world (sim/scene.xml, the robot, a rod) as one MJCF file",
        description="Write the world the experiments run in, sim/scene.xml with the robot "
        "compiled from urdf/ and a rod on the table, as one MJCF file that MuJoCo's own viewer "
        "opens (python -m mujoco.viewer --mjcf=FILE). Keyframes 'home' and 'park' hold the "
        "arm's named poses.",
    )
    scene.add_argument("--object", default="obj2", choices=OBJECTS, help="the rod (%(default)s)")
    scene.add_argument("--seed", type=SEED, default=0, help="scene seed: where the rod lies")
    scene.add_argument(
        "--out", type=out_dir, default="results/scene", help="output folder (%(default)s)"
    )
    scene.set_defaults(func=_cmd_scene)
