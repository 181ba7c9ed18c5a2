"""Faults survived, injected for real (issue 15): a worker process that dies mid-trial, a
disk that takes no more bytes, physics that goes unstable."""

import os
import signal
import subprocess
import sys
import textwrap
import threading
from pathlib import Path

import numpy as np
import pytest

from comgrasp_pin.errors import OutputError, UnstablePhysicsError
from comgrasp_pin.experiments.run_files import RowAppender
from comgrasp_pin.experiments.runner import WORKER_DIED, read_rows, run_trials

COLUMNS = ["object", "trial", "method", "value", "pid"]


def _tasks(n):
    return [{"object": "obj1", "trial": k, "method": "m"} for k in range(n)]


def _exits_on_two(task: dict) -> dict:
    """A trial kind for this test only: trial 2 ends its process at once."""
    if task["trial"] == 2:
        os._exit(3)
    return {"value": task["trial"] * 10, "pid": os.getpid()}


def _killed_on_one(task: dict) -> dict:
    """Trial 1 is killed by a signal (as by the OOM killer) while it runs."""
    if task["trial"] == 1:
        os.kill(os.getpid(), signal.SIGKILL)
    return {"value": task["trial"] * 10, "pid": os.getpid()}


def _value(task: dict) -> dict:
    return {"value": task["trial"] * 10, "pid": os.getpid()}


@pytest.mark.parametrize("fn", [_exits_on_two, _killed_on_one])
def test_a_worker_that_dies_fails_its_trial_only_and_can_be_retried(tmp_path, fn):
    path = tmp_path / "out.csv"
    rows = run_trials(fn, _tasks(6), path, COLUMNS, workers=2)
    dead = 2 if fn is _exits_on_two else 1
    on_disk = read_rows(path)
    assert len(rows) == len(on_disk) == 6
    assert sorted(int(r["trial"]) for r in on_disk) == list(range(6))
    for row in on_disk:
        if int(row["trial"]) == dead:
            assert row["error"] == f"comgrasp_pin.errors.WorkerDiedError: {WORKER_DIED}"
        else:
            assert row["error"] == "" and int(row["value"]) == 10 * int(row["trial"])
    rows = run_trials(_value, _tasks(6), path, COLUMNS, resume=True, retry_failed=True)
    assert [r["error"] for r in read_rows(path)] == [""] * 6


def _accuracy_killed_mid_trial(task: dict) -> dict:
    """A real accuracy trial (MuJoCo running) whose process dies 0.5 s into trial 0."""
    from comgrasp_pin.experiments.trials import accuracy_trial

    if task["trial"] == 0:
        threading.Timer(0.5, os._exit, (9,)).start()
    return accuracy_trial(task)


@pytest.mark.slow
def test_a_real_trial_killed_mid_simulation_is_recorded_and_the_run_goes_on(tmp_path):
    from comgrasp_pin.experiments.trials import ACCURACY_COLUMNS, make_tasks

    tasks = make_tasks(["obj1"], 2, 0, ("trial",))
    rows = run_trials(_accuracy_killed_mid_trial, tasks, tmp_path / "a.csv", ACCURACY_COLUMNS,
                      workers=2)  # fmt: skip
    by_trial = {int(r["trial"]): r for r in read_rows(tmp_path / "a.csv")}
    assert len(rows) == 2 and "WorkerDiedError" in by_trial[0]["error"]
    assert by_trial[1]["error"] == "" and 0.0 < float(by_trial[1]["accuracy"]) <= 1.0


# --- full disk ----------------------------------------------------------------------------


def test_a_write_to_a_full_disk_is_an_output_error():
    with RowAppender(Path("/dev/full"), COLUMNS) as out:
        with pytest.raises(OutputError, match="No space left on device.*intact.*--resume"):
            out.write({"object": "obj1", "trial": 0, "method": "m", "value": 1})


_FILLS_UP = """
import resource, signal, sys
from pathlib import Path
from comgrasp_pin.cli import main
from comgrasp_pin.experiments import run_files

real_write = run_files.RowAppender.write_rows
csv_path = Path(sys.argv[1]) / "accuracy.csv"

def write_then_disk_full(self, rows):  # in the driver: trials run in worker processes
    real_write(self, rows)
    if self.written == 1:  # from now on the CSV cannot grow by a row: EFBIG at write
        limit = csv_path.stat().st_size + 20
        resource.setrlimit(resource.RLIMIT_FSIZE, (limit, resource.getrlimit(
            resource.RLIMIT_FSIZE)[1]))

signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # the write fails instead of killing us
run_files.RowAppender.write_rows = write_then_disk_full
sys.exit(main(["accuracy", "--objects", "obj1", "--trials", "3", "--workers", "1",
               "--out", sys.argv[1]]))
"""


@pytest.mark.slow
def test_a_full_disk_stops_the_run_cleanly_with_every_finished_row_intact(tmp_path):
    out = tmp_path / "run"
    result = subprocess.run([sys.executable, "-c", textwrap.dedent(_FILLS_UP), str(out)],
                            capture_output=True, text=True, check=False,
                            env={**os.environ, "MUJOCO_GL": "egl"})  # fmt: skip
    assert result.returncode == 2, result.stderr
    assert "Traceback" not in result.stderr
    assert "error: cannot write to" in result.stderr and "File too large" in result.stderr
    data = (out / "accuracy.csv").read_bytes()
    assert data.endswith(b"\n")
    rows = read_rows(out / "accuracy.csv")
    assert [r["trial"] for r in rows] == ["0"] and rows[0]["error"] == ""
    from comgrasp_pin.cli import main

    assert main(["accuracy", "--objects", "obj1", "--trials", "2", "--workers", "1",
                 "--out", str(out), "--resume"]) == 0  # fmt: skip
    assert [r["trial"] for r in read_rows(out / "accuracy.csv")] == ["0", "1"]


# --- unstable physics ---------------------------------------------------------------------


@pytest.mark.parametrize(
    ("break_it", "warning"),
    [(lambda s: s.data.qfrc_applied.__setitem__(0, 1e300), "mjWARN_BADQACC"),
     (lambda s: s.data.qvel.__setitem__(0, 1e30), "mjWARN_BADQVEL"),
     (lambda s: s.data.qpos.__setitem__(0, np.nan), "mjWARN_BADQPOS"),
     (lambda s: s.q_des.__setitem__(0, np.nan), "mjWARN_BADCTRL")],
)  # fmt: skip
def test_unstable_physics_raises_instead_of_going_on_from_a_reset(break_it, warning):
    from comgrasp_pin.simulation.sim import Simulation

    sim = Simulation()
    sim.step(5)
    break_it(sim)
    with pytest.raises(UnstablePhysicsError, match=warning):
        sim.step(5)


def _unstable_trial(task: dict) -> dict:
    """A trial kind for this test only: a real world whose physics blows up at trial 1."""
    from comgrasp_pin.simulation.sim import Simulation

    sim = Simulation()
    if task["trial"] == 1:
        sim.data.qfrc_applied[2] = 1e300
    sim.hold(0.02)
    return {"value": float(sim.q[2]), "pid": os.getpid()}


def test_unstable_physics_is_a_failed_trial_with_that_reason(tmp_path):
    rows = run_trials(_unstable_trial, _tasks(3), tmp_path / "out.csv", COLUMNS)
    errors = [r["error"] for r in read_rows(tmp_path / "out.csv")]
    assert errors[0] == errors[2] == "" and len(rows) == 3
    assert errors[1].startswith("comgrasp_pin.errors.UnstablePhysicsError: the simulation went "
                                "unstable")  # fmt: skip
    assert "mjWARN_BADQACC" in errors[1]
