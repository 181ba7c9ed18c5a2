"""The Ray backend on a real local Ray (issue 16): the same rows as local processes, resumable
across backends, failed tasks (an exception, a killed worker) recorded as failed trials.

One Ray session (2 CPUs) is shared by the module; the tests folder is put on the workers'
PYTHONPATH so that they can import this module's trial functions.
"""

import json
import os
import signal
import time
from pathlib import Path

import pytest

ray = pytest.importorskip("ray")

from comgrasp_pin.cli import main  # noqa: E402
from comgrasp_pin.errors import UnstablePhysicsError  # noqa: E402
from comgrasp_pin.experiments.runner import WORKER_DIED, read_rows, run_trials  # noqa: E402

COLUMNS = ["object", "trial", "method", "value", "pid"]
TESTS = str(Path(__file__).resolve().parent)


@pytest.fixture(scope="module", autouse=True)
def ray_session():
    path = os.pathsep.join(p for p in (TESTS, os.environ.get("PYTHONPATH", "")) if p)
    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False,
             runtime_env={"env_vars": {"PYTHONPATH": path}})  # fmt: skip
    yield
    ray.shutdown()


def _tasks(n):
    return [{"object": "obj1", "trial": k, "method": "m"} for k in range(n)]


def _killed_or_failing(task: dict) -> dict:
    """Trial 1 kills its own worker (as the OOM killer would); trial 3 raises."""
    if task["trial"] == 1:
        os.kill(os.getpid(), signal.SIGKILL)
    if task["trial"] == 3:
        raise UnstablePhysicsError("trial three failed")
    return {"value": task["trial"] * 10, "pid": os.getpid()}


def _value(task: dict) -> dict:
    return {"value": task["trial"] * 10, "pid": os.getpid()}


def test_a_killed_worker_and_an_exception_are_failed_trials_and_can_be_retried(tmp_path):
    path = tmp_path / "out.csv"
    rows = run_trials(_killed_or_failing, _tasks(5), path, COLUMNS, workers=2, backend="ray")
    on_disk = {int(r["trial"]): r for r in read_rows(path)}
    assert len(rows) == len(on_disk) == 5
    assert on_disk[1]["error"].startswith(f"comgrasp_pin.errors.WorkerDiedError: {WORKER_DIED}")
    assert "WorkerCrashedError" in on_disk[1]["error"]
    assert on_disk[3]["error"] == "comgrasp_pin.errors.UnstablePhysicsError: trial three failed"
    for k in (0, 2, 4):
        assert on_disk[k]["error"] == "" and int(on_disk[k]["value"]) == 10 * k
        assert int(on_disk[k]["pid"]) != os.getpid()  # ran in a Ray worker
    run_trials(_value, _tasks(5), path, COLUMNS, workers=2, backend="ray", resume=True,
               retry_failed=True)  # fmt: skip
    again = read_rows(path)
    assert sorted(int(r["value"]) for r in again) == [0, 10, 20, 30, 40]
    assert all(r["error"] == "" for r in again)


def test_hung_and_crashing_ray_tasks_are_failed_rows_and_the_run_goes_on(tmp_path):
    """As locally (test_trial_timeout): a task past its limit is cancelled (its worker
    killed), a segfault or os._exit fails its own row; --retry-failed reruns those."""
    from test_trial_timeout import check_failed_rows_and_retry

    # Ray's clock starts at submission, before a new Ray worker has started: a wider limit
    # (6 s was not enough on a loaded 2-core machine: a quick trial's new worker took longer
    # to start, and its row read as a timeout)
    check_failed_rows_and_retry(tmp_path / "out.csv", tmp_path, limit_s=12.0, workers=2,
                                backend="ray")  # fmt: skip


def _slow_value(task: dict) -> dict:
    # long enough for Ray to start its second worker on a loaded machine (0.5 s was not:
    # both tasks went to the first worker while the second was still starting)
    time.sleep(2.0)
    return _value(task)


@pytest.mark.parametrize("workers", [2, 0])  # 0: one task per CPU of the cluster (2)
def test_two_workers_run_two_tasks_at_a_time(tmp_path, workers):
    rows = run_trials(_slow_value, _tasks(4), tmp_path / "out.csv", COLUMNS, workers=workers,
                      backend="ray")  # fmt: skip
    assert len({r["pid"] for r in rows}) == 2


def _same(rows):
    keyed = {(r["object"], r["trial"], r["method"]): r for r in rows}
    return {k: {c: v for c, v in r.items() if c != "wall_s"} for k, r in keyed.items()}


@pytest.mark.slow
def test_ray_rows_equal_local_rows_and_a_local_run_resumes_on_ray(tmp_path):
    base = ["accuracy", "--objects", "obj1,obj2"]
    local, mixed = tmp_path / "local", tmp_path / "mixed"
    assert main([*base, "--trials", "2", "--workers", "1", "--out", str(local)]) == 0
    # started locally with one trial each, continued on Ray with the second
    assert main([*base, "--trials", "1", "--workers", "1", "--out", str(mixed)]) == 0
    assert main([*base, "--trials", "2", "--workers", "2", "--out", str(mixed), "--resume",
                 "--backend", "ray"]) == 0  # fmt: skip
    reference, on_ray = read_rows(local / "accuracy.csv"), read_rows(mixed / "accuracy.csv")
    assert len(reference) == len(on_ray) == 4
    assert all(r["error"] == "" and float(r["sim_s"]) > 1.0 for r in on_ray)
    assert _same(on_ray) == _same(reference)
    settings = json.loads((mixed / "accuracy.settings.json").read_text())
    assert settings["backend"] == "ray" and settings["trials"] == 2
    # a sweep on Ray: its point at the default grip force is the experiment's row
    sweep = tmp_path / "sweep"
    assert main(["sweep", "--param", "grip_force=15", "--objects", "obj1", "--trials", "1",
                 "--backend", "ray", "--workers", "2", "--out", str(sweep)]) == 0  # fmt: skip
    (point,) = read_rows(sweep / "sweep.csv")
    assert point.pop("motion.grip_force") == "15.0"
    assert _same([point]) == {k: v for k, v in _same(reference).items() if k[:2] == ("obj1", "0")}


@pytest.mark.slow
def test_a_pick_and_place_on_ray_gives_the_local_row(tmp_path):
    from comgrasp_pin.experiments.trials import REGRASP_COLUMNS, make_tasks, regrasp_trial

    tasks = make_tasks(["obj2"], 1, 0, ("regrasp",))
    local = run_trials(regrasp_trial, tasks, tmp_path / "a.csv", REGRASP_COLUMNS)
    on_ray = run_trials(regrasp_trial, tasks, tmp_path / "b.csv", REGRASP_COLUMNS,
                        backend="ray")  # fmt: skip
    assert local[0]["error"] == "" and local[0]["reason"]
    assert _same(read_rows(tmp_path / "b.csv")) == _same(read_rows(tmp_path / "a.csv"))
    assert len(on_ray) == 1
