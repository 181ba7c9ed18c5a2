"""The payload files of `comgrasp estimate`: their options and their writing, in one place.

``add_export_args(parser)`` adds ``--flange-frame``, every ``--export-*`` option and
``--export-anyway``. Every estimate mode ends in ``finish_estimate(args, robot, est)``: it
writes RESULT.json and the summary, and the payload files only for an ``identified`` verdict
(or ``--export-anyway``); it renders every file asked for and checks that each path can be
written before it writes any, so a URDF that cannot take the payload or an unwritable path
ends the command (exit status 2) with no payload file written.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from comgrasp_pin.errors import InvalidInputError, OutputError

EXPORTS: tuple[tuple[str, str], ...] = (
    ("--export-ur", "URScript set_target_payload line (UR)"),
    ("--export-franka", "JSON of libfranka setLoad's arguments (a load held by the hand)"),
    ("--export-ros2", "YAML: ur_msgs/SetPayload and franka_msgs/SetLoad requests"),
    ("--export-urdf", "the robot's URDF with a fixed link 'payload' on the ee frame"),
    ("--export-mjcf", "an MJCF <body name='payload'> with its <inertial>, to paste"),
    ("--export-franka-desk", "Franka Desk end-effector configuration JSON (the tool on the "
     "flange: mass, centerOfMass, inertia, transformation)"),
    ("--export-kuka", "KUKA KRL $LOAD line (KSS: mass, CoM mm, A B C deg, J)"),
    ("--export-kuka-sunrise", "KUKA Sunrise (LBR iiwa) Java LoadData statement"),
    ("--export-abb", "ABB RAPID PERS loaddata declaration"),
    ("--export-moveit", "YAML moveit_msgs/AttachedCollisionObject with the weight"),
)  # fmt: skip
"""(option, help), in writing order: every file asked for is made by ``_render``."""


def _render(option: str, robot, p, path: Path, urdf: Path) -> str:
    """The text of ``option``'s file (robot_io imported here: ``--help`` stays fast)."""
    from comgrasp_pin.file_checks import parse_xml, read_description
    from comgrasp_pin.robot_io.payload_files import controller_files as cf
    from comgrasp_pin.robot_io.payload_files import model_exports as me
    from comgrasp_pin.robot_io.payload_files.payload import T_flange_ee

    if option == "--export-moveit":
        text = read_description(urdf, "URDF", robot.package_dirs)
        link, T = me.urdf_link_of(robot, p.flange_frame, parse_xml(text, str(urdf), "URDF"))
        return cf.moveit_yaml(p, link, T)
    if option == "--export-urdf":
        return me.urdf_with_payload(robot, p, urdf, out_dir=path.parent)
    if option == "--export-mjcf":
        return me.mjcf_payload_body(p, robot)
    if option == "--export-franka-desk":
        desk = cf.franka_desk(p, T_flange_ee(robot, p.flange_frame))
        return json.dumps(desk, indent=2) + "\n"
    if option == "--export-franka":
        return json.dumps(cf.franka_load(p), indent=2) + "\n"
    texts = {"--export-ur": cf.urscript, "--export-ros2": cf.ros2_yaml, "--export-kuka":
             cf.krl_load, "--export-kuka-sunrise": cf.sunrise_load_data,
             "--export-abb": cf.rapid_loaddata}  # fmt: skip
    return texts[option](p)


def _dest(option: str) -> str:
    return option.removeprefix("--").replace("-", "_")


def add_export_args(parser: argparse.ArgumentParser) -> None:
    """``--flange-frame`` and every ``--export-*`` option (a file path each) on ``parser``."""
    g = parser.add_argument_group(
        "payload files",
        "the payload in each controller's format, in --flange-frame (units and frames: "
        "docs/robot.md, 'Payload files')",
    )
    g.add_argument("--flange-frame", default=None,
                   help="frame of the exported CoM (UR tool0, Franka panda_link8, KUKA/ABB "
                   "the flange); default: the ee frame")  # fmt: skip
    for option, text in EXPORTS:
        g.add_argument(option, default=None, metavar="FILE", help=text)
    g.add_argument("--export-anyway", action="store_true",
                   help="write the payload files although the verdict is not 'identified' "
                   "(default: refuse them, exit status 2); each file's header then states "
                   "the verdict and its reasons")  # fmt: skip


def wants_exports(args: argparse.Namespace) -> bool:
    """True when any ``--export-*`` option names a file."""
    return any(getattr(args, _dest(option), None) for option, _ in EXPORTS)


def _check_writable(path: Path, option: str) -> None:
    folder = path.parent
    if path.is_dir():
        raise OutputError(f"{option} {path}: a folder; give a file path")
    if not folder.is_dir():
        raise OutputError(f"{option} {path}: cannot write it, {folder} is not a folder")


def render_exports(args: argparse.Namespace, robot, payload, urdf_path=None) -> list:
    """Every payload file the ``--export-*`` options of ``args`` ask for, made, not written.

    Args:
        args: the parsed options (``add_export_args``).
        robot: the ``RobotModel`` the estimate was made with.
        payload: the ``Payload`` (flange frame) to write.
        urdf_path: the URDF that ``--export-urdf`` copies; default ``robot.urdf_path``.

    Returns:
        [(option, path, text)] in the order of ``EXPORTS``.

    Raises:
        InvalidInputError, OutputError: a file cannot be made (the URDF cannot take the
            payload, a frame is not in it) or written (a folder, a missing folder, two
            options naming one file).
    """
    urdf = Path(urdf_path if urdf_path is not None else robot.urdf_path)
    jobs = [(option, Path(getattr(args, _dest(option))))
            for option, _ in EXPORTS if getattr(args, _dest(option), None)]  # fmt: skip
    paths = [path.resolve() for _, path in jobs]
    if len(set(paths)) < len(paths):
        raise InvalidInputError("two --export-* options name the same file; give each its own")
    rendered = []
    for option, path in jobs:
        _check_writable(path, option)
        rendered.append((option, path, _render(option, robot, payload, path, urdf)))
    return rendered


def write_rendered(rendered: list) -> list[Path]:
    """Write the files of ``render_exports``; their paths."""
    for option, path, text in rendered:
        try:
            path.write_text(text)
        except OSError as exc:
            raise OutputError(f"{option}: cannot write {path}: {exc}") from None
    return [path for _, path, _ in rendered]


def write_exports(args: argparse.Namespace, robot, payload, urdf_path=None) -> list[Path]:
    """Make, check, then write every file the ``--export-*`` options ask for; their paths."""
    return write_rendered(render_exports(args, robot, payload, urdf_path))


def finish_estimate(args: argparse.Namespace, robot, est, extra=None) -> int:
    """Every estimate command's ending: RESULT.json, the summary, the payload files.

    The payload files are written only for an ``identified`` verdict (``trust``), or with
    ``--export-anyway``; each is made and checked before anything is written. Otherwise
    RESULT.json and the summary are written, the verdict's reasons printed, and the exit
    status is 2. ``extra(est)``: more files to write (a plot), their paths.

    Returns:
        The exit status: 0, or 2 where payload files were asked for and refused.
    """
    from comgrasp_pin.errors import NotIdentifiedError
    from comgrasp_pin.robot_io.payload_files.payload import payload_in_flange
    from comgrasp_pin.robot_io.results.report import summary
    from comgrasp_pin.robot_io.results.result_file import write_result

    rendered, refused, payload = [], None, None
    if wants_exports(args):
        try:
            payload = payload_in_flange(robot, est, args.flange_frame, args.inertia,
                                        anyway=args.export_anyway)  # fmt: skip
        except NotIdentifiedError as exc:
            refused = exc
        else:
            rendered = render_exports(args, robot, payload)
    write_result(est, args.out)
    print(summary(est))
    if payload is not None:
        c = 1e3 * payload.com_flange
        print(f"  CoM in {payload.flange_frame}: ({c[0]:.2f}, {c[1]:.2f}, {c[2]:.2f}) mm, "
              f"inertia: {payload.inertia_model}")  # fmt: skip
    written = [*write_rendered(rendered), *([] if extra is None else extra(est)), args.out]
    for path in written:
        print(f"wrote {path}")
    if refused is not None:
        print(f"comgrasp estimate: {refused}", file=sys.stderr)
        return 2
    return 0
