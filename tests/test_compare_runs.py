"""benchmarks/compare_runs.py: identical rows, last digits moved within --rtol, outcomes."""

from __future__ import annotations

import csv
import importlib.util
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
_spec = importlib.util.spec_from_file_location(
    "compare_runs", ROOT / "benchmarks" / "compare_runs.py"
)
compare_runs = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(compare_runs)

COLUMNS = ["object", "trial", "method", "mass_esti_kg", "success", "wall_s", "error"]


def _write(folder: Path, rows: list[list]) -> Path:
    folder.mkdir()
    with open(folder / "regrasp.csv", "w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(COLUMNS)
        writer.writerows(rows)
    return folder


def test_last_digits_are_a_difference_unless_within_rtol_and_outcomes_always_are(tmp_path):
    before = _write(tmp_path / "a", [["obj1", 0, "regrasp", "0.6225853166451396", "True", 1.0, ""],
                                     ["obj2", 0, "regrasp", "0.5", "True", 2.0, ""]])  # fmt: skip
    after = _write(tmp_path / "b", [["obj1", 0, "regrasp", "0.6225853166451391", "True", 9.0, ""],
                                    ["obj2", 0, "regrasp", "0.5", "False", 2.0, ""]])  # fmt: skip
    exact = compare_runs.compare(before, after)["regrasp.csv"]
    assert [d["columns"] for d in exact["differences"]] == [["mass_esti_kg"], ["success"]]
    paired = compare_runs.compare(before, after, rtol=1e-12)["regrasp.csv"]
    assert [d["columns"] for d in paired["differences"]] == [["success"]]  # never within rtol
    assert paired["moved"]["rows"] == 1
    moved = paired["moved"]["max_relative_by_column"]["mass_esti_kg"]
    assert moved == abs(0.6225853166451396 - 0.6225853166451391) / 0.6225853166451396
    same = compare_runs.compare(before, before, rtol=1e-12)["regrasp.csv"]
    assert same["differences"] == [] and same["moved"]["rows"] == 0
