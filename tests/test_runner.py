"""The trial runner keeps every finished trial, records failures and resumes."""

import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

from comgrasp_pin.errors import ResumeError, UnstablePhysicsError
from comgrasp_pin.experiments.runner import read_rows, run_trials
from comgrasp_pin.experiments.threads import THREAD_VARIABLES, thread_env, worker_threads


def _square(task: dict) -> dict:
    if task["trial"] == 3:
        raise UnstablePhysicsError("this trial fails")
    return {"value": task["trial"] ** 2}


def _tasks(n):
    return [{"object": "obj1", "trial": k, "method": "m"} for k in range(n)]


COLUMNS = ["object", "trial", "method", "value"]


def test_failures_are_recorded_and_the_run_goes_on(tmp_path):
    path = tmp_path / "out.csv"
    rows = run_trials(_square, _tasks(6), path, COLUMNS)
    on_disk = read_rows(path)
    assert len(rows) == len(on_disk) == 6
    failed = [r for r in on_disk if r["error"]]
    assert len(failed) == 1 and "this trial fails" in failed[0]["error"]
    assert {int(r["value"]) for r in on_disk if not r["error"]} == {0, 1, 4, 16, 25}


def test_resume_runs_only_missing_trials(tmp_path):
    path = tmp_path / "out.csv"
    run_trials(_square, _tasks(3), path, COLUMNS)
    with pytest.raises(ResumeError, match="already holds"):
        run_trials(_square, _tasks(5), path, COLUMNS)
    calls = []

    def counting(task):
        calls.append(task["trial"])
        return _square(task)

    rows = run_trials(counting, _tasks(5), path, COLUMNS, resume=True)
    assert calls == [3, 4]
    assert len(rows) == len(read_rows(path)) == 5


def test_parallel_workers_give_the_same_rows(tmp_path):
    serial = run_trials(_square, _tasks(6), tmp_path / "a.csv", COLUMNS)
    parallel = run_trials(_square, _tasks(6), tmp_path / "b.csv", COLUMNS, workers=2)

    def key(rows):
        return sorted((str(r["trial"]), str(r.get("value", "")), r["error"]) for r in rows)

    assert key(serial) == key(read_rows(tmp_path / "b.csv")) == key(parallel)


def _thread_settings(task: dict) -> dict:
    import os

    import cv2

    return {"value": f"{os.environ.get('OPENBLAS_NUM_THREADS')},{cv2.getNumThreads()}"}


def test_workers_share_the_cores_instead_of_each_taking_them_all(tmp_path, monkeypatch):
    """Each of 2 worker processes on 2 cores runs its libraries on 1 thread (their default
    is one per core: measured, the two processes then wait on each other's threads); the
    driver's own environment is left as it was."""
    monkeypatch.setattr(os, "cpu_count", lambda: 2)
    for name in THREAD_VARIABLES:
        monkeypatch.delenv(name, raising=False)
    rows = run_trials(_thread_settings, _tasks(2), tmp_path / "t.csv", COLUMNS, workers=2)
    assert [r["value"] for r in rows] == ["1,1", "1,1"]
    assert not any(name in os.environ for name in THREAD_VARIABLES)


def _calibration_row(task: dict) -> dict:
    return {**task, "pid": os.getpid(), "threads": os.environ.get("OPENBLAS_NUM_THREADS")}


def test_the_tilt_calibration_pool_is_the_runners(tmp_path, monkeypatch):
    """The tilt calibration's pool (``spawn_pool``, as the runner's): 2 spawned workers,
    1 thread each on 2 cores, every task once; with its log, a second pool runs none again."""
    from comgrasp_pin.experiments.tilt_calibration import _Pool

    monkeypatch.setattr(os, "cpu_count", lambda: 2)
    for name in THREAD_VARIABLES:
        monkeypatch.delenv(name, raising=False)
    tasks = [{"object": "obj1", "lever": 0.01 * k, "side": 1.0, "seed": k} for k in range(6)]
    log = tmp_path / "calibration.jsonl"
    with _Pool(2, log) as pool:
        rows = pool.map(_calibration_row, tasks)
    assert [r["seed"] for r in rows] == list(range(6))
    assert {r["threads"] for r in rows} == {"1"} and os.getpid() not in {r["pid"] for r in rows}
    with _Pool(2, log) as pool:
        assert pool.map(_calibration_row, tasks) == rows  # all from the log
    assert len(log.read_text().splitlines()) == 6


def test_threads_per_worker(monkeypatch):
    for name in THREAD_VARIABLES:  # none set by the user (tests/conftest.py sets some)
        monkeypatch.delenv(name, raising=False)
    assert thread_env(2, cores=2) == dict.fromkeys(THREAD_VARIABLES, "1")
    assert thread_env(1, cores=2)["LP_NUM_THREADS"] == "2"
    assert thread_env(3, cores=8)["OPENBLAS_NUM_THREADS"] == "2"
    assert thread_env(16, cores=2)["OMP_NUM_THREADS"] == "1"  # never none


def test_a_thread_count_the_user_set_is_kept(monkeypatch):
    monkeypatch.delenv("LP_NUM_THREADS", raising=False)
    monkeypatch.setenv("OPENBLAS_NUM_THREADS", "4")
    env = thread_env(2, cores=2)
    assert env["OPENBLAS_NUM_THREADS"] == "4" and env["LP_NUM_THREADS"] == "1"
    with worker_threads(2):
        assert os.environ["OPENBLAS_NUM_THREADS"] == "4" and os.environ["LP_NUM_THREADS"] == "1"
    assert os.environ["OPENBLAS_NUM_THREADS"] == "4" and "LP_NUM_THREADS" not in os.environ


DRIVER = """
import sys
sys.path.insert(0, {tests!r})
from _slow_task import sleep_and_record_pid
from comgrasp_pin.experiments.runner import run_trials
tasks = [{{"object": "obj1", "trial": k, "method": "m", "pid_dir": {pids!r}, "sleep_s": 120}}
         for k in range(4)]
run_trials(sleep_and_record_pid, tasks, {csv!r}, ["object", "trial", "method", "value"], workers=2)
"""


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    return not Path(f"/proc/{pid}/stat").read_text().split()[2] == "Z"  # a zombie is gone


def test_workers_of_a_killed_driver_do_not_run_on(tmp_path):
    """Killing a run's driver (SIGKILL: no clean-up) ends its pool's workers within seconds,
    rather than leaving them to run their trials as orphans."""
    pids = tmp_path / "pids"
    pids.mkdir()
    code = DRIVER.format(tests=str(Path(__file__).parent), pids=str(pids),
                         csv=str(tmp_path / "out.csv"))  # fmt: skip
    driver = subprocess.Popen([sys.executable, "-c", code])
    deadline = time.monotonic() + 60
    while len(list(pids.iterdir())) < 2 and time.monotonic() < deadline:
        time.sleep(0.2)
    workers = [int(p.name) for p in pids.iterdir()]
    assert len(workers) == 2 and all(_alive(pid) for pid in workers)
    driver.kill()
    driver.wait()
    deadline = time.monotonic() + 10
    while any(_alive(pid) for pid in workers) and time.monotonic() < deadline:
        time.sleep(0.2)
    assert not any(_alive(pid) for pid in workers)


def _pid_or_death(task: dict) -> dict:
    if task.get("die"):
        os._exit(3)
    return {"value": os.getpid()}


def test_a_kept_pool_serves_several_runs_and_replaces_a_worker_that_dies(tmp_path):
    """Inside ``kept_pool`` two experiments run on the same two worker processes (started
    once); a worker's death fails that trial only and that worker is replaced, the runs
    after it complete on the kept set."""
    from comgrasp_pin.experiments.runner import _KEPT, kept_pool

    with kept_pool(2):
        kept = _KEPT[2]
        first = run_trials(_pid_or_death, _tasks(6), tmp_path / "a.csv", COLUMNS, workers=2)
        second = run_trials(_pid_or_death, _tasks(6), tmp_path / "b.csv", COLUMNS, workers=2)
        # Both ran in the kept set's processes (how the tasks spread over the two depends
        # on the machine's load, so which of them ran a task is not asserted).
        pids = {int(r["value"]) for r in first} | {int(r["value"]) for r in second}
        assert pids <= set(kept.pids()) and len(kept.pids()) == 2
        assert os.getpid() not in pids
        dying = [{**t, "die": t["trial"] == 2} for t in _tasks(6)]
        third = run_trials(_pid_or_death, dying, tmp_path / "c.csv", COLUMNS, workers=2)
        assert _KEPT[2] is kept  # kept, its dead worker replaced
        fourth = run_trials(_pid_or_death, _tasks(4), tmp_path / "d.csv", COLUMNS, workers=2)
        assert {int(r["value"]) for r in fourth} <= set(kept.pids())
    assert [bool(r["error"]) for r in sorted(third, key=lambda r: r["trial"])] == [
        False, False, True, False, False, False
    ]  # fmt: skip
    assert not any(r["error"] for r in fourth)
    assert not _KEPT
