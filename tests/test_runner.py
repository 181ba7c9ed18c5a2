"""The trial runner keeps every finished trial, records failures and resumes."""

import pytest

from comgrasp_pin.errors import ResumeError
from comgrasp_pin.experiments.runner import read_rows, run_trials


def _square(task: dict) -> dict:
    if task["trial"] == 3:
        raise RuntimeError("this trial fails")
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
