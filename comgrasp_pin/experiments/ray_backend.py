"""Trials as Ray tasks: the same trial functions, seeds and rows as the local processes.

``run_on_ray`` runs ``workers.safe_call(fn, task)`` as a Ray task per trial, at most
``workers`` in flight, and hands each row to ``record`` (the runner's CSV appender) as it
finishes, so the driver appends rows exactly as a local run does and ``--resume`` works the
same. A trial that raises is an error row, or an internal error's row when what it raised
is not a ``ComGraspError`` (inside the task, as locally: ``workers.safe_call``); a task
whose worker crashed (killed, out of memory: Ray's ``WorkerCrashedError``) is recorded as
failed (``WorkerDiedError``), and is not retried (``max_retries=0``): a trial that kills its
worker would kill the next one as well. Any other Ray error is an internal error: not the
world's verdict on the trial, so never counted as one, and ``--resume`` runs it again. A
task running past ``trial_timeout_s`` is cancelled with ``force=True`` (Ray kills its worker
process) and recorded as ``TrialTimeoutError``. Ray does not tell the driver when a task
starts, so its clock starts when it is submitted: with at most ``workers`` tasks in flight
on as many CPUs it starts at once, after a new Ray worker's start-up (seconds, against a
limit of minutes).

Ray is an optional extra (``pip install 'comgrasp_pin[ray]'``). A Ray already initialised
in this process is used as it is; otherwise ``ray.init(address=...)`` joins an existing
cluster, or, without an address, a local Ray is started with ``num_cpus=workers``.
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable, Sequence

from comgrasp_pin.errors import BackendError, WorkerDiedError
from comgrasp_pin.experiments.threads import thread_env
from comgrasp_pin.experiments.workers import (
    WORKER_DIED,
    error_row,
    internal_error_row,
    timed_out,
)

BACKENDS = ("local", "ray")
RAY_INIT_OPTIONS = {"include_dashboard": False, "log_to_driver": False}
"""Options of a local Ray this package starts: no dashboard (seconds of start-up, a port),
worker output not echoed (a failed trial's message is in its row)."""
TASK_OPTIONS = {"num_cpus": 1, "max_retries": 0}
"""Each trial takes one CPU (MuJoCo and OpenCV single-threaded); a task whose worker died is
not run again (see the module docstring)."""


def import_ray():
    """The ``ray`` module.

    Raises:
        BackendError: Ray is not installed.
    """
    try:
        import ray
    except ImportError:
        raise BackendError(
            "--backend ray needs Ray, which is not installed: pip install 'comgrasp_pin[ray]' "
            "(or pip install 'ray>=2.9'), or use --backend local"
        ) from None
    return ray


def check_backend(backend: str, address: str | None) -> None:
    """Refuse an unknown backend, an address without Ray, or Ray not installed.

    Raises:
        InvalidInputError: unknown backend, or an address with the local backend.
        BackendError: Ray asked for but not installed.
    """
    from comgrasp_pin import validate
    from comgrasp_pin.errors import InvalidInputError

    validate.choice(backend, "backend", BACKENDS)
    if address and backend != "ray":
        raise InvalidInputError("--ray-address is for --backend ray")
    if backend == "ray":
        import_ray()


def ensure_ray(workers: int, address: str | None = None):
    """The ``ray`` module, initialised: as it is, on ``address``, or a local Ray of ``workers``.

    Raises:
        BackendError: Ray not installed, or the cluster cannot be started or reached.
    """
    ray = import_ray()
    if ray.is_initialized():
        return ray
    # headless rendering on every worker, wherever it runs; one thread per task's CPU
    # (experiments.threads: Ray runs as many tasks as a node has CPUs)
    env_vars = {"MUJOCO_GL": os.environ.get("MUJOCO_GL", "egl"), **thread_env(1, cores=1)}
    env = {"env_vars": env_vars}
    try:
        if address:
            ray.init(address=address, runtime_env=env, **RAY_INIT_OPTIONS)
        else:
            ray.init(num_cpus=workers or os.cpu_count(), runtime_env=env, **RAY_INIT_OPTIONS)
    except (ConnectionError, RuntimeError) as exc:
        where = f"the Ray cluster at {address!r}" if address else "a local Ray"
        raise BackendError(f"cannot start or reach {where}: {exc}") from None
    return ray


def _died_message(exc: BaseException) -> str:
    return f"{WORKER_DIED} (Ray: {type(exc).__name__})"


def run_on_ray(
    call: Callable[[Callable, dict], dict],
    fn: Callable[[dict], dict],
    todo: Sequence[dict],
    workers: int,
    record: Callable[[dict], None],
    address: str | None = None,
    trial_timeout_s: float | None = None,
) -> None:
    """Run ``call(fn, task)`` for every task of ``todo`` as Ray tasks, at most ``workers`` at
    a time, and ``record`` the rows (in the order they finish; those that finished together
    in one call, written with one fsync); a task past ``trial_timeout_s`` (s, None: no
    limit) is cancelled and recorded as ``TrialTimeoutError``."""
    ray = ensure_ray(workers, address)
    remote = ray.remote(**TASK_OPTIONS)(call)
    fn_ref = ray.put(fn)
    queue, running, deadlines = list(todo), {}, {}
    queue.reverse()
    limit_s = float("inf") if trial_timeout_s is None else trial_timeout_s
    try:
        while queue or running:
            while queue and len(running) < workers:
                task = queue.pop()
                ref = remote.remote(fn_ref, task)
                running[ref], deadlines[ref] = task, time.monotonic() + limit_s
            done = _finished(ray, list(running), min(deadlines.values()) - time.monotonic())
            rows = [_row(ray, ref, running.pop(ref)) for ref in done]
            late = [ref for ref in running if deadlines[ref] <= time.monotonic()]
            for ref in late:
                ray.cancel(ref, force=True)  # kills the worker process, stuck or not
                rows.append(error_row(running.pop(ref), timed_out(limit_s)))
            for ref in [*done, *late]:
                del deadlines[ref]
            if rows:
                record(*rows)
    finally:  # the run stopped (a row that cannot be written, ^C): stop what is in flight
        for ref in running:
            ray.cancel(ref, force=True)


def _finished(ray, refs: list, wait_s: float) -> list:
    """The refs done within ``wait_s`` (s; at least one if that is infinite): O(in flight)
    per pass, not per row."""
    timeout = None if wait_s == float("inf") else max(0.0, wait_s)
    done, rest = ray.wait(refs, num_returns=1, timeout=timeout)
    if rest and done:
        done += ray.wait(rest, num_returns=len(rest), timeout=0)[0]
    return done


def _row(ray, ref, task: dict) -> dict:
    """The task's row; when Ray could not run it, a dead worker's error row, or an internal
    error's row for any other Ray error."""
    try:
        return ray.get(ref)
    except ray.exceptions.RayError as exc:
        if isinstance(exc, ray.exceptions.WorkerCrashedError):
            return error_row(task, WorkerDiedError(_died_message(exc)))
        return internal_error_row(task, exc)
