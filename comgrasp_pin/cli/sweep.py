"""`comgrasp sweep`: an experiment over a grid of config values (``experiments.sweep``)."""

from __future__ import annotations

import argparse

from comgrasp_pin.cli.args import argument_type
from comgrasp_pin.cli.experiments import add_experiment_args, exit_status, run_options


def _param(text: str):
    from comgrasp_pin.experiments.sweep import parse_param

    return parse_param(text)


param = argument_type(_param, "param")
"""``NAME=V1,V2,...``: a config value by its dotted path or alias, and its values."""


def _cmd_sweep(args: argparse.Namespace) -> int:
    from comgrasp_pin.experiments.sweep import SWEEP_TRIALS, SweepOptions, run_sweep

    if args.trials is None and not args.quick:
        args.trials = SWEEP_TRIALS
    opts = SweepOptions(run_options(args), args.experiment, tuple(args.param))

    def run() -> None:
        run_sweep(opts)
        out = opts.run.out
        print((out / "sweep_table.md").read_text())
        print(f"wrote {out / 'sweep.csv'}, sweep_table.md and a figure per measure (sweep_*.png)")

    return exit_status("sweep", run)


def add_subcommand(sub) -> None:
    """The ``sweep`` subcommand, with the experiment commands' options."""
    p = sub.add_parser(
        "sweep",
        help="an experiment over a grid of config values (sweep.csv, heatmaps, table)",
        description="Run the accuracy or regrasp experiment at every combination of the "
        "--param values (the same trials and seeds at each), into one resumable sweep.csv with "
        "the swept values as columns, a figure per measure and sweep_table.md.",
    )
    add_experiment_args(p, "results/sweep")
    p.add_argument("--param", type=param, action="append", required=True,
                   help="NAME=V1,V2,...: a value of the config tree by its dotted path "
                   "(motion.grip_force, sensors.torque.noise_std, world.pad_friction, ...) or "
                   "an alias (grip_force, noise, friction, ...); repeat for a grid")  # fmt: skip
    p.add_argument("--experiment", default="accuracy", choices=("accuracy", "regrasp"),
                   help="which experiment runs at each grid point (%(default)s)")  # fmt: skip
    p.set_defaults(func=_cmd_sweep)
