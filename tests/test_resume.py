"""Runs that cannot be mixed or damaged: settings beside the CSV, cut lines repaired, other
headers refused, failed rows retried (issue 15)."""

import csv
import json
import warnings
from pathlib import Path

import pytest

from comgrasp_pin.cli import main
from comgrasp_pin.errors import ComGraspError, OutputError, ResumeError, UnstablePhysicsError
from comgrasp_pin.experiments.run_files import read_results, settings_path
from comgrasp_pin.experiments.runner import read_rows, run_trials

COLUMNS = ["object", "trial", "method", "value"]
SETTINGS = {"seed": 0, "noise": 0.05, "config": {"a": {"b": 1}}, "objects": ["obj1"], "trials": 4}


def _value(task: dict) -> dict:
    return {"value": task["trial"] * 10}


def _tasks(n: int, objects=("obj1",)) -> list[dict]:
    return [{"object": o, "trial": k, "method": "m"} for k in range(n) for o in objects]


def _run(path, n=4, fn=_value, **kwargs):
    kwargs.setdefault("settings", SETTINGS)
    return run_trials(fn, _tasks(n), path, COLUMNS, **kwargs)


def _lines(path) -> list[str]:
    return path.read_text().splitlines()


# --- settings ---------------------------------------------------------------------------


def test_settings_are_recorded_beside_the_csv(tmp_path):
    path = tmp_path / "accuracy.csv"
    _run(path)
    assert settings_path(path) == tmp_path / "accuracy.settings.json"
    assert json.loads(settings_path(path).read_text()) == SETTINGS


@pytest.mark.parametrize(
    ("change", "named"),
    [({"seed": 1}, "seed: 0 in the run, 1 now"),
     ({"noise": 0.1}, "noise: 0.05 in the run, 0.1 now"),
     ({"config": {"a": {"b": 2}}}, "config.a.b: 1 in the run, 2 now"),
     ({"version": "9.9"}, "version: 'not set' in the run, '9.9' now")],
)  # fmt: skip
def test_resume_refuses_other_settings_and_names_them(tmp_path, change, named):
    path = tmp_path / "out.csv"
    _run(path)
    before = path.read_bytes()
    with pytest.raises(ResumeError) as info:
        _run(path, resume=True, settings={**SETTINGS, **change})
    assert named in str(info.value)
    assert path.read_bytes() == before


def test_trials_and_objects_may_grow(tmp_path):
    path = tmp_path / "out.csv"
    _run(path, n=2, settings={**SETTINGS, "trials": 2})
    calls = []

    def counting(task):
        calls.append((task["object"], task["trial"]))
        return _value(task)

    grown = {**SETTINGS, "trials": 3, "objects": ["obj1", "obj2"]}
    rows = run_trials(counting, _tasks(3, ("obj1", "obj2")), path, COLUMNS, resume=True,
                      settings=grown)  # fmt: skip
    assert sorted(calls) == [("obj1", 2), ("obj2", 0), ("obj2", 1), ("obj2", 2)]
    assert len(rows) == len(read_rows(path)) == 6
    recorded = json.loads(settings_path(path).read_text())
    assert recorded["trials"] == 3 and recorded["objects"] == ["obj1", "obj2"]


def test_resume_without_recorded_settings_is_refused(tmp_path):
    path = tmp_path / "out.csv"
    _run(path)
    settings_path(path).unlink()
    with pytest.raises(ResumeError, match="no out.settings.json beside it"):
        _run(path, resume=True)
    for damaged, message in (("{not json", "cannot read"), ("[1, 2]", "does not hold")):
        settings_path(path).write_text(damaged)
        with pytest.raises(ResumeError, match=message):
            _run(path, resume=True)


def test_cli_resume_with_another_seed_or_noise_exits_2(tmp_path, capsys):
    out = tmp_path / "run"
    base = ["accuracy", "--objects", "obj1", "--trials", "1", "--workers", "1", "--out", str(out)]
    assert main(base) == 0
    before = (out / "accuracy.csv").read_bytes()
    recorded = json.loads((out / "accuracy.settings.json").read_text())
    assert recorded["seed"] == 0 and recorded["noise"] == 0.05
    assert recorded["config"]["sensors"]["torque"]["noise_std"] == 0.05
    assert recorded["version"] and recorded["estimator"] == "ipopt"
    capsys.readouterr()
    assert main([*base, "--resume", "--seed", "1"]) == 2
    assert "seed: 0 in the run, 1 now" in capsys.readouterr().err
    assert main([*base, "--resume", "--noise", "0.1"]) == 2
    err = capsys.readouterr().err
    assert "noise: 0.05 in the run, 0.1 now" in err and "Traceback" not in err
    assert main([*base]) == 2  # neither --resume nor --overwrite
    assert "already holds results" in capsys.readouterr().err
    assert (out / "accuracy.csv").read_bytes() == before


# --- damaged files ----------------------------------------------------------------------


@pytest.mark.parametrize("cut", ["half", "newline"])
def test_a_cut_last_line_is_dropped_with_a_warning_and_its_trial_rerun(tmp_path, cut):
    path = tmp_path / "out.csv"
    _run(path)
    whole = path.read_bytes()
    last = whole.rstrip(b"\r\n").rfind(b"\n") + 1
    # killed half-way through the last row, or just before its newline
    path.write_bytes(whole[: last + 5] if cut == "half" else whole.rstrip(b"\r\n"))
    calls = []

    def counting(task):
        calls.append(task["trial"])
        return _value(task)

    with pytest.warns(UserWarning, match="the last line was cut"):
        rows = _run(path, fn=counting, resume=True)
    assert calls == [3]
    assert path.read_bytes() == whole
    assert [int(r["value"]) for r in rows] == [0, 10, 20, 30]


def test_another_header_is_refused(tmp_path):
    path = tmp_path / "out.csv"
    _run(path)
    text = path.read_text().replace("value", "other", 1)
    path.write_text(text)
    with pytest.raises(ResumeError, match=r"another header .*not expected: \['other'\]"):
        _run(path, resume=True)
    assert path.read_text() == text


def test_a_damaged_row_before_the_last_is_refused(tmp_path):
    path = tmp_path / "out.csv"
    _run(path)
    lines = path.read_text().splitlines(keepends=True)
    lines[2] = lines[2].rstrip("\r\n") + lines[3]  # two rows glued: 4 + 1 + 4 fields
    path.write_text("".join(lines))
    with pytest.raises(ResumeError, match="line 3 has 9 fields, the header 5"):
        _run(path, resume=True)


def test_the_cli_repairs_a_cut_csv_and_writes_the_same_rows(tmp_path, capsys):
    out = tmp_path / "run"
    base = ["accuracy", "--objects", "obj1", "--trials", "2", "--workers", "1", "--out", str(out)]
    assert main(base) == 0
    csv_path = out / "accuracy.csv"
    first = read_rows(csv_path)
    data = csv_path.read_bytes()
    csv_path.write_bytes(data[: len(data) - 40])  # killed while writing the second row
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        assert main([*base, "--resume"]) == 0
    assert any("the last line was cut" in str(w.message) for w in caught)
    again = read_rows(csv_path)
    assert len(again) == 2

    def same(rows):
        return [{k: v for k, v in r.items() if k != "wall_s"} for r in rows]

    assert same(again) == same(first)
    assert "accuracy" in (out / "accuracy_table.md").read_text().lower()


# --- failed rows ------------------------------------------------------------------------


def _fails_on_two(task: dict) -> dict:
    if task["trial"] == 2:
        raise UnstablePhysicsError("trial two failed")  # the world failed it: a row
    return _value(task)


def test_failed_rows_count_as_done_without_retry_failed(tmp_path):
    path = tmp_path / "out.csv"
    _run(path, fn=_fails_on_two)
    calls = []
    _run(path, fn=lambda t: calls.append(t) or _value(t), resume=True)
    assert calls == []


def test_retry_failed_reruns_the_failed_rows_and_replaces_them(tmp_path):
    path = tmp_path / "out.csv"
    _run(path, fn=_fails_on_two)
    assert [r["error"] != "" for r in read_rows(path)] == [False, False, True, False]
    rows = _run(path, resume=True, retry_failed=True)
    on_disk = read_rows(path)
    assert len(rows) == len(on_disk) == 4
    assert all(r["error"] == "" for r in on_disk)
    assert sorted(int(r["value"]) for r in on_disk) == [0, 10, 20, 30]
    assert sorted(p.name for p in tmp_path.iterdir() if not p.name.endswith(".lock")) == [
        "out.csv",
        "out.settings.json",
    ]  # no temporary file left


def test_rows_are_whole_on_disk_while_the_run_goes_on(tmp_path):
    path = tmp_path / "out.csv"
    seen = []

    def peeking(task):
        rows, repaired = read_results(path, [*COLUMNS, "error"])
        seen.append((len(rows), repaired, path.read_bytes().endswith(b"\n")))
        return _value(task)

    _run(path, fn=peeking)
    assert seen == [(k, False, True) for k in range(4)]


def test_duplicate_tasks_are_refused(tmp_path):
    with pytest.raises(ComGraspError, match="listed more than once"):
        run_trials(_value, _tasks(2) + _tasks(1), tmp_path / "out.csv", COLUMNS)


def test_rows_keep_commas_quotes_and_newlines_on_one_line(tmp_path):
    path = tmp_path / "out.csv"

    def awkward(task):
        raise ValueError('bad, "quoted"\nsecond line')

    _run(path, fn=awkward, n=2)
    assert len(_lines(path)) == 3
    rows = list(csv.DictReader(path.open(newline="")))
    assert rows[0]["error"] == 'internal error: ValueError: bad, "quoted" second line'


def test_a_second_run_on_the_same_csv_is_refused(tmp_path):
    path = tmp_path / "out.csv"
    outcome = []

    def nested(task):
        if task["trial"] == 1:  # another run starts on the same CSV while this one writes
            try:
                _run(path, resume=True)
            except ResumeError as exc:
                outcome.append(str(exc))
        return _value(task)

    _run(path, fn=nested)
    assert len(outcome) == 1 and "another run is writing" in outcome[0]
    assert [int(r["value"]) for r in read_rows(path)] == [0, 10, 20, 30]
    _run(path, resume=True)  # the lock went with the run


def test_rows_that_finished_together_are_written_whole_with_one_fsync(tmp_path):
    from comgrasp_pin.experiments.run_files import RowAppender, rewrite

    path, columns = tmp_path / "out.csv", [*COLUMNS, "error"]
    rewrite(path, columns, [])
    with RowAppender(path, columns) as out:
        out.write_rows(
            [{"object": "obj1", "trial": k, "method": "m", "value": k} for k in range(3)]
        )
        assert out.written == 3
    rows, repaired = read_results(path, columns)
    assert [r["value"] for r in rows] == ["0", "1", "2"] and not repaired
    with RowAppender(Path("/dev/full"), columns) as out, pytest.raises(OutputError):
        out.write_rows(rows)
