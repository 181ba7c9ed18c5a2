"""Runs that cannot hang (issue 27): a trial past ``--trial-timeout`` is stopped and recorded
as ``TrialTimeoutError``; one that crashes its process (segfault, ``os._exit``) or runs out
of memory is its own failed row, with one worker as with two; ``--retry-failed`` reruns just
those rows. Real hung and crashing worker processes (``_slow_task.misbehave``)."""

import json
import os
import signal
import time
from pathlib import Path

import pytest
from _slow_task import misbehave

from comgrasp_pin.errors import InvalidInputError
from comgrasp_pin.experiments.run_files import settings_differences
from comgrasp_pin.experiments.runner import read_rows, run_trials

COLUMNS = ["object", "trial", "method", "value", "pid"]
ACTS = {1: "hang", 2: "exit", 3: "segfault", 4: "oom"}  # trial -> what it does
LIMIT_S = 2.0  # the hung trial's limit; each healthy trial takes milliseconds
RUN_BOUND_S = 40.0  # the whole run, hang included: far below the hour the trial sleeps


class RunHung(Exception):
    """The run went on past RUN_BOUND_S: the time limit did not end the hung trial."""


@pytest.fixture(autouse=True)
def bounded_run():
    """Each test ends within RUN_BOUND_S, or fails (SIGALRM) instead of hanging the suite."""

    def hung(*_):
        raise RunHung(f"still running after {RUN_BOUND_S} s")

    before = signal.signal(signal.SIGALRM, hung)
    signal.alarm(int(RUN_BOUND_S))
    yield
    signal.alarm(0)
    signal.signal(signal.SIGALRM, before)


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    return Path(f"/proc/{pid}/stat").read_text().split()[2] != "Z"  # a zombie is gone


def _tasks(ran_dir, acts=ACTS, n=6):
    ran_dir.mkdir(exist_ok=True)
    return [{"object": "obj1", "trial": k, "method": "m", "ran_dir": str(ran_dir),
             "act": acts.get(k, "")} for k in range(n)]  # fmt: skip


def check_failed_rows_and_retry(path, ran_dir, limit_s=LIMIT_S, **run):
    """The rows of a run of the misbehaving trials: each failure its own row, the others
    their values, the hung process gone; then --retry-failed reruns exactly the four failed
    trials."""
    start = time.monotonic()
    rows = run_trials(misbehave, _tasks(ran_dir / "first"), path, COLUMNS,
                      trial_timeout_s=limit_s, **run)  # fmt: skip
    assert time.monotonic() - start < RUN_BOUND_S
    on_disk = {int(r["trial"]): r for r in read_rows(path)}
    assert len(rows) == len(on_disk) == 6
    assert on_disk[1]["error"].startswith("comgrasp_pin.errors.TrialTimeoutError: the trial ran "
                                          f"past its time limit of {limit_s:g} s")  # fmt: skip
    hung_pid = int((ran_dir / "first" / "1").read_text())
    deadline = time.monotonic() + 5.0  # Ray reaps a cancelled worker asynchronously
    while _alive(hung_pid) and time.monotonic() < deadline:
        time.sleep(0.1)
    assert not _alive(hung_pid)
    assert "WorkerDiedError" in on_disk[2]["error"] and "WorkerDiedError" in on_disk[3]["error"]
    assert on_disk[4]["error"] == "internal error: MemoryError"  # not the world's failure
    for k in (0, 5):
        assert on_disk[k]["error"] == "" and int(on_disk[k]["value"]) == 10 * k
    retry = _tasks(ran_dir / "again", acts={})
    run_trials(misbehave, retry, path, COLUMNS, resume=True, retry_failed=True,
               trial_timeout_s=limit_s, **run)  # fmt: skip
    assert sorted(int(p.name) for p in (ran_dir / "again").iterdir()) == [1, 2, 3, 4]
    again = sorted(read_rows(path), key=lambda r: int(r["trial"]))
    assert [r["error"] for r in again] == [""] * 6
    assert [int(r["value"]) for r in again] == [0, 10, 20, 30, 40, 50]


@pytest.mark.parametrize("workers", [1, 2])
def test_hung_and_crashing_trials_are_failed_rows_and_the_run_goes_on(tmp_path, workers):
    check_failed_rows_and_retry(tmp_path / "out.csv", tmp_path, workers=workers)


def test_a_hang_while_the_other_worker_runs_on_loses_nothing(tmp_path):
    """Two workers: the one stuck is killed and replaced; the other's trials all finish
    (each once) while it hangs."""
    acts = {0: "hang"}
    rows = run_trials(misbehave, _tasks(tmp_path / "ran", acts, n=8), tmp_path / "out.csv",
                      COLUMNS, workers=2, trial_timeout_s=LIMIT_S)  # fmt: skip
    assert sorted(int(p.name) for p in (tmp_path / "ran").iterdir()) == list(range(8))
    by_trial = {int(r["trial"]): r for r in read_rows(tmp_path / "out.csv")}
    assert len(rows) == len(by_trial) == 8 and "TrialTimeoutError" in by_trial[0]["error"]
    assert all(by_trial[k]["error"] == "" for k in range(1, 8))


def test_a_trial_function_that_cannot_reach_a_worker_is_refused_before_any_file(tmp_path):
    def local(task):
        return {}

    with pytest.raises(InvalidInputError, match="cannot be sent to a worker process"):
        run_trials(local, _tasks(tmp_path / "ran"), tmp_path / "out.csv", COLUMNS,
                   trial_timeout_s=LIMIT_S)  # fmt: skip
    assert not (tmp_path / "out.csv").exists()
    with pytest.raises(InvalidInputError, match="trial_timeout_s must be > 0"):
        run_trials(misbehave, [], tmp_path / "out.csv", COLUMNS, trial_timeout_s=0.0)


def test_the_limit_is_an_option_recorded_in_the_settings_and_may_change_on_resume(tmp_path):
    from comgrasp_pin.cli import build_parser
    from comgrasp_pin.cli.experiments import run_options
    from comgrasp_pin.experiments.reproduce import run_settings

    parser = build_parser()
    args = parser.parse_args(["accuracy", "--trial-timeout", "42.5", "--out", str(tmp_path)])
    settings = run_settings(run_options(args))
    assert settings["trial_timeout_s"] == 42.5
    assert json.loads(json.dumps(settings))["trial_timeout_s"] == 42.5
    assert settings_differences(settings, {**settings, "trial_timeout_s": 900.0}) == []
    default = run_settings(run_options(parser.parse_args(["sweep", "--param", "noise=0.1"])))
    assert default["trial_timeout_s"] == 600.0
    for bad in ("0", "-1", "inf", "soon"):
        with pytest.raises(SystemExit):
            parser.parse_args(["regrasp", "--trial-timeout", bad])


def test_a_real_trial_past_the_limit_on_the_command_line_then_retried(tmp_path):
    """`comgrasp accuracy --workers 1 --trial-timeout 0.5`: the real trial (seconds of
    MuJoCo) is stopped and its row says so; the settings record the limit; --retry-failed
    with the default limit runs it to the end."""
    from comgrasp_pin.cli import main

    base = ["accuracy", "--objects", "obj1", "--trials", "1", "--workers", "1",
            "--out", str(tmp_path)]  # fmt: skip
    assert main([*base, "--trial-timeout", "0.5"]) == 0
    (row,) = read_rows(tmp_path / "accuracy.csv")
    assert row["error"].startswith("comgrasp_pin.errors.TrialTimeoutError")
    settings = json.loads((tmp_path / "accuracy.settings.json").read_text())
    assert settings["trial_timeout_s"] == 0.5
    assert main([*base, "--retry-failed"]) == 0
    (row,) = read_rows(tmp_path / "accuracy.csv")
    assert row["error"] == "" and 0.0 < float(row["accuracy"]) <= 1.0
    settings = json.loads((tmp_path / "accuracy.settings.json").read_text())
    assert settings["trial_timeout_s"] == 600.0


def test_a_stopped_run_leaves_no_late_row_for_the_next_run_on_kept_workers(tmp_path):
    """A run that stops (its CSV cannot take a row) while a kept worker still runs a trial:
    that worker is killed, so the next run on the kept set gets its own rows only."""
    from _slow_task import sleep_and_record_pid

    from comgrasp_pin.errors import OutputError
    from comgrasp_pin.experiments.workers import WorkerSet, safe_call

    def task(k, sleep_s):
        return {"object": "obj1", "trial": k, "method": "m", "pid_dir": str(tmp_path),
                "sleep_s": sleep_s}  # fmt: skip

    def full_disk(*rows):
        raise OutputError("no room")

    got = []
    with WorkerSet(2) as kept:
        with pytest.raises(OutputError):
            kept.run(safe_call, sleep_and_record_pid, [task(0, 0.0), task(1, 3.0)], full_disk)
        kept.run(safe_call, sleep_and_record_pid, [task(k, 0.0) for k in (5, 6, 7)],
                 lambda *rows: got.extend(rows))  # fmt: skip
    assert sorted(r["trial"] for r in got) == [5, 6, 7]
    assert all(r["error"] == "" for r in got)
