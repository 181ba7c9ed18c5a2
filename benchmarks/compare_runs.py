"""Are two runs' rows identical, every column except wall_s? (a speed change's check)

    python benchmarks/compare_runs.py BEFORE_DIR AFTER_DIR [--common] [--out compare.json]

Compares every CSV the two folders share (accuracy.csv, regrasp.csv, sweep.csv) row by row,
matched by object, trial and method (and a sweep's swept values), as text: a float that
moved in its last bit is a difference. ``--common``: only the rows both runs have (a short
run's first trials against a long run with the same seed). Exit status 0 when identical, 1
otherwise.
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


def compare(before: Path, after: Path, common: bool = False) -> dict:
    out = {}
    for path in sorted(before.glob("*.csv")):
        if not (after / path.name).exists():
            continue
        a, b = _keyed(read_rows(path)), _keyed(read_rows(after / path.name))
        differences = []
        keys = set(a) & set(b) if common else set(a) | set(b)
        for key in sorted(keys):
            if key not in a or key not in b:
                differences.append({"row": key, "only_in": "after" if key in b else "before"})
                continue
            columns = [c for c in a[key] if c not in IGNORED and a[key][c] != b[key].get(c)]
            if columns:
                differences.append({"row": key, "columns": columns})
        out[path.name] = {"rows": len(keys), "columns_compared": len(next(iter(a.values()), {}))
                          - len(IGNORED), "differences": differences}  # fmt: skip
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("before", type=Path)
    parser.add_argument("after", type=Path)
    parser.add_argument("--common", action="store_true", help="compare the shared rows only")
    parser.add_argument("--out", type=Path, default=None)
    args = parser.parse_args()
    result = compare(args.before, args.after, args.common)
    text = json.dumps(result, indent=2, default=str)
    if args.out:
        args.out.write_text(text + "\n")
    print(text)
    same = result and all(r["rows"] and not r["differences"] for r in result.values())
    sys.exit(0 if same else 1)


if __name__ == "__main__":
    main()
