"""Trial workers: spawned processes that run one trial at a time, watched by the driver.

A local run hands each trial to a worker process (``workers`` of them; one for a serial run)
and waits on the workers' pipes and process sentinels (``multiprocessing.connection.wait``):

- a row that comes back is recorded;
- a worker that dies (segfault, ``os._exit``, killed, out of memory) fails its own trial
  (``WorkerDiedError``) and only that one: the driver knows which trial each worker runs.
  The worker is replaced;
- a trial that runs past ``trial_timeout_s`` has its worker killed (SIGKILL: the whole
  process, whatever it is stuck in) and replaced, and is recorded as ``TrialTimeoutError``.

So neither a crash nor a hang ends or stalls the run, and the other workers' trials go on.

What a trial raises decides what its row is (``safe_call``):

- a ``ComGraspError`` (the robot dropped the rod, perception refused, unstable physics; the
  harness's ``WorkerDiedError`` and ``TrialTimeoutError`` too) is the world's or the run's
  verdict on that trial: a row with the error's last line, counted as a failed trial;
- anything else (``TypeError``, ``KeyError``, ``MemoryError``, ...) is an internal error, a
  bug and not the world's failure: a row whose error begins ``internal error:``
  (``internal_errors``) carrying the whole traceback, which the driver keeps in
  ``NAME.tracebacks.txt`` beside the CSV. The run goes on (the other trials are worth
  having), but such a row is never counted as a failed trial: the report leaves it out of
  every rate and mean and names it, the command ends with exit status 1 naming it, and
  ``--resume`` runs it again (``runner``). A worker that cannot unpickle a job or pickle a
  row reports an internal error the same way.
A trial's clock starts when its worker is ready: a new worker first starts Python and
imports the package (0.3 s here), which is not the trial's time; a worker not ready within
``WORKER_START_S`` counts as hung. The workers are spawned (each has its own MuJoCo and
OpenGL context), run their libraries on ``cores // workers`` threads (``worker_threads``),
are daemons (a trial cannot start processes of its own) and end when the driver is gone
(``exit_with_parent``).
"""

from __future__ import annotations

import multiprocessing
import os
import threading
import time
import traceback
from collections import deque
from collections.abc import Callable, Sequence
from multiprocessing.connection import wait

from comgrasp_pin.errors import ComGraspError, TrialTimeoutError, WorkerDiedError
from comgrasp_pin.experiments.internal_errors import INTERNAL_ERROR, TRACEBACK
from comgrasp_pin.experiments.threads import worker_threads

PARENT_CHECK_S = 1.0  # how often a worker checks that its driver is still there (s)
WORKER_START_S = 120.0
"""How long a new worker may take to be ready (s): Python and the package start in 0.3 s on
this machine's two shared cores, a few seconds on a loaded one; one stuck for two minutes is
hung, and its trial is recorded as timed out."""
READY = "ready"  # a worker's first message: started, waiting for trials
WORKER_DIED = (
    "the worker process running this trial died (killed, crashed or out of memory); the run "
    "went on without it: run it again with --resume --retry-failed"
)


def timed_out(limit_s: float) -> TrialTimeoutError:
    """The error of a trial stopped at its time limit."""
    return TrialTimeoutError(
        f"the trial ran past its time limit of {limit_s:g} s (--trial-timeout) and was "
        "stopped; run it again with --resume --retry-failed, with a longer --trial-timeout "
        "if it needs more time"
    )


def _last_line(exc: BaseException) -> str:
    return traceback.format_exception_only(type(exc), exc)[-1].strip()


def error_row(task: dict, exc: BaseException) -> dict:
    """The row of a failed trial (a ``ComGraspError``): the task and the error's last line."""
    return {**task, "error": _last_line(exc)}


def internal_error_row(task: dict, exc: BaseException) -> dict:
    """The row of a trial that raised something other than a ``ComGraspError``: the error's
    last line after ``internal error:``, and its whole traceback under ``TRACEBACK``."""
    text = "".join(traceback.format_exception(type(exc), exc, exc.__traceback__))
    return {**task, "error": f"{INTERNAL_ERROR}: {_last_line(exc)}", TRACEBACK: text}


def safe_call(fn: Callable[[dict], dict], task: dict) -> dict:
    """``fn(task)``'s row: the task, its result columns and an empty error; the error's row
    for a ``ComGraspError``; an internal error's row for any other exception."""
    try:
        return {**task, **fn(task), "error": ""}
    except ComGraspError as exc:  # the world (or the harness) failed the trial: data
        return error_row(task, exc)
    except Exception as exc:  # a bug: kept, with its traceback, but never a failed trial
        return internal_error_row(task, exc)


def exit_with_parent(parent: int) -> None:
    """In a worker: end it when the process that started it (``parent``, its pid) is gone.
    A driver killed outright cannot stop its workers, which would run on as orphans, each a
    core busy with trials nobody records."""

    def watch() -> None:
        while os.getppid() == parent:
            time.sleep(PARENT_CHECK_S)
        os._exit(1)

    threading.Thread(target=watch, name="exit-with-parent", daemon=True).start()


def _serve(conn, parent: int) -> None:
    """A worker's life: say it is ready, then run ``call(fn, task)`` per job until told to
    stop (None) or the driver's end of the pipe closes."""
    exit_with_parent(parent)
    conn.send(READY)
    while True:
        try:
            job = conn.recv()
        except EOFError:
            return
        except Exception as exc:  # a job that cannot be unpickled here (its module)
            conn.send(internal_error_row({}, exc))
            continue
        if job is None:
            return
        call, fn, task = job
        row = call(fn, task)
        try:
            conn.send(row)
        except Exception as exc:  # a result that cannot be pickled
            conn.send(internal_error_row(task, exc))


_NOTHING = object()  # no message this pass


def _receive(conn) -> object:
    """The next message on ``conn``, or None when the worker's end is closed (it died)."""
    try:
        return conn.recv()
    except (EOFError, OSError):
        return None


class _Worker:
    """One worker process, the pipe to it and the trial it runs (or None)."""

    def __init__(self, threads_for: int):
        context = multiprocessing.get_context("spawn")
        self.conn, child = context.Pipe()
        with worker_threads(threads_for):
            self.process = context.Process(target=_serve, args=(child, os.getpid()),
                                           name="comgrasp-trial-worker", daemon=True)  # fmt: skip
            self.process.start()
        child.close()
        self.ready, self.task, self.deadline = False, None, float("inf")

    def start(self, job: tuple, limit_s: float | None) -> None:
        self.conn.send(job)
        self.task = job[2]
        self._arm(limit_s)

    def _arm(self, limit_s: float | None) -> None:
        wait_s = (limit_s or float("inf")) + (0.0 if self.ready else WORKER_START_S)
        self.deadline = time.monotonic() + wait_s

    def kill(self) -> None:
        self.process.kill()
        self.process.join()
        self.conn.close()

    def stop(self) -> None:
        """End the worker: asked to when idle, killed when it runs a trial."""
        if self.task is None and self.process.is_alive():
            try:
                self.conn.send(None)
                self.process.join(timeout=PARENT_CHECK_S)
            except OSError:
                pass
        if self.process.is_alive():
            self.kill()
        self.conn.close()


class WorkerSet:
    """Up to ``size`` trial workers, started as trials need them, replaced when one dies or
    is killed; used for one run (``with WorkerSet(n) as w: w.run(...)``) or kept for several
    (the runner's ``kept_pool``)."""

    def __init__(self, size: int):
        self.size = max(1, int(size))
        self._workers: list[_Worker] = []

    def pids(self) -> list[int]:
        """The process ids of the live workers."""
        return [w.process.pid or 0 for w in self._workers if w.process.is_alive()]

    def run(self, call: Callable, fn: Callable[[dict], dict], todo: Sequence[dict],
            record: Callable[..., None], trial_timeout_s: float | None = None) -> None:  # fmt: skip
        """Run ``call(fn, task)`` for every task of ``todo`` and ``record`` the rows (those
        that finished together in one call). If the run stops (a row that cannot be
        written, ^C), the workers still running trials are killed: no late row of this run
        reaches another."""
        queue = deque(todo)
        try:
            while queue or self._busy():
                for worker in self._idle()[: len(queue)]:
                    try:
                        worker.start((call, fn, queue[0]), trial_timeout_s)
                    except OSError:  # it died since it last ran a trial: another takes it
                        self._drop(worker)
                        continue
                    queue.popleft()
                rows = self._collect(trial_timeout_s)
                if rows:
                    record(*rows)
        except BaseException:
            for worker in self._busy():
                self._drop(worker)
            raise

    def _busy(self) -> list[_Worker]:
        return [w for w in self._workers if w.task is not None]

    def _idle(self) -> list[_Worker]:
        for dead in [w for w in self._workers if w.task is None and not w.process.is_alive()]:
            self._drop(dead)
        while len(self._workers) < self.size:
            self._workers.append(_Worker(self.size))
        return [w for w in self._workers if w.task is None]

    def _drop(self, worker: _Worker) -> None:
        worker.kill()
        self._workers.remove(worker)

    def _collect(self, limit_s: float | None) -> list[dict]:
        """The rows of the trials that end within the next wait: finished, died or timed out."""
        busy = self._busy()
        wait_s = max(0.0, min(w.deadline for w in busy) - time.monotonic())
        ready = set(wait([w.conn for w in busy] + [w.process.sentinel for w in busy],
                         timeout=None if wait_s == float("inf") else wait_s))  # fmt: skip
        rows = []
        for worker in busy:
            task: dict = worker.task or {}
            message = _NOTHING
            if worker.conn in ready:
                message = _receive(worker.conn)
            if message == READY:
                worker.ready = True
                worker._arm(limit_s)
            elif isinstance(message, dict):
                worker.task = None
                rows.append({**task, **message})
                continue
            if message is None or worker.process.sentinel in ready:  # died: EOF, or ended
                rows.append(error_row(task, WorkerDiedError(WORKER_DIED)))
                self._drop(worker)
            elif time.monotonic() >= worker.deadline:  # only with a limit: else never
                rows.append(error_row(task, timed_out(limit_s or 0.0)))
                self._drop(worker)
        return rows

    def close(self) -> None:
        """Stop every worker."""
        for worker in self._workers:
            worker.stop()
        self._workers.clear()

    def __enter__(self) -> WorkerSet:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
