"""Are two runs' rows identical, every column except wall_s? (a speed change's check)

    python benchmarks/compare_runs.py BEFORE_DIR AFTER_DIR [--common] [--rtol R]
                                      [--out compare.json]

Compares every CSV the two folders share (accuracy.csv, regrasp.csv, sweep.csv) row by row,
matched by object, trial and method (and a sweep's swept values), as text: a float that
moved in its last bit is a difference. ``--common``: only the rows both runs have (a short
run's first trials against a long run with the same seed). ``--rtol R``: the paired
equivalence of a change that moves last digits (a faster solver's rounding): a number
counts as the same within R relative (1e-300 absolute), any other column (outcome, reason,
error) must be the same text; each CSV also reports ``moved``, the largest relative change
per column among the rows that differ only within R. Exit status 0 when identical (within R),
1 otherwise.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from comgrasp_pin.experiments.runner import read_rows

IGNORED = ("wall_s",)


def _keyed(rows: list[dict]) -> dict[tuple, dict]:
    key_columns = [c for c in rows[0] if "." in c] + ["object", "trial", "method"] if rows else []
    return {tuple(r[c] for c in key_columns): r for r in rows}


def _same(x: str, y: str | None, rtol: float) -> bool:
    if x == y or y is None or rtol <= 0:
        return x == y
    try:
        a, b = float(x), float(y)
    except ValueError:
        return False
    return abs(a - b) <= rtol * max(abs(a), abs(b)) + 1e-300


def _relative(x: str, y: str) -> float:
    a, b = float(x), float(y)
    return abs(a - b) / max(abs(a), abs(b), 1e-300)


def compare(before: Path, after: Path, common: bool = False, rtol: float = 0.0) -> dict:
    out = {}
    for path in sorted(before.glob("*.csv")):
        if not (after / path.name).exists():
            continue
        a, b = _keyed(read_rows(path)), _keyed(read_rows(after / path.name))
        differences, moved, moved_rows = [], {}, 0
        keys = set(a) & set(b) if common else set(a) | set(b)
        for key in sorted(keys):
            if key not in a or key not in b:
                differences.append({"row": key, "only_in": "after" if key in b else "before"})
                continue
            ra, rb = a[key], b[key]
            columns = [c for c in ra if c not in IGNORED and not _same(ra[c], rb.get(c), rtol)]
            if columns:
                differences.append({"row": key, "columns": columns})
                continue
            within = [c for c in ra if c not in IGNORED and ra[c] != rb.get(c)]
            moved_rows += bool(within)
            for c in within:
                moved[c] = max(moved.get(c, 0.0), _relative(ra[c], rb[c]))
        out[path.name] = {"rows": len(keys), "columns_compared": len(next(iter(a.values()), {}))
                          - len(IGNORED), "differences": differences}  # fmt: skip
        if rtol > 0:
            out[path.name]["moved"] = {"rows": moved_rows, "max_relative_by_column": moved}
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("before", type=Path)
    parser.add_argument("after", type=Path)
    parser.add_argument("--common", action="store_true", help="compare the shared rows only")
    parser.add_argument(
        "--rtol",
        type=float,
        default=0.0,
        help="numbers within this relative difference count as the same",
    )
    parser.add_argument("--out", type=Path, default=None)
    args = parser.parse_args()
    result = compare(args.before, args.after, args.common, args.rtol)
    text = json.dumps(result, indent=2, default=str)
    if args.out:
        args.out.write_text(text + "\n")
    print(text)
    same = result and all(r["rows"] and not r["differences"] for r in result.values())
    sys.exit(0 if same else 1)


if __name__ == "__main__":
    main()
