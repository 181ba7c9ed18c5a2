"""Running many independent trials that survive failures, interruptions and crashes.

Every finished trial is appended to the CSV at once, whole (``run_files.RowAppender``), so an
interrupted run loses nothing and ``resume=True`` continues where it stopped; the run's
settings are kept beside the CSV and a resumed run must match them. A trial that raises a
``ComGraspError`` (the world or the harness failed it) is recorded with its error and does
not stop the run; ``retry_failed=True`` runs those again. A trial that raises anything else
(a bug) is recorded as an internal error (``workers``: its row's error begins ``internal
error:``, its traceback goes to ``NAME.tracebacks.txt`` beside the CSV); the run goes on,
the report never counts it as a failed trial, ``resume=True`` runs it again (with or without
``retry_failed``: it has no outcome to keep), and a command run within
``internal_errors.fail_on_internal_errors`` ends with ``InternalTrialError`` (exit
status 1) naming it.
``backend="ray"`` runs the same trials as Ray tasks (``ray_backend``), the driver appending
rows as they finish. Locally, trials run in worker processes (``workers``: spawned, each
with its own MuJoCo and OpenGL context), one per worker for a serial run with a time limit:
a trial that kills its worker is recorded as failed (``WorkerDiedError``), one that runs
past ``trial_timeout_s`` has its worker killed and is recorded as ``TrialTimeoutError``;
the worker is replaced and the run goes on. Only a serial run without a time limit calls
the trial in this process (a debugger, closures), where a crash or a hang ends the run.
A row that cannot be written (full disk) stops the run with ``OutputError``; the rows
before it stay intact.
"""

from __future__ import annotations

import csv
import multiprocessing
import os
import pickle
from collections import Counter
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import ProcessPoolExecutor
from contextlib import contextmanager
from pathlib import Path

from tqdm import tqdm

from comgrasp_pin import validate
from comgrasp_pin.errors import InvalidInputError, ResumeError
from comgrasp_pin.experiments import internal_errors, run_files
from comgrasp_pin.experiments.ray_backend import check_backend, ensure_ray, run_on_ray
from comgrasp_pin.experiments.run_files import RowAppender
from comgrasp_pin.experiments.threads import worker_threads
from comgrasp_pin.experiments.workers import (
    WORKER_DIED,  # noqa: F401 (callers and tests read it from the runner)
    WorkerSet,
    exit_with_parent,
    safe_call,
)

KEY_COLUMNS = ("object", "trial", "method")
DEFAULT_TRIAL_TIMEOUT_S = 600.0
"""The experiment commands' time limit per trial (s). The longest trial in docs/results
(4891 rows: accuracy, regrasp, sweeps, sensitivity; ideal and realistic sensors) took 27 s,
the 99th percentile 12.5 s, the median 1.7 s: 600 s is 22 times the longest, room for a
machine several times slower or more loaded, and still ends a hung trial within minutes."""


def read_rows(csv_path: Path) -> list[dict]:
    """All rows of a results CSV (empty when the file does not exist), its own header."""
    if not csv_path.exists():
        return []
    with csv_path.open(newline="") as f:
        return list(csv.DictReader(f))


def _kept_rows(csv_path: Path, columns: list[str], resume: bool, overwrite: bool,
               retry_failed: bool, settings: dict | None) -> list[dict]:  # fmt: skip
    """The rows of an earlier run to keep; the CSV and its settings made ready to append."""
    fresh = overwrite or not csv_path.exists() or csv_path.stat().st_size == 0
    if fresh:
        rows, rewrite = [], True
        if settings is not None:
            run_files.write_settings(csv_path, settings)
        internal_errors.tracebacks_path(csv_path).unlink(missing_ok=True)  # an earlier run's
    elif not resume:
        raise ResumeError(
            f"{csv_path} already holds results: pass resume (--resume) to continue it or "
            "overwrite (--overwrite) to start again"
        )
    else:
        rows, repaired = run_files.read_results(csv_path, columns)
        if settings is not None:
            run_files.write_settings(csv_path, run_files.check_settings(csv_path, settings))
        # an internal error is no outcome: its trial runs again, retry_failed or not
        again = internal_errors.is_internal_error if not retry_failed else lambda r: r.get("error")
        kept = [row for row in rows if not again(row)]
        rewrite = repaired or len(kept) < len(rows)
        rows = kept
    if rewrite:
        run_files.rewrite(csv_path, columns, rows)
    return rows


def run_trials(
    fn: Callable[[dict], dict],
    tasks: Sequence[dict],
    csv_path: Path,
    columns: Sequence[str],
    workers: int = 1,
    resume: bool = False,
    overwrite: bool = False,
    desc: str = "trials",
    retry_failed: bool = False,
    settings: dict | None = None,
    backend: str = "local",
    ray_address: str | None = None,
    keys: Sequence[str] = KEY_COLUMNS,
    trial_timeout_s: float | None = None,
) -> list[dict]:
    """Run ``fn(task)`` for every task not already in ``csv_path``; return all rows.

    Args:
        fn: a picklable top-level function returning a dict of result columns.
        tasks: dicts with at least the KEY_COLUMNS, each key once; their items are copied
            into the row.
        csv_path: results file; rows are appended as trials finish.
        columns: the CSV header (an ``error`` column is added).
        workers: worker processes, or Ray tasks in flight (0: as many as the Ray cluster
            has CPUs). 1 without ``trial_timeout_s``: in this process.
        resume: keep the rows already in ``csv_path`` and run only the missing tasks.
        overwrite: start a new file even if one exists.
        retry_failed: with ``resume``, run again the tasks whose rows hold an error (those
            of an internal error run again in any case).
        settings: every setting of the run, recorded beside the CSV; with ``resume`` the
            recorded ones must match (``run_files.check_settings``).
        backend: "local" (this process or ``workers`` processes) or "ray" (Ray tasks, at
            most ``workers`` at a time, on ``ray_address`` or a local Ray).
        keys: the columns that identify a trial (each task once).
        trial_timeout_s: a trial running longer (s) is stopped (its worker killed) and
            recorded as ``TrialTimeoutError``; None: no limit.

    Returns:
        Every row, the CSV's order; those of trials that ended in an internal error too
        (``internal_errors.is_internal_error``), which are also reported to the open
        ``internal_errors.fail_on_internal_errors`` blocks.

    Raises:
        ResumeError: the CSV cannot be continued (see ``run_files``).
        OutputError: a row cannot be written; the run stopped, earlier rows intact.
    """
    columns = [*columns, "error"] if "error" not in columns else list(columns)
    key = _key_of(tuple(keys))
    repeated = sorted(k for k, n in Counter(key(t) for t in tasks).items() if n > 1)
    if repeated:
        raise InvalidInputError(f"tasks {repeated[:5]} are listed more than once")
    check_backend(backend, ray_address)
    if trial_timeout_s is not None:
        validate.number(trial_timeout_s, "trial_timeout_s", low=0.0, low_open=True)
    execute = _executor(backend, workers, ray_address, trial_timeout_s)
    if execute is not _run_serial and backend == "local":
        _check_picklable(fn)
    with run_files.run_lock(Path(csv_path)):
        rows = _kept_rows(Path(csv_path), columns, resume, overwrite, retry_failed, settings)
        rows = _run_missing(fn, tasks, rows, Path(csv_path), columns, execute, desc, tuple(keys))
    internal_errors.found(Path(csv_path), [(_name(row, keys), row["error"]) for row in rows
                                           if internal_errors.is_internal_error(row)])  # fmt: skip
    return rows


def _key_of(keys: tuple[str, ...]) -> Callable[[dict], tuple[str, ...]]:
    return lambda row: tuple(str(row.get(k, "")) for k in keys)


def _name(row: dict, keys: Sequence[str]) -> str:
    """A trial's name in messages: ``object=obj1, trial=2, method=m``."""
    return ", ".join(f"{k}={row.get(k, '')}" for k in keys)


def _check_picklable(fn) -> None:
    try:
        pickle.dumps(fn)
    except (pickle.PicklingError, AttributeError, TypeError) as exc:
        raise InvalidInputError(
            f"the trial function {fn!r} cannot be sent to a worker process ({exc}): pass a "
            "module's top-level function, or run it in this process (workers=1, "
            "trial_timeout_s=None)"
        ) from None


def _executor(backend: str, workers: int, ray_address: str | None, timeout_s: float | None):
    """``execute(fn, todo, record)`` for the backend."""
    if backend == "ray":
        ray = ensure_ray(workers, ray_address)  # before any file is touched: none if it fails
        workers = workers or max(1, int(ray.cluster_resources().get("CPU", 1)))
        return lambda fn, todo, record: run_on_ray(safe_call, fn, todo, workers, record,
                                                   ray_address, timeout_s)  # fmt: skip
    if workers <= 1 and timeout_s is None:
        return _run_serial
    return lambda fn, todo, record: _run_local(fn, todo, max(1, workers), record, timeout_s)


def _run_serial(fn, todo, record) -> None:
    for task in todo:
        record(safe_call(fn, task))


def _run_local(fn, todo, workers: int, record, timeout_s: float | None) -> None:
    """All of ``todo`` on ``workers`` worker processes: the ``kept_pool``'s, if it has as
    many, else a set of this run's own."""
    kept = _KEPT.get(workers)
    if kept is not None:
        kept.run(safe_call, fn, todo, record, timeout_s)
        return
    with WorkerSet(workers) as own:
        own.run(safe_call, fn, todo, record, timeout_s)


def _run_missing(fn, tasks, rows: list[dict], csv_path: Path, columns: list[str],
                 execute, desc: str, keys: tuple[str, ...]) -> list[dict]:  # fmt: skip
    """Run the tasks that have no row in ``rows`` yet, appending theirs; all rows. An
    internal error's traceback goes to ``internal_errors.tracebacks_path`` before its row."""
    key = _key_of(keys)
    done = {key(row) for row in rows}
    todo = [task for task in tasks if key(task) not in done]
    bar = tqdm(total=len(tasks), initial=len(tasks) - len(todo), desc=desc, unit="trial")
    tracebacks = internal_errors.tracebacks_path(csv_path)
    with RowAppender(csv_path, columns) as out:

        def record(*finished: dict) -> None:
            for row in finished:
                text = row.pop(internal_errors.TRACEBACK, None)
                if internal_errors.is_internal_error(row):
                    internal_errors.append_traceback(csv_path, _name(row, keys), text)
            out.write_rows(finished)  # one fsync for the rows that finished together
            rows.extend(finished)
            bar.update(len(finished))
            for row in finished:
                if internal_errors.is_internal_error(row):
                    bar.write(
                        f"trial {key(row)} ended in an internal error (a bug, not a "
                        f"failed trial; traceback in {tracebacks}): {row['error']}"
                    )
                elif row.get("error"):
                    bar.write(f"trial {key(row)} failed: {row['error']}")

        try:
            execute(fn, todo, record)
        finally:
            bar.close()
    return rows


_KEPT: dict[int, WorkerSet] = {}
"""The worker sets ``kept_pool`` keeps, by their number of workers."""


@contextmanager
def kept_pool(workers: int) -> Iterator[None]:
    """Within the block, every local run on ``workers`` worker processes uses one set of
    them: they start (imports, OpenGL context, solvers) once for several experiments, not
    once for each; one that dies or is killed is replaced. A trial's result does not depend
    on the worker it runs in: each builds its world from its own seed."""
    workers = max(1, workers)
    if workers in _KEPT:
        yield
        return
    with WorkerSet(workers) as kept:
        _KEPT[workers] = kept
        try:
            yield
        finally:
            _KEPT.pop(workers, None)


@contextmanager
def spawn_pool(workers: int) -> Iterator[ProcessPoolExecutor]:
    """A pool of ``workers`` spawned processes (the tilt calibration's ``map``; each with
    its own MuJoCo and OpenGL context) that run their libraries on ``cores // workers``
    threads (``worker_threads``) and end when this process is gone (``exit_with_parent``);
    shut down, tasks not yet started cancelled, when the block ends."""
    with worker_threads(workers):  # the workers start as tasks are submitted
        context = multiprocessing.get_context("spawn")
        pool = ProcessPoolExecutor(
            max_workers=workers,
            mp_context=context,
            initializer=exit_with_parent,
            initargs=(os.getpid(),),
        )
        try:
            yield pool
        finally:
            pool.shutdown(wait=True, cancel_futures=True)
