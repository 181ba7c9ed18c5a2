"""`comgrasp accuracy`, `comgrasp regrasp` and `comgrasp reproduce`: runs, files, report."""

from __future__ import annotations

import json
import platform
import time
from collections.abc import Callable
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass, replace
from importlib import metadata
from pathlib import Path

from comgrasp_pin import __version__
from comgrasp_pin.config import sensor_preset
from comgrasp_pin.experiments import report
from comgrasp_pin.experiments.ray_backend import check_backend
from comgrasp_pin.experiments.report.sensors import sensors_comparison
from comgrasp_pin.experiments.report.wrist_sensor import wrist_sensor_table
from comgrasp_pin.experiments.reproduce_report import ReportSections, report_markdown
from comgrasp_pin.experiments.runner import (
    DEFAULT_TRIAL_TIMEOUT_S,
    kept_pool,
    read_rows,
    run_trials,
)
from comgrasp_pin.experiments.trials import (
    ACCURACY_COLUMNS,
    REGRASP_COLUMNS,
    REGRASP_TASK_METHODS,
    accuracy_trial,
    make_tasks,
    regrasp_trial,
    settings_summary,
)
from comgrasp_pin.simulation.objects import OBJECTS

ALL_OBJECTS = tuple(OBJECTS)
PAPER_TRIALS = 50
QUICK_TRIALS = 3


@dataclass(frozen=True)
class RunOptions:
    """What the experiment commands share.

    Attributes:
        out: output folder. objects: object names. trials: trials per object (and method).
        seed: the run's seed. workers: parallel processes (0 with Ray: one per CPU of
        the cluster). resume: continue the CSVs in
        ``out``. overwrite: start them again. noise: torque sensor noise (N m per sample).
        estimator: the trial grasp's estimator, "ipopt" (with the side view's axis prior)
        or "lstsq" (closed form). retry_failed: with ``resume``, run again the trials
        that ended in an error. backend: "local" (processes) or "ray" (Ray tasks, at most
        ``workers`` at a time); ray_address: an existing Ray cluster (None: a local Ray).
        second_seed: ``reproduce`` also runs the accuracy experiment with this seed (in
        ``out/seed<S>``) and reports its calibration and accuracy beside the first's, or
        None. sensors: the sensor preset (``config.sensor_preset``). trial_timeout_s: a
        trial running longer (s) is stopped and recorded as ``TrialTimeoutError``.
    """

    out: Path
    objects: tuple[str, ...] = ALL_OBJECTS
    trials: int = PAPER_TRIALS
    seed: int = 0
    workers: int = 1
    resume: bool = False
    overwrite: bool = False
    noise: float = 0.05
    estimator: str = "ipopt"
    retry_failed: bool = False
    backend: str = "local"
    ray_address: str | None = None
    second_seed: int | None = None
    sensors: str = "ideal"
    trial_timeout_s: float = DEFAULT_TRIAL_TIMEOUT_S


def run_settings(opts: RunOptions) -> dict:
    """Every setting of a run, recorded beside its CSV (``NAME.settings.json``)."""
    return {
        "seed": opts.seed,
        "noise": opts.noise,
        "estimator": opts.estimator,
        "sensors": opts.sensors,
        "config": settings_summary(opts.noise, opts.estimator, opts.sensors),
        "version": __version__,
        "objects": list(opts.objects),
        "trials": opts.trials,
        "backend": opts.backend,  # recorded, not compared: a local run may resume on Ray
        "trial_timeout_s": opts.trial_timeout_s,  # recorded, not compared (run_files.FREE)
    }


def _run(opts: RunOptions, fn, methods, name: str, columns) -> list[dict]:
    tasks = make_tasks(list(opts.objects), opts.trials, opts.seed, methods)
    for task in tasks:
        task["noise"] = opts.noise
        task["estimator"] = opts.estimator
        task["sensors"] = opts.sensors
    return run_trials(fn, tasks, opts.out / f"{name}.csv", columns, opts.workers, opts.resume,
                      opts.overwrite, name, opts.retry_failed, run_settings(opts),
                      opts.backend, opts.ray_address,
                      trial_timeout_s=opts.trial_timeout_s)  # fmt: skip


Draw = Callable[[Callable[[], object]], object]  # runs a job that writes report files


def _now(job: Callable[[], object]) -> object:
    return job()


def run_accuracy(opts: RunOptions, draw: Draw = _now) -> list[dict]:
    """Experiment 1: writes accuracy.csv (its settings beside it), accuracy.png and
    accuracy_table.md (by ``draw``: now, or beside the next part's trials)."""
    rows = _run(opts, accuracy_trial, ("trial",), "accuracy", ACCURACY_COLUMNS)

    def files() -> None:
        report.accuracy_figure(rows, opts.out / "accuracy.png")
        (opts.out / "accuracy_table.md").write_text(report.accuracy_table(rows) + "\n")

    draw(files)
    return rows


def run_regrasp(opts: RunOptions, draw: Draw = _now) -> list[dict]:
    """Experiment 2: writes regrasp.csv (its settings beside it), regrasp.png and
    regrasp_table.md (by ``draw``, as ``run_accuracy``)."""
    rows = _run(opts, regrasp_trial, REGRASP_TASK_METHODS, "regrasp", REGRASP_COLUMNS)

    def files() -> None:
        report.regrasp_figure(rows, opts.out / "regrasp.png")
        (opts.out / "regrasp_table.md").write_text(report.regrasp_table(rows) + "\n")

    draw(files)
    return rows


def _versions() -> dict:
    names = ["comgrasp_pin", "pin", "mujoco", "casadi", "numpy", "opencv-python-headless"]
    out = {"python": platform.python_version()}
    for name in names:
        try:
            out[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            out[name] = "not installed"
    return out


def _second_seed_section(opts: RunOptions, out: Path, draw: Draw) -> str:
    """The accuracy experiment again with ``opts.second_seed`` (its files in
    ``out/seed<S>``), and with ideal sensors too where the headline preset is another
    (``out/ideal/seed<S>``), as a report section: each one's calibration and accuracy
    table; "" without a second seed."""
    if opts.second_seed is None:
        return ""
    seed = opts.second_seed
    runs = [(opts.sensors, replace(opts, seed=seed, out=out / f"seed{seed}", second_seed=None))]
    if opts.sensors != "ideal":
        noise = sensor_preset("ideal").torque.noise_std
        runs.append(("ideal", replace(runs[0][1], sensors="ideal", noise=noise,
                                      out=out / "ideal" / f"seed{seed}")))  # fmt: skip
    parts = []
    for sensors, sub in runs:
        rows = run_accuracy(sub, draw)
        parts.append(f"""### `{sensors}` sensors (files in `{sub.out.relative_to(out)}/`)

{report.calibration_table(rows)}

{report.accuracy_table(rows)}
""")
    return f"""## A second seed: the accuracy experiment with seed {seed}

The same design and objects, other scenes and grasps; per sensor preset the calibration
first, then the accuracy per bin.

""" + "\n".join(parts)


def _ideal_section(opts: RunOptions, out: Path, acc: list, reg: list, draw: Draw) -> str:
    """Both experiments again with ideal sensors (the paper's world; files in ``out/ideal``)
    and a report section with the headline run beside them; "" when the headline is the
    ideal preset. Same seeds, objects and trials; the ideal preset's torque noise."""
    if opts.sensors == "ideal":
        return ""
    noise = sensor_preset("ideal").torque.noise_std
    sub = replace(opts, sensors="ideal", noise=noise, out=out / "ideal", second_seed=None)
    acc_ideal, reg_ideal = run_accuracy(sub, draw), run_regrasp(sub, draw)
    return f"""## Realistic sensors against ideal ones

This report's runs use the `{opts.sensors}` sensor preset (RealSense-class depth, its
calibration error, the torque sensors' offsets and drift, the gripper's model error; see
docs/experiments.md, "Sensors"). The same experiments with ideal sensors, the world the paper ran
in, are in `ideal/`: same seeds, same scenes, the paper's measuring procedure. The paper's
six objects; in brackets the 95 % interval (t for means, Wilson for rates).

{sensors_comparison(acc, reg, acc_ideal, reg_ideal, opts.sensors)}

### The wrist force/torque sensor with ideal sensors

{wrist_sensor_table(acc_ideal)}
"""


def _trial_minutes(folders: list[Path]) -> float:
    """The trials' own wall time in minutes: the ``wall_s`` of every row of the run's CSVs in
    ``folders`` (the run's, ``ideal/``, ``seed<S>/``), rows of an earlier, resumed part too."""
    paths = [folder / name for folder in folders for name in ("accuracy.csv", "regrasp.csv")]
    return sum(float(row.get("wall_s") or 0.0) for p in paths for row in read_rows(p)) / 60


def _run_folders(opts: RunOptions) -> list[Path]:
    """The folders a run writes its CSVs to: its own, ``ideal/``, ``seed<S>/`` and
    ``ideal/seed<S>/``."""
    seed = opts.second_seed
    seeds = [] if seed is None else [opts.out / f"seed{seed}", opts.out / "ideal" / f"seed{seed}"]
    return [opts.out, opts.out / "ideal", *seeds]


def _parts(meta: dict) -> str:
    """The minutes of each part of the run, the optional parts only where they ran."""
    text = f"accuracy {meta['accuracy_minutes']:.1f}, pick-and-place {meta['regrasp_minutes']:.1f}"
    for name, key in (
        ("the second seed", "second_seed_minutes"),
        ("ideal sensors", "ideal_minutes"),
    ):
        if meta[key] > 0.05:
            text += f", {name} {meta[key]:.1f}"
    return text + " min"


def reproduce(opts: RunOptions) -> Path:
    """Both experiments and ``report.md`` with figures, tables and the settings used.

    A part's figures and tables are drawn in a thread while the next part's trials run (the
    workers wait on nothing; a drawing error is raised at the end, as it would have been).
    """
    check_backend(opts.backend, opts.ray_address)
    opts.out.mkdir(parents=True, exist_ok=True)
    drawn: list[Future] = []
    with (
        kept_pool(opts.workers if opts.backend == "local" else 1),  # workers started once
        ThreadPoolExecutor(max_workers=1, thread_name_prefix="report") as drawing,
    ):

        def draw(job: Callable[[], object]) -> Future:
            drawn.append(drawing.submit(job))
            return drawn[-1]

        start = time.perf_counter()
        acc = run_accuracy(opts, draw)
        mid = time.perf_counter()
        calibration = draw(lambda: report.calibration_section(acc, opts.out))  # its PNG too
        reg = run_regrasp(opts, draw)
        end = time.perf_counter()
        second = _second_seed_section(opts, opts.out, draw)
        after_second = time.perf_counter()
        ideal = _ideal_section(opts, opts.out, acc, reg, draw)
        done = time.perf_counter()
        for job in drawn:
            job.result()
    meta = _run_meta(opts, (start, mid, end, after_second, done))
    (opts.out / "run.json").write_text(json.dumps(meta, indent=2, default=str))
    sections = ReportSections(acc, reg, calibration.result(), second, ideal)
    path = opts.out / "report.md"
    path.write_text(report_markdown(meta, opts.sensors, opts.noise, _parts(meta), sections))
    return path


def _run_meta(opts: RunOptions, times: tuple) -> dict:
    """What ``run.json`` records: the run's objects, trials, seed and workers, the minutes of
    each part from ``times`` (perf_counter at the start, after the accuracy run, the
    pick-and-place run, the second seed and the ideal sensors), versions and settings."""
    start, mid, end, after_second, done = times
    return {
        "objects": list(opts.objects), "trials_per_object": opts.trials, "seed": opts.seed,
        "workers": opts.workers,
        "backend": opts.backend,
        "accuracy_minutes": (mid - start) / 60, "regrasp_minutes": (end - mid) / 60,
        "second_seed_minutes": (after_second - end) / 60,
        "ideal_minutes": (done - after_second) / 60,
        "total_minutes": (done - start) / 60,
        "trial_core_minutes": _trial_minutes(_run_folders(opts)),
        "versions": _versions(),
        "settings": settings_summary(opts.noise, opts.estimator, opts.sensors),
    }  # fmt: skip
