"""A failed trial is data only when the world failed it (issue 33, item 3).

A trial that raises a ``ComGraspError`` is a row counted as a failed trial, as before. One
that raises anything else (here a ``TypeError``: a bug) is a row marked ``internal error``
with its traceback kept beside the CSV; the report counts it in no rate or mean and names
it; the command ends with exit status 1 naming it; ``--resume`` runs it again. Through the
real worker paths: in this process, one worker process, two worker processes."""

import numpy as np
import pytest

from comgrasp_pin.errors import ComGraspError, InternalTrialError, RodDroppedError
from comgrasp_pin.experiments import report
from comgrasp_pin.experiments.internal_errors import (
    fail_on_internal_errors,
    is_internal_error,
    tracebacks_path,
)
from comgrasp_pin.experiments.runner import read_rows, run_trials

COLUMNS = ["object", "trial", "method", "value"]
BUG = "unsupported operand type(s) for +: 'int' and 'str'"


def _trial(task: dict) -> dict:
    """Trial 1 has a bug, trial 2 drops the rod (the world's failure), the others a value."""
    if task["trial"] == 1:
        return {"value": _add(task["trial"], "ten")}
    if task["trial"] == 2:
        raise RodDroppedError("it slid out of the jaws")
    return {"value": task["trial"] * 10}


def _add(a, b):
    return a + b  # the TypeError is raised here, two frames below the worker


def _fixed(task: dict) -> dict:
    """The same trials with the bug fixed (and the rod still dropped in trial 2)."""
    if task["trial"] == 2:
        raise RodDroppedError("it slid out of the jaws")
    return {"value": task["trial"] * 10, "rerun": True}


def _tasks(n=4):
    return [{"object": "obj1", "trial": k, "method": "m"} for k in range(n)]


RUNS = {  # the three ways a local run calls a trial
    "in this process": {},
    "one worker process": {"trial_timeout_s": 60.0},
    "two worker processes": {"workers": 2},
}


@pytest.mark.parametrize("run", list(RUNS), ids=lambda r: r.replace(" ", "-"))
def test_a_bug_is_an_internal_error_row_with_its_traceback_kept(tmp_path, run):
    path = tmp_path / "out.csv"
    rows = run_trials(_trial, _tasks(), path, COLUMNS, **RUNS[run])
    on_disk = {int(r["trial"]): r for r in read_rows(path)}
    assert len(rows) == len(on_disk) == 4
    assert on_disk[1]["error"] == f"internal error: TypeError: {BUG}"
    assert is_internal_error(on_disk[1]) and not is_internal_error(on_disk[2])
    assert on_disk[2]["error"].endswith("RodDroppedError: the rod was dropped in the trial "
                                        "grasp: it slid out of the jaws")  # fmt: skip
    assert [on_disk[k]["value"] for k in (0, 3)] == ["0", "30"]
    assert all("traceback" not in r for r in rows)  # kept in the file, not in the rows
    text = tracebacks_path(path).read_text()
    assert text.startswith("=== object=obj1, trial=1, method=m (")
    assert "Traceback (most recent call last)" in text and f"TypeError: {BUG}" in text
    assert "in _trial" in text and "in _add" in text and "return a + b" in text
    assert "RodDroppedError" not in text  # the world's failure is a row, not a bug


def test_resume_runs_the_internal_errors_again_and_keeps_the_worlds_failures(tmp_path):
    path = tmp_path / "out.csv"
    run_trials(_trial, _tasks(), path, COLUMNS)
    calls = []

    def fixed(task):
        calls.append(task["trial"])
        return _fixed(task)

    rows = run_trials(fixed, _tasks(), path, COLUMNS, resume=True)
    assert calls == [1]  # the bug's trial only: the dropped rod is an outcome, kept
    on_disk = sorted(read_rows(path), key=lambda r: int(r["trial"]))
    assert len(rows) == len(on_disk) == 4
    assert [r["value"] for r in on_disk] == ["0", "10", "", "30"]
    assert not any(is_internal_error(r) for r in on_disk)
    assert "RodDroppedError" in on_disk[2]["error"]
    assert "TypeError" in tracebacks_path(path).read_text()  # the earlier run's, kept
    run_trials(_fixed, _tasks(), path, COLUMNS, resume=True, retry_failed=True)
    again = sorted(read_rows(path), key=lambda r: int(r["trial"]))
    assert [r["error"] != "" for r in again] == [False, False, True, False]
    run_trials(_value, _tasks(), path, COLUMNS, overwrite=True)
    assert not tracebacks_path(path).exists()  # a new run: no earlier run's tracebacks


def _value(task: dict) -> dict:
    return {"value": 1}


def test_the_run_fails_at_its_end_naming_the_trials_and_the_tracebacks(tmp_path):
    ran = []
    with pytest.raises(InternalTrialError) as caught, fail_on_internal_errors():
        run_trials(_trial, _tasks(), tmp_path / "a.csv", COLUMNS)
        ran.append("a")
        run_trials(_trial, _tasks(6), tmp_path / "b.csv", COLUMNS, workers=2)
        ran.append("b")  # the runs after the bug's went on
    assert ran == ["a", "b"]
    exc = caught.value
    assert isinstance(exc, RuntimeError) and isinstance(exc, ComGraspError)
    assert not isinstance(exc, ValueError)
    assert exc.trials == ["object=obj1, trial=1, method=m"] * 2
    assert exc.traceback_paths == [tmp_path / "a.tracebacks.txt", tmp_path / "b.tracebacks.txt"]
    message = str(exc)
    assert message.startswith("2 trial(s) ended in an internal error")
    assert f"object=obj1, trial=1, method=m in {tmp_path / 'a.csv'} (internal error: TypeError"
    assert str(tmp_path / "b.tracebacks.txt") in message and "--resume" in message
    with fail_on_internal_errors() as found:  # none: no error
        run_trials(_fixed, _tasks(), tmp_path / "c.csv", COLUMNS)
    assert found == []
    with pytest.raises(KeyError), fail_on_internal_errors():  # its own error is not masked
        run_trials(_trial, _tasks(), tmp_path / "d.csv", COLUMNS)
        raise KeyError("the command's own failure")


def test_the_command_exits_1_naming_the_trials_and_where_the_tracebacks_are(tmp_path, capsys):
    from comgrasp_pin.cli.experiments import exit_status

    def run():
        run_trials(_trial, _tasks(), tmp_path / "accuracy.csv", COLUMNS, trial_timeout_s=60.0)
        print("report written")

    assert exit_status("accuracy", run) == 1
    out, err = capsys.readouterr()
    assert "report written" in out  # the command went to its end
    message = err.split("\n")[-2]  # the last line (the progress bar's are before it)
    assert message.startswith("comgrasp accuracy: error: 1 trial(s) ended in an internal error")
    assert "object=obj1, trial=1, method=m" in message
    assert str(tmp_path / "accuracy.tracebacks.txt") in message
    assert "Traceback (most recent call last)" not in err  # in the file, not on the screen
    assert exit_status("accuracy", lambda: None) == 0


def test_the_real_command_line_exits_1_and_its_report_leaves_the_bug_out(
    tmp_path, monkeypatch, capsys
):
    """`comgrasp accuracy` on real trials, one of them with a bug put in (a trial function
    that sends trial 1 to a TypeError), in a worker process: the table and figure are
    written from the other grasp, the CSV holds both rows, the exit status is 1."""
    from comgrasp_pin.cli import main
    from comgrasp_pin.experiments import reproduce

    monkeypatch.setattr(reproduce, "accuracy_trial", _accuracy_with_a_bug)
    out = tmp_path / "acc"
    status = main(["accuracy", "--objects", "obj1", "--trials", "2", "--workers", "1",
                   "--out", str(out)])  # fmt: skip
    err = capsys.readouterr().err
    assert status == 1
    assert "comgrasp accuracy: error: 1 trial(s) ended in an internal error" in err
    assert "object=obj1, trial=1, method=trial" in err
    assert str(out / "accuracy.tracebacks.txt") in err
    rows = {int(r["trial"]): r for r in read_rows(out / "accuracy.csv")}
    assert rows[1]["error"] == f"internal error: TypeError: {BUG}"
    assert rows[0]["error"] == "" and np.isfinite(float(rows[0]["accuracy"]))
    assert "_accuracy_with_a_bug" in (out / "accuracy.tracebacks.txt").read_text()
    assert (out / "accuracy.png").exists()
    table = (out / "accuracy_table.md").read_text()
    assert table == report.accuracy_table([rows[0]]) + "\n"  # as if the bug's row were not
    # --resume with the bug fixed runs that trial only, and the command succeeds
    monkeypatch.setattr(reproduce, "accuracy_trial", _accuracy_fixed)
    assert main(["accuracy", "--objects", "obj1", "--trials", "2", "--workers", "1",
                 "--out", str(out), "--resume"]) == 0  # fmt: skip
    again = {int(r["trial"]): r for r in read_rows(out / "accuracy.csv")}
    assert again[0] == rows[0] and again[1]["error"] == ""


def _accuracy_with_a_bug(task: dict) -> dict:
    if task["trial"] == 1:
        return {"accuracy": _add(1, "ten")}
    from comgrasp_pin.experiments.trials import accuracy_trial

    return accuracy_trial(task)


def _accuracy_fixed(task: dict) -> dict:
    from comgrasp_pin.experiments.trials import accuracy_trial

    return accuracy_trial(task)


# --- the report counts no internal error ---------------------------------------------------


def _regrasp_rows():
    rows = []
    for k in range(10):
        rows.append({"object": "obj1", "trial": k, "method": "baseline", "success": int(k < 7)})
        rows.append({"object": "obj1", "trial": k, "method": "regrasp", "success": int(k < 9)})
    rows.append({"object": "obj1", "trial": 10, "method": "regrasp", "success": "",
                 "error": "comgrasp_pin.errors.RodDroppedError: the rod was dropped"})  # fmt: skip
    return rows


BUG_ROWS = [
    {"object": "obj1", "trial": 11, "method": "regrasp", "success": "",
     "error": f"internal error: TypeError: {BUG}"},
    {"object": "obj1", "trial": 12, "method": "baseline", "success": "",
     "error": "internal error: KeyError: 'q'"},
]  # fmt: skip


def test_the_run_summary_names_internal_errors_and_counts_them_nowhere():
    acc = [{"object": "obj1", "seed": 1000 + k, "method": "trial", "accuracy": 0.9}
           for k in range(3)]  # fmt: skip
    acc_bug = [*acc, {"object": "obj1", "seed": 1003, "trial": 3, "method": "trial",
                      "error": "internal error: AttributeError: 'NoneType'"}]  # fmt: skip
    reg = _regrasp_rows()
    plain = report.run_summary(acc, reg, seed=0)
    text = report.run_summary(acc_bug, [*reg, *BUG_ROWS], seed=0)
    assert text.startswith(plain)  # the same counts, rates and failures
    assert "1 trial(s) failed with an error" in plain
    assert "3 trial(s) ended in an internal error" in text
    assert "obj1 trial 11 (regrasp): TypeError" in text and "obj1 trial 3 (trial)" in text


def test_verdicts_and_tables_of_selected_rows_leave_internal_errors_out():
    reg = _regrasp_rows()
    with_bugs = [*reg, *BUG_ROWS]
    assert report.regrasp_verdict(with_bugs) == report.regrasp_verdict(reg)
    assert "regrasp" in report.regrasp_verdict(with_bugs)
    acc = [{"object": "obj1", "trial": k, "method": "trial", "theta_deg": 5.0 * k,
            "theta_true_deg": 5.0 * k, "accuracy": 0.9 + 0.01 * k, "length_m": 0.4,
            "pos_real_m": 0.0, "pos_esti_m": 0.001 * k, "pos_std_m": 0.002, "error": ""}
           for k in range(6)]  # fmt: skip
    acc_bug = [
        *acc,
        {"object": "obj1", "trial": 6, "method": "trial", "error": BUG_ROWS[0]["error"]},
    ]
    assert report.accuracy_table(acc_bug) == report.accuracy_table(acc)
    assert report.accuracy_verdict(acc_bug) == report.accuracy_verdict(acc)
    assert report.calibration_table(acc_bug) == report.calibration_table(acc)


def test_a_sweeps_rates_and_means_leave_internal_errors_out():
    from comgrasp_pin.experiments.sweep import point_measures

    acc = [{"accuracy": 0.9, "pos_esti_m": 0.0, "pos_real_m": 0.001, "pos_std_m": 0.002,
            "error": ""} for _ in range(4)]  # fmt: skip
    dropped = {"accuracy": "", "error": "comgrasp_pin.errors.RodDroppedError: dropped"}
    bug = {"accuracy": "", "error": BUG_ROWS[0]["error"]}
    plain = point_measures([*acc, dropped], "accuracy")
    assert point_measures([*acc, dropped, bug, bug], "accuracy") == plain
    assert plain["success"][3] == 5  # the dropped rod is a failed trial; the bugs are not
    reg = [{**acc[0], "method": "regrasp", "success": 1}] * 3
    with_bug = [*reg, {**bug, "method": "regrasp", "success": ""}]
    assert point_measures(with_bug, "regrasp")["success"][:1] == (100.0,)


def test_success_rates_leave_internal_errors_out():
    assert report.success_rates([*_regrasp_rows(), *BUG_ROWS]) == report.success_rates(
        _regrasp_rows()
    )
