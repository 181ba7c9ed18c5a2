"""``comgrasp demo`` and ``comgrasp views``: an episode to watch, both cameras' overlays."""

from __future__ import annotations

import argparse
import os
from pathlib import Path

from comgrasp_pin.cli import camera_files
from comgrasp_pin.cli.args import OBJECTS, SEED, add_sensors_arg, out_dir, sentence
from comgrasp_pin.errors import InvalidInputError
from comgrasp_pin.geometry import tilt_difference_deg, tilt_from_level_deg
from comgrasp_pin.procedures import phases as ph

TILT = "tilt in the jaws, 0–90° from level"


def _rerun_path(text: str) -> Path:
    """``--rerun``'s value: a file name ending in .rrd."""
    path = Path(text)
    if path.suffix != ".rrd" or path.is_dir():
        raise argparse.ArgumentTypeError(f"must name a .rrd file, got {text!r}")
    return path


def _row(label: str, value: str) -> str:
    return f"  {label:<{len(TILT) + 2}}{value}"


def summary(result) -> list[str]:
    """The demo's printout of an ``EpisodeResult``: what happened, the estimate vs the truth."""
    kinds = [ph.phase_of(c) for _, c in result.phases]
    where = "delivered to the drop box" if result.success else "NOT delivered"
    lines = [f"object {result.scene.object}, method {result.method}: {where}",
             "phases (simulated time):"]  # fmt: skip
    lines += [f"  {t:6.1f} s  {caption}" for t, caption in result.phases]
    if result.method == "regrasp":
        trials = kinds.count(ph.TRIAL_GRASP)
        retries = trials - 1
        why = "the rod turned or fell, was put back and grasped again"
        lines.append(_row("trial grasps", f"{trials} " + ("(no retry)" if retries == 0 else
                     f"({retries} retr{'y' if retries == 1 else 'ies'}: {why})")))  # fmt: skip
        lines.append(_row("put-down and regrasp",
                          f"{'yes' if result.regrasped else 'no'}: {result.reason}"))  # fmt: skip
    else:
        lines.append(_row("grasp", result.reason))
    if result.trial is not None:
        t, s = result.trial, result.trial_score
        est, true = tilt_from_level_deg(t.theta), tilt_from_level_deg(s.theta_true)
        diff = tilt_difference_deg(t.theta, s.theta_true)
        error_mm = 1e3 * (s.pos_esti - s.pos_real)
        lines += [
            _row(TILT, f"{est:7.2f} deg (truth {true:.2f}, difference {diff:.2f})"),
            _row("CoM along the rod", f"{1e3 * s.pos_esti:7.1f} mm +- {2e3 * t.x_com_std:.1f} "
                 f"(2 sigma) (truth {1e3 * s.pos_real:.1f}, error {error_mm:+.1f})"),
            _row("mass", f"{t.mass_esti:7.3f} kg (truth {s.mass_real:.3f})"),
            _row("accuracy", f"{100 * s.accuracy:7.1f} %"),
        ]  # fmt: skip
    lines.append(_row("success", str(result.success)))
    return lines


def _cmd_demo(args: argparse.Namespace) -> int:
    from comgrasp_pin.experiments.trials import episode_config
    from comgrasp_pin.simulation.episode import run_episode

    if args.viewer and not os.environ.get("DISPLAY"):
        raise InvalidInputError(
            "--viewer needs a display (DISPLAY is not set); drop it for the video"
        )
    video = Path(args.out) / f"episode_{args.object}_{args.method}_seed{args.seed}.mp4"
    config = episode_config(sensors=args.sensors)
    result = run_episode(args.object, args.seed, args.method, config=config, video=video,
                         viewer=args.viewer, rerun=args.rerun)  # fmt: skip
    print(f"sensors {args.sensors}, seed {args.seed}")
    print("\n".join(summary(result)))
    print(f"video: {video}\nkey frames: {video.with_suffix('.png')}")
    if args.rerun is not None:
        print(f"rerun: {args.rerun} (open it with: rerun {args.rerun})")
    return 0


def _cmd_views(args: argparse.Namespace) -> int:
    from comgrasp_pin.simulation.views import save_camera_views

    if camera_files.wants_files(args):
        return camera_files.run(args)

    for path in save_camera_views(Path(args.out), args.object, args.seed):
        print(f"wrote {path}")
    return 0


def add_subcommands(sub: argparse._SubParsersAction) -> None:
    """Add ``demo`` and ``views`` to the subparsers ``sub``."""
    demo_help = "one episode with a video, key frames and the estimate vs the truth"
    demo = sub.add_parser("demo", help=demo_help, description=sentence(demo_help))
    demo.add_argument("--object", default="obj1", choices=OBJECTS, help="the rod (%(default)s)")
    demo.add_argument("--seed", type=SEED, default=0, help="scene seed, >= 0 (%(default)s)")
    demo.add_argument(
        "--method",
        default="regrasp",
        choices=("baseline", "regrasp"),
        help="regrasp planner or the geometric-centre grasp (%(default)s)",
    )
    demo.add_argument(
        "--out", type=out_dir, default="results/demo", help="output folder (%(default)s)"
    )
    demo.add_argument("--viewer", action="store_true", help="also show MuJoCo's viewer (display)")
    demo.add_argument("--rerun", type=_rerun_path, default=None, metavar="FILE.rrd",
                      help="also write a Rerun recording: both cameras' RGB, depth and point "
                      "clouds, the CoM estimate and truth, the joint torques, on a sim_time "
                      "timeline (the rerun extra: pip install 'comgrasp_pin[rerun]')")  # fmt: skip
    add_sensors_arg(demo)
    demo.set_defaults(func=_cmd_demo)

    views_help = "both camera views with mask, rectangle, axis, grasp point, CoM, legends"
    views = sub.add_parser("views", help=views_help, description=sentence(views_help))
    views.add_argument("--object", default="obj2", choices=OBJECTS, help="the rod (%(default)s)")
    views.add_argument("--seed", type=SEED, default=0, help="scene seed, >= 0 (%(default)s)")
    views.add_argument(
        "--out", type=out_dir, default="results/views", help="output folder (%(default)s)"
    )
    camera_files.add_arguments(views)  # --rgb --depth --camera-info: the user's own camera
    views.set_defaults(func=_cmd_views)


__all__ = ["add_subcommands", "summary"]
