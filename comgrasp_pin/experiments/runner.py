"""Running many independent trials that survive failures, interruptions and crashes.

Every finished trial is appended to the CSV at once, whole (``run_files.RowAppender``), so an
interrupted run loses nothing and ``resume=True`` continues where it stopped; the run's
settings are kept beside the CSV and a resumed run must match them. A trial that raises is
recorded with its error and does not stop the run; ``retry_failed=True`` runs those again.
``backend="ray"`` runs the same trials as Ray tasks (``ray_backend``), the driver appending
rows as they finish. ``workers > 1`` runs trials in separate processes (spawned, so each has
its own MuJoCo and OpenGL context); a worker that dies (killed, crashed) breaks the pool:
it is restarted, the trials that were in flight are run again one at a time, and the one
that kills its worker again is recorded as failed (``WorkerDiedError``). A row that cannot
be written (full disk) stops the run with ``OutputError``; the rows before it stay intact.
"""

from __future__ import annotations

import csv
import multiprocessing
import os
import threading
import time
import traceback
from collections import Counter, deque
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from contextlib import contextmanager
from pathlib import Path

from tqdm import tqdm

from comgrasp_pin.errors import InvalidInputError, ResumeError, WorkerDiedError
from comgrasp_pin.experiments import run_files
from comgrasp_pin.experiments.ray_backend import check_backend, ensure_ray, run_on_ray
from comgrasp_pin.experiments.run_files import RowAppender
from comgrasp_pin.experiments.threads import worker_threads

KEY_COLUMNS = ("object", "trial", "method")
PARENT_CHECK_S = 1.0  # how often a pool worker checks that its driver is still there (s)
WORKER_DIED = (
    "the worker process running this trial died (killed, crashed or out of memory); the run "
    "went on without it: run it again with --resume --retry-failed"
)


def task_key(row: dict) -> tuple[str, ...]:
    """Identity of a trial: its object, trial index and method."""
    return tuple(str(row.get(k, "")) for k in KEY_COLUMNS)


def read_rows(csv_path: Path) -> list[dict]:
    """All rows of a results CSV (empty when the file does not exist), its own header."""
    if not csv_path.exists():
        return []
    with csv_path.open(newline="") as f:
        return list(csv.DictReader(f))


def _error_row(task: dict, exc: BaseException) -> dict:
    last = traceback.format_exception_only(type(exc), exc)[-1].strip()
    return {**task, "error": last}


def _safe_call(fn: Callable[[dict], dict], task: dict) -> dict:
    try:
        return {**task, **fn(task), "error": ""}
    except Exception as exc:  # a failed trial is data, not the end of the run
        return _error_row(task, exc)


def _kept_rows(csv_path: Path, columns: list[str], resume: bool, overwrite: bool,
               retry_failed: bool, settings: dict | None) -> list[dict]:  # fmt: skip
    """The rows of an earlier run to keep; the CSV and its settings made ready to append."""
    fresh = overwrite or not csv_path.exists() or csv_path.stat().st_size == 0
    if fresh:
        rows, rewrite = [], True
        if settings is not None:
            run_files.write_settings(csv_path, settings)
    elif not resume:
        raise ResumeError(
            f"{csv_path} already holds results: pass resume (--resume) to continue it or "
            "overwrite (--overwrite) to start again"
        )
    else:
        rows, repaired = run_files.read_results(csv_path, columns)
        if settings is not None:
            run_files.write_settings(csv_path, run_files.check_settings(csv_path, settings))
        failed = [row for row in rows if row.get("error")]
        if retry_failed:
            rows = [row for row in rows if not row.get("error")]
        rewrite = repaired or bool(retry_failed and failed)
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
) -> list[dict]:
    """Run ``fn(task)`` for every task not already in ``csv_path``; return all rows.

    Args:
        fn: a picklable top-level function returning a dict of result columns.
        tasks: dicts with at least the KEY_COLUMNS, each key once; their items are copied
            into the row.
        csv_path: results file; rows are appended as trials finish.
        columns: the CSV header (an ``error`` column is added).
        workers: processes (1: in this process), or Ray tasks in flight (0: as many as the
            Ray cluster has CPUs).
        resume: keep the rows already in ``csv_path`` and run only the missing tasks.
        overwrite: start a new file even if one exists.
        retry_failed: with ``resume``, run again the tasks whose rows hold an error.
        settings: every setting of the run, recorded beside the CSV; with ``resume`` the
            recorded ones must match (``run_files.check_settings``).
        backend: "local" (this process or ``workers`` processes) or "ray" (Ray tasks, at
            most ``workers`` at a time, on ``ray_address`` or a local Ray).
        keys: the columns that identify a trial (each task once).

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
    execute = _executor(backend, workers, ray_address)
    with run_files.run_lock(Path(csv_path)):
        rows = _kept_rows(Path(csv_path), columns, resume, overwrite, retry_failed, settings)
        return _run_missing(fn, tasks, rows, Path(csv_path), columns, execute, desc, key)


def _key_of(keys: tuple[str, ...]) -> Callable[[dict], tuple[str, ...]]:
    return lambda row: tuple(str(row.get(k, "")) for k in keys)


def _executor(backend: str, workers: int, ray_address: str | None):
    """``execute(fn, todo, record)`` for the backend."""
    if backend == "ray":
        ray = ensure_ray(workers, ray_address)  # before any file is touched: none if it fails
        workers = workers or max(1, int(ray.cluster_resources().get("CPU", 1)))
        return lambda fn, todo, record: run_on_ray(_safe_call, fn, todo, workers, record,
                                                   ray_address)  # fmt: skip
    if workers <= 1:
        return _run_serial
    return lambda fn, todo, record: _run_parallel(fn, todo, workers, record)


def _run_serial(fn, todo, record) -> None:
    for task in todo:
        record(_safe_call(fn, task))


def _run_missing(fn, tasks, rows: list[dict], csv_path: Path, columns: list[str],
                 execute, desc: str, key) -> list[dict]:  # fmt: skip
    """Run the tasks that have no row in ``rows`` yet, appending theirs; all rows."""
    done = {key(row) for row in rows}
    todo = [task for task in tasks if key(task) not in done]
    bar = tqdm(total=len(tasks), initial=len(tasks) - len(todo), desc=desc, unit="trial")
    with RowAppender(csv_path, columns) as out:

        def record(*finished: dict) -> None:
            out.write_rows(finished)  # one fsync for the rows that finished together
            rows.extend(finished)
            bar.update(len(finished))
            for row in finished:
                if row.get("error"):
                    bar.write(f"trial {key(row)} failed: {row['error']}")

        try:
            execute(fn, todo, record)
        finally:
            bar.close()
    return rows


def _run_parallel(fn, todo, workers: int, record) -> None:
    """All of ``todo`` on ``workers`` processes, a pool restarted whenever a worker dies."""
    queue = deque(todo)
    while queue:
        for task in _run_pool(fn, queue, workers, record):
            _run_pool(fn, deque([task]), 1, record)  # alone: a second death is its own


def _run_pool(fn, queue: deque, workers: int, record) -> list[dict]:
    """Run tasks from ``queue`` (at most ``workers`` at a time) until it is empty or a
    worker dies; return the tasks in flight when it died (none otherwise). A task that
    kills the only worker of a one-worker pool is recorded as failed. The pool is the one
    ``kept_pool`` keeps, if it has as many workers, else a new one."""
    kept = _KEPT.get(workers)
    if kept is not None:
        died = _run_in_pool(kept, fn, queue, workers, record)
        if died:
            del _KEPT[workers]  # broken: what runs next starts a pool of its own
        return died
    with spawn_pool(workers) as pool:
        return _run_in_pool(pool, fn, queue, workers, record)


_KEPT: dict[int, ProcessPoolExecutor] = {}
"""The pools ``kept_pool`` keeps, by their number of workers."""


@contextmanager
def kept_pool(workers: int) -> Iterator[None]:
    """Within the block, every local run of ``workers`` processes uses one pool: its
    workers start (imports, OpenGL context, solvers) once for several experiments, not
    once for each. A trial's result does not depend on the worker it runs in: each builds
    its world from its own seed."""
    if workers <= 1 or workers in _KEPT:
        yield
        return
    with spawn_pool(workers) as pool:
        _KEPT[workers] = pool
        try:
            yield
        finally:
            _KEPT.pop(workers, None)


@contextmanager
def spawn_pool(workers: int) -> Iterator[ProcessPoolExecutor]:
    """A pool of ``workers`` spawned processes (each with its own MuJoCo and OpenGL
    context) that run their libraries on ``cores // workers`` threads (``worker_threads``)
    and end when this process is gone (``exit_with_parent``); shut down, tasks not yet
    started cancelled, when the block ends."""
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


def exit_with_parent(parent: int) -> None:
    """A pool worker's initializer: the worker ends when the process that started it
    (``parent``, its pid) is gone. A driver killed outright cannot shut its pool down, and
    its workers would run on as orphans, each a core busy with trials nobody records."""

    def watch() -> None:
        while os.getppid() == parent:
            time.sleep(PARENT_CHECK_S)
        os._exit(1)

    threading.Thread(target=watch, name="exit-with-parent", daemon=True).start()


def _run_in_pool(pool: ProcessPoolExecutor, fn, queue: deque, workers: int, record) -> list[dict]:
    running: dict[Future, dict] = {}
    while queue or running:
        while queue and len(running) < workers:
            try:
                future = pool.submit(_safe_call, fn, queue[0])
            except BrokenProcessPool:
                return list(running.values())
            running[future] = queue.popleft()
        finished, _ = wait(running, return_when=FIRST_COMPLETED)
        died = [running[f] for f in finished if isinstance(f.exception(), BrokenProcessPool)]
        for future in finished:
            task, exc = running.pop(future), future.exception()
            if not isinstance(exc, BrokenProcessPool):
                record(_error_row(task, exc) if exc is not None else future.result())
        if died and workers == 1:
            record(_error_row(died[0], WorkerDiedError(WORKER_DIED)))
        elif died:
            return died + list(running.values())
    return []
