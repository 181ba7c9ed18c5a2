"""`comgrasp accuracy`, `regrasp` and `reproduce`: the paper's experiments (``experiments``).

``add_experiment_args`` gives their options (output folder, objects, trials, seed, workers,
backend, sensors, resume, ...) to ``sweep`` as well; ``run_options`` turns them into the
runner's ``RunOptions``.

Exit status: 0; 2 for a ``ComGraspError`` (bad input, a results folder that cannot be
continued, a full disk: ``cli.main``); 1 when every run went to its end but trials ended in
an internal error (``exit_status``: a bug, not the world's failure; the message names them
and the files with their tracebacks, and ``--resume`` runs them again).
"""

from __future__ import annotations

import argparse
import os
import sys
from collections.abc import Callable

from comgrasp_pin.cli import args as cli_args
from comgrasp_pin.cli.args import OBJECTS, SEED, add_sensors_arg, sentence
from comgrasp_pin.errors import InvalidInputError
from comgrasp_pin.experiments.runner import DEFAULT_TRIAL_TIMEOUT_S
from comgrasp_pin.experiments.trials import MAX_TRIALS


def run_options(args: argparse.Namespace):
    """The experiment options of ``args`` as the runner's ``RunOptions``."""
    from comgrasp_pin.config import sensor_preset
    from comgrasp_pin.experiments.ray_backend import check_backend
    from comgrasp_pin.experiments.reproduce import PAPER_TRIALS, QUICK_TRIALS, RunOptions

    if args.overwrite and args.retry_failed:
        raise InvalidInputError("--retry-failed continues a run, --overwrite starts it again: "
                                "pass one of them")  # fmt: skip
    trials = args.trials
    if trials is None:
        trials = QUICK_TRIALS if getattr(args, "quick", False) else PAPER_TRIALS
    check_backend(args.backend, args.ray_address)
    workers = args.workers
    if workers is None:  # 0: as many as the Ray cluster has CPUs
        workers = 0 if args.ray_address else os.cpu_count() or 1
    noise = args.noise
    if noise is None:
        noise = sensor_preset(args.sensors).torque.noise_std
    return RunOptions(args.out, args.objects, trials, args.seed, workers,
                      args.resume or args.retry_failed, args.overwrite, noise,
                      args.estimator, args.retry_failed, args.backend,
                      args.ray_address, getattr(args, "second_seed", None),
                      args.sensors, args.trial_timeout)  # fmt: skip


def exit_status(command: str, run: Callable[[], None]) -> int:
    """Call ``run()`` (the command's runs and files); 0, or 1 with a message naming the
    trials that ended in an internal error (``internal_errors.fail_on_internal_errors``)."""
    from comgrasp_pin.errors import InternalTrialError
    from comgrasp_pin.experiments.internal_errors import fail_on_internal_errors

    try:
        with fail_on_internal_errors():
            run()
    except InternalTrialError as exc:
        print(f"comgrasp {command}: error: {exc}", file=sys.stderr)
        return 1
    return 0


def _cmd_experiment(args: argparse.Namespace) -> int:
    from comgrasp_pin.experiments import reproduce

    opts = run_options(args)

    def run() -> None:
        if args.command == "accuracy":
            reproduce.run_accuracy(opts)
            print(f"wrote {opts.out / 'accuracy.csv'}, accuracy.png, accuracy_table.md")
        elif args.command == "regrasp":
            reproduce.run_regrasp(opts)
            print(f"wrote {opts.out / 'regrasp.csv'}, regrasp.png, regrasp_table.md")
        else:
            path = reproduce.reproduce(opts)
            print(path.read_text())
            print(f"report written to {path}")

    return exit_status(args.command, run)


def add_experiment_args(p: argparse.ArgumentParser, default_out: str) -> None:
    """The options of the experiment commands (and ``sweep``), writing to ``default_out``."""
    p.add_argument("--out", type=cli_args.out_dir, default=default_out,
                   help="output folder (%(default)s)")  # fmt: skip
    p.add_argument("--objects", type=cli_args.object_list(OBJECTS), default=",".join(OBJECTS),
                   help="comma-separated, each once (%(default)s)")  # fmt: skip
    p.add_argument(
        "--trials",
        type=cli_args.int_at_least(1, MAX_TRIALS),
        default=None,
        help=f"trials per object, 1 to {MAX_TRIALS}: accuracy, grasps (each scored with ours "
        "and the paper's one-pose estimate); regrasp, scenes (each run by both methods, "
        "baseline and regrasp); a sweep runs them at every grid point (default 50, the "
        "paper's, 10 for a sweep; 3 with --quick)",
    )
    p.add_argument("--seed", type=SEED, default=0,
                   help="run seed, >= 0 (%(default)s)")  # fmt: skip
    p.add_argument("--workers", type=cli_args.int_at_least(1), default=None,
                   help="parallel processes, or Ray tasks in flight with --backend ray "
                   f"(default: one per core, {os.cpu_count() or 1} here; with --ray-address, "
                   "every CPU of the cluster)")  # fmt: skip
    p.add_argument("--backend", default="local", choices=("local", "ray"),
                   help="where trials run: local processes, or Ray tasks (needs the ray extra; "
                   "a local Ray of --workers CPUs unless --ray-address) (%(default)s)")  # fmt: skip
    p.add_argument(
        "--ray-address",
        default=None,
        help="an existing Ray cluster to run on (e.g. auto, ray://head:10001)",
    )
    p.add_argument("--noise", type=cli_args.float_at_least(0.0), default=None,
                   help="torque sensor noise per sample, N m, >= 0 (default: the sensor "
                   "preset's, 0.05; 0.1 for realistic_current)")  # fmt: skip
    p.add_argument("--estimator", default="ipopt", choices=("ipopt", "lstsq"),
                   help="the trial grasp's estimator: IPOPT with the side view's prior on the "
                   "CoM's distance from the rod's axis, or the closed-form least squares "
                   "(%(default)s)")  # fmt: skip
    add_sensors_arg(p)
    again = p.add_mutually_exclusive_group()
    again.add_argument("--resume", action="store_true",
                       help="continue the CSV in --out (same settings; trials and objects may "
                       "grow)")  # fmt: skip
    again.add_argument("--overwrite", action="store_true", help="start the CSV in --out again")
    p.add_argument(
        "--retry-failed",
        action="store_true",
        help="with --resume (implied): run again the trials that ended in an error (those "
        "that ended in an internal error, a bug, run again on any --resume)",
    )
    p.add_argument("--trial-timeout", type=cli_args.positive_seconds, metavar="S",
                   default=DEFAULT_TRIAL_TIMEOUT_S,
                   help="a trial running longer (s) is stopped (its worker process killed) and "
                   "recorded as failed (TrialTimeoutError); --retry-failed runs it again "
                   "(%(default)g; the longest measured trial took 27 s)")  # fmt: skip
    p.add_argument("--quick", action="store_true", help="a few-minute run (3 trials)")
    p.set_defaults(func=_cmd_experiment)


def add_subcommands(sub: argparse._SubParsersAction) -> None:
    """Add ``accuracy``, ``regrasp`` and ``reproduce`` to the subparsers ``sub``."""
    for name, help_text in (
        ("accuracy", "experiment 1: CoM accuracy against tilt (accuracy.csv, figure, table)"),
        ("regrasp", "experiment 2: pick-and-place success, baseline vs regrasp (regrasp.csv)"),
        (
            "reproduce",
            "both experiments and report.md (paper's sizes; --quick for minutes): "
            "realistic sensors, and ideal ones beside them for the comparison with the paper",
        ),
    ):
        p = sub.add_parser(name, help=help_text, description=sentence(help_text))
        add_experiment_args(p, f"results/{name}")
        if name == "reproduce":
            p.set_defaults(sensors="realistic")
            p.add_argument(
                "--second-seed",
                type=SEED,
                default=None,
                help="also run the accuracy experiment with this seed (in OUT/seed<S>) and "
                "report its calibration beside the first's",
            )
