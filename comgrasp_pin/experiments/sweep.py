"""`comgrasp sweep`: an experiment over a grid of config values, in one resumable CSV.

    comgrasp sweep --param grip_force=10,15,20 --param noise=0.02,0.05,0.1 \\
        --experiment accuracy --objects obj1,obj2 --trials 5 --out results/sweep

Each ``--param`` names a number of the ``EpisodeConfig`` tree by its dotted path or an alias
(``config.paths``) and lists its values; the grid is their product. Every grid point runs the
same trials with the same seeds (the scenes and sensor noise of trial k are the same at every
point: common random numbers, so differences between points are the settings', not luck's).
``sweep.csv`` holds one row per trial with the swept values as its first columns; the runner
appends rows as they finish and ``--resume`` continues it (``sweep.settings.json`` records
the grid and every point's whole config tree). Per measure (``MEASURES``): a figure (one
swept value: a line with 95 % intervals; two: a heatmap) and ``sweep_table.md``.

The accuracy experiment places each grasp at a lever in units of the jaws' holding lever
(``experiments.design``), which grows with ``motion.grip_force`` and ``world.pad_friction``:
sweeping those moves the grasp with them (the target tilts stay), as the design intends.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import asdict, dataclass

import numpy as np

from comgrasp_pin.config import paths as config_paths
from comgrasp_pin.errors import InvalidInputError
from comgrasp_pin.experiments.internal_errors import is_internal_error
from comgrasp_pin.experiments.reproduce import RunOptions, run_settings
from comgrasp_pin.experiments.runner import KEY_COLUMNS, run_trials
from comgrasp_pin.experiments.stats import coverage, mean_ci, wilson_interval, z_scores
from comgrasp_pin.experiments.trials import (
    ACCURACY_COLUMNS,
    REGRASP_COLUMNS,
    REGRASP_TASK_METHODS,
    accuracy_trial,
    episode_config,
    make_tasks,
    regrasp_trial,
)

EXPERIMENTS = {
    "accuracy": (accuracy_trial, ("trial",), ACCURACY_COLUMNS),
    "regrasp": (regrasp_trial, REGRASP_TASK_METHODS, REGRASP_COLUMNS),
}
MEASURES = {
    "accuracy": "mean accuracy (%)",
    "success": "success rate (%)",
    "coverage": "coverage of the 95 % interval (%)",
}
"""What each grid point is summarised by. accuracy: 1 - 5 |pos_esti - pos_real| / l, mean
over the trial grasps (t interval). success: accuracy experiment, trial grasps that kept the
rod and gave an estimate; regrasp experiment, the regrasp method's rods in the drop box
(Wilson interval). coverage: share of trial grasps whose truth lies within pos_esti +- 1.96
pos_std (Wilson interval; 95 % if the stated std is right)."""
Z_95 = 1.96
SWEEP_TRIALS = 10
"""Trials per object, method and grid point when ``--trials`` is not given."""


@dataclass(frozen=True)
class SweepOptions:
    """A sweep: the experiment's options, which experiment, and the swept values.

    Attributes:
        run: out, objects, trials, seed, workers, backend, ... (``RunOptions``).
        experiment: "accuracy" or "regrasp".
        params: ((dotted path, values), ...), each path once, each list non-empty.
    """

    run: RunOptions
    experiment: str
    params: tuple[tuple[str, tuple[float, ...]], ...]


def parse_param(text: str) -> tuple[str, tuple[float, ...]]:
    """``NAME=V1,V2,...`` as (dotted path, values).

    Raises:
        InvalidInputError: no ``=``, an unknown name (the valid ones listed), an empty list,
            a value that is not a finite number, or a value given twice.
    """
    name, sep, listed = text.partition("=")
    if not sep or not name.strip():
        raise InvalidInputError(f"needs NAME=V1,V2,..., got {text!r}")
    path = config_paths.resolve(name.strip())
    parts = [p.strip() for p in listed.split(",")]
    if not listed.strip() or not all(parts):
        raise InvalidInputError(f"{name} needs a comma-separated list of numbers, got {text!r}")
    try:
        values = tuple(float(p) for p in parts)
    except ValueError:
        raise InvalidInputError(f"{name}: values must be numbers, got {listed!r}") from None
    if not all(math.isfinite(v) for v in values):
        raise InvalidInputError(f"{name}: values must be finite, got {listed!r}")
    if len(set(values)) < len(values):
        raise InvalidInputError(f"{name}: a value is listed more than once in {listed!r}")
    return path, values


def check_params(params) -> tuple[tuple[str, tuple[float, ...]], ...]:
    """The params, each path once and every value accepted by the config tree.

    Raises:
        InvalidInputError: no param, a path given twice, a value the tree refuses.
    """
    params = tuple((path, tuple(values)) for path, values in params)
    if not params:
        raise InvalidInputError(f"a sweep needs at least one --param; {config_paths.valid_names()}")
    paths = [path for path, _ in params]
    twice = sorted({p for p in paths if paths.count(p) > 1})
    if twice:
        raise InvalidInputError(f"--param {twice} given more than once")
    for point in grid(params):
        config_paths.with_values(episode_config(), point)
    return params


def grid(params) -> list[dict[str, float]]:
    """Every combination of the swept values: [{path: value}, ...], the last param fastest."""
    paths = [path for path, _ in params]
    return [dict(zip(paths, combo)) for combo in itertools.product(*(v for _, v in params))]


def _point_value(path: str, value: float) -> float | int:
    """The value as the config holds it (an int for integer settings): one text in the CSV."""
    return int(value) if config_paths.numeric_paths()[path] is int else float(value)


def sweep_tasks(opts: SweepOptions) -> list[dict]:
    """Every grid point's trials: the experiment's tasks with the point's values as columns
    and as ``overrides`` of the config."""
    _, methods, _ = EXPERIMENTS[opts.experiment]
    base = make_tasks(list(opts.run.objects), opts.run.trials, opts.run.seed, methods)
    tasks = []
    for point in grid(opts.params):
        point = {p: _point_value(p, v) for p, v in point.items()}
        for task in base:
            tasks.append({**point, **task, "noise": opts.run.noise,
                          "estimator": opts.run.estimator, "sensors": opts.run.sensors,
                          "overrides": point})  # fmt: skip
    return tasks


def sweep_settings(opts: SweepOptions) -> dict:
    """Every setting of the sweep: the run's, the grid, and each point's whole config tree."""
    base = episode_config(opts.run.noise, opts.run.estimator, opts.run.sensors)
    points = [
        {"values": point, "config": asdict(config_paths.with_values(base, point))}
        for point in grid(opts.params)
    ]
    return {**run_settings(opts.run), "experiment": opts.experiment,
            "params": {path: list(values) for path, values in opts.params},
            "points": points}  # fmt: skip


def run_sweep(opts: SweepOptions) -> list[dict]:
    """Run the sweep; write sweep.csv, a figure per measure and sweep_table.md; all rows."""
    from comgrasp_pin.experiments.report.sweep_plot import sweep_figures

    if opts.experiment not in EXPERIMENTS:
        raise InvalidInputError(f"experiment must be one of {tuple(EXPERIMENTS)}")
    params = check_params(opts.params)
    fn, _, columns = EXPERIMENTS[opts.experiment]
    paths = [path for path, _ in params]
    r = opts.run
    rows = run_trials(fn, sweep_tasks(opts), r.out / "sweep.csv", [*paths, *columns], r.workers,
                      r.resume, r.overwrite, "sweep", r.retry_failed, sweep_settings(opts),
                      r.backend, r.ray_address, keys=(*paths, *KEY_COLUMNS),
                      trial_timeout_s=r.trial_timeout_s)  # fmt: skip
    table = summarise(rows, params, opts.experiment)
    sweep_figures(table, params, r.out, MEASURES)
    (r.out / "sweep_table.md").write_text(markdown_table(table, params) + "\n")
    return rows


def _float(value) -> float:
    try:
        return float(value)
    except (TypeError, ValueError):
        return float("nan")


def _rate(successes: int, n: int) -> tuple[float, float, float, int]:
    if n == 0:
        return (float("nan"),) * 3 + (0,)
    lo, hi = wilson_interval(successes, n)
    return successes / n, lo, hi, n


def point_measures(rows: list[dict], experiment: str) -> dict[str, tuple[float, ...]]:
    """(value, 95 % low, 95 % high, n) of each of MEASURES over one grid point's rows; a
    trial that ended in an internal error (a bug, not an outcome) is in none of them."""
    rows = [row for row in rows if not is_internal_error(row)]
    if experiment == "regrasp":
        rows = [row for row in rows if row.get("method") == "regrasp"]
        ok = [row for row in rows if not row.get("error")]
        success = _rate(sum(_float(r["success"]) == 1 for r in ok), len(rows))
    else:
        ok = [row for row in rows if not row.get("error")]
        success = _rate(sum(np.isfinite(_float(r["accuracy"])) for r in ok), len(rows))
    acc = mean_ci([100 * _float(r["accuracy"]) for r in ok])
    z = z_scores(*(np.array([_float(r[c]) for r in ok]) for c in
                   ("pos_esti_m", "pos_real_m", "pos_std_m")))  # fmt: skip
    z = z[np.isfinite(z)]
    inside = int(round(coverage(z, Z_95) * len(z))) if len(z) else 0
    return {
        "accuracy": (acc.mean, acc.lo, acc.hi, acc.n),
        "success": tuple(100 * x for x in success[:3]) + (success[3],),
        "coverage": tuple(100 * x for x in _rate(inside, len(z))[:3]) + (len(z),),
    }


def summarise(rows: list[dict], params, experiment: str) -> list[tuple[dict, dict]]:
    """[(grid point, point_measures), ...] in grid order."""
    out = []
    for point in grid(params):
        mine = [row for row in rows
                if all(_float(row[p]) == _float(v) for p, v in point.items())]  # fmt: skip
        out.append((point, point_measures(mine, experiment)))
    return out


def _cell(measure: tuple[float, ...]) -> str:
    value, lo, hi, n = measure
    if not n or not math.isfinite(value):
        return "–"
    interval = f" [{lo:.1f}, {hi:.1f}]" if math.isfinite(lo) else ""
    return f"{value:.1f}{interval} (n={n})"


def markdown_table(table: list[tuple[dict, dict]], params) -> str:
    """One row per grid point: its values, then each measure with its 95 % interval."""
    paths = [path for path, _ in params]
    head = [*paths, *MEASURES.values()]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for point, measures in table:
        cells = [f"{point[p]:g}" for p in paths] + [_cell(measures[m]) for m in MEASURES]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)
