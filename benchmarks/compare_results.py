"""Are two golden trees' numbers the same? (a refactor's "numbers unchanged" check)

    python benchmarks/compare_results.py BEFORE AFTER [--rtol 1e-12] [--rename OLD=NEW]

BEFORE and AFTER are folders written by ``benchmarks/golden_results.py`` (or any two trees of
results). Every file of BEFORE is looked for in AFTER and compared by kind:

- JSON: flattened to ``key.sub.0 -> value`` (lists indexed, dicts joined by "."); every number
  present in both must agree within ``--rtol`` (plus an absolute 1e-15 times the file's largest
  number, so that exact zeros stay zeros); a number of BEFORE missing from AFTER is an error,
  a key new in AFTER is listed. Renamed keys: ``--rename OLD=NEW`` (repeatable) or
  ``--renames FILE`` (one OLD=NEW a line), applied to a key and everything under it, to CSV
  columns and to file paths; ``GLOB:OLD=NEW`` only in the files whose path matches GLOB (a
  key that moved to different places in different files), the first match winning;
- ``rc.txt``: the exit status, exactly;
- CSV: row by row (an experiment's by object, trial and method), column by column (by
  name), numbers within ``--rtol``;
- other text (payload files: .script, .yaml, .urdf, .dat, .mod, .java, .xml, .md): every number
  in order, comment lines (``#``, ``//``, ``;``, ``!``, ``<!-- -->``) left out, headers may change;
- ``stdout.txt`` and Markdown reports likewise, but reported only (they print run times)
  unless ``--strict-stdout``; ``cmd.txt``, ``stderr.txt``, binary and dot files are not.

Changed text values (strings, booleans) are listed, errors only with ``--strict-text``;
``--ignore GLOB`` leaves out ``path:key`` matches (timings by default). Exit status 1 on any
numeric difference, missing number or file, or changed exit status; 0 otherwise.
"""

from __future__ import annotations

import argparse
import csv
import json
import math
import re
import sys
from fnmatch import fnmatch
from pathlib import Path

NUMBER = re.compile(r"(?<![\w.])[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?(?![\w.])")
FLOAT = re.compile(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?|[-+]?(?:nan|inf)", re.I)
COMMENT_LINE = ("#", "//", ";", "!", "<!--")
XML_COMMENT = re.compile(r"<!--.*?-->", re.S)
BINARY = {".png", ".jpg", ".jpeg", ".mp4", ".gif", ".pdf", ".npz", ".npy", ".pkl", ".db3"}
NOT_COMPARED = {"cmd.txt", "stderr.txt"}
# wall-clock times and the machine's load, which no two runs share (found by running twice)
DEFAULT_IGNORE = ("*:*wall_s*", "*:environment.*", "*:*timing.*", "*:*_minutes", "*:plan_s*",
                  "*:*fit_s*", "*:*load_avg*", "*/.*")  # fmt: skip
REPORT_ONLY = {".md"}  # a report's text carries its run time
MAX_SHOWN = 12


class Report:
    """Differences found, by file: errors fail the check, notes are listed only."""

    def __init__(self) -> None:
        self.errors: dict[str, list[str]] = {}
        self.notes: dict[str, list[str]] = {}
        self.numbers = self.files = 0

    def add(self, path: str, msg: str, fail: bool = True) -> None:
        (self.errors if fail else self.notes).setdefault(path, []).append(msg)


def flatten(obj, prefix: str = "") -> dict[str, object]:
    """``{"a": {"b": [1, 2]}}`` -> ``{"a.b.0": 1, "a.b.1": 2}``; empty containers kept."""
    if not isinstance(obj, (dict, list)) or not obj:
        return {prefix: obj}
    out: dict[str, object] = {}
    for k, v in obj.items() if isinstance(obj, dict) else enumerate(obj):
        out.update(flatten(v, f"{prefix}.{k}" if prefix else str(k)))
    return out


def is_number(v) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def close(a: float, b: float, rtol: float, atol: float) -> bool:
    if math.isnan(a) or math.isnan(b):
        return math.isnan(a) and math.isnan(b)
    if math.isinf(a) or math.isinf(b):
        return a == b
    return abs(a - b) <= rtol * max(abs(a), abs(b)) + atol


def scale_of(values) -> float:
    finite = [abs(float(v)) for v in values if is_number(v) and math.isfinite(v)]
    return max(finite, default=0.0)


class Comparer:
    """The comparison of two trees with one set of tolerances, renames and ignores."""

    def __init__(self, args: argparse.Namespace, renames: list[tuple[str, str, str]]) -> None:
        self.rtol, self.atol_scale = args.rtol, args.atol_scale
        self.renames = renames
        self.ignore = list(args.ignore or []) + (
            [] if args.no_default_ignore else list(DEFAULT_IGNORE)
        )
        self.strict_text, self.strict_stdout = args.strict_text, args.strict_stdout
        self.report = Report()

    def rename(self, key: str, path: str = "") -> str:
        for glob, old, new in self.renames:
            if glob and not fnmatch(path, glob):
                continue
            if key == old or key.startswith(old + ".") or key.startswith(old + "/"):
                return new + key[len(old) :]
        return key

    def key_in(self, key: str, after, path: str = "") -> str:
        """``key`` renamed, or as it was where AFTER has it so and not the new name."""
        new = self.rename(key, path)
        return key if new not in after and key in after else new

    def ignored(self, path: str, key: str) -> bool:
        return any(fnmatch(f"{path}:{key}", g) or fnmatch(path, g) for g in self.ignore)

    def numbers(self, path: str, where: str, a: float, b: float, atol: float, fail=True) -> None:
        self.report.numbers += 1
        if not close(float(a), float(b), self.rtol, atol):
            rel = abs(a - b) / max(abs(a), abs(b), 1e-300)
            msg = f"{where}: {a!r} -> {b!r} (rel {rel:.2e})"
            self.report.add(path, msg, fail)

    def json_files(self, path: str, before: Path, after: Path) -> None:
        try:
            fa, fb = flatten(json.loads(before.read_text())), flatten(json.loads(after.read_text()))
        except (json.JSONDecodeError, UnicodeDecodeError) as exc:
            self.report.add(path, f"unreadable JSON: {exc}")
            return
        fb = {k: v for k, v in fb.items() if not self.ignored(path, k)}
        fa = {self.key_in(k, fb, path): v for k, v in fa.items() if not self.ignored(path, k)}
        atol = self.atol_scale * scale_of(fa.values())
        for key, va in fa.items():
            vb = fb.get(key, "<missing in AFTER>")
            if is_number(va) and is_number(vb):
                self.numbers(path, key, va, vb, atol)
            elif is_number(va) or is_number(vb):
                self.report.add(path, f"{key}: {va!r} -> {vb!r}")
            elif va != vb:
                self.report.add(path, f"{key}: {va!r} -> {vb!r} (text)", self.strict_text)
        for key in sorted(set(fb) - set(fa)):
            self.report.add(path, f"{key}: new in AFTER ({fb[key]!r})", False)

    def csv_files(self, path: str, before: Path, after: Path) -> None:
        ra, rb = read_table(before), read_table(after)
        if not ra or not rb:
            self.text_numbers(path, before, after, fail=True)
            return
        head_a = [self.key_in(c, rb[0], path) for c in ra[0]]
        col_b = {c: i for i, c in enumerate(rb[0])}
        for c in set(head_a) - set(col_b):
            self.report.add(path, f"column {c!r} missing in AFTER")
        for c in set(col_b) - set(head_a):
            self.report.add(path, f"column {c!r} new in AFTER", False)
        cols = [(i, c, col_b[c]) for i, c in enumerate(head_a) if c in col_b]
        cols = [x for x in cols if not self.ignored(path, x[1])]
        rows_a, rows_b = keyed(head_a, ra[1:]), keyed(rb[0], rb[1:])
        for k in sorted(rows_a.keys() - rows_b.keys()):
            self.report.add(path, f"row {k} missing in AFTER")
        for k in sorted(rows_b.keys() - rows_a.keys()):
            self.report.add(path, f"row {k} new in AFTER", False)
        atol = self.atol_scale * scale_of(
            float(r[i]) for r in ra[1:] for i, _, _ in cols if i < len(r) and is_float(r[i])
        )
        for k in sorted(rows_a.keys() & rows_b.keys()):
            row_a, row_b = rows_a[k], rows_b[k]
            for i, c, j in cols:
                a = row_a[i] if i < len(row_a) else None
                b = row_b[j] if j < len(row_b) else None
                if is_float(a) and is_float(b):
                    self.numbers(path, f"row {k} {c}", float(a), float(b), atol)
                elif a != b:
                    fail = self.strict_text or is_float(a) or is_float(b)
                    self.report.add(path, f"row {k} {c}: {a!r} -> {b!r}", fail)

    def text_numbers(self, path: str, before: Path, after: Path, fail: bool) -> None:
        na, nb = numbers_in(before), numbers_in(after)
        if len(na) != len(nb):
            msg = f"{len(na)} numbers -> {len(nb)} (outside comment lines)"
            self.report.add(path, msg, fail)
        atol = self.atol_scale * scale_of(na)
        for n, (a, b) in enumerate(zip(na, nb), start=1):
            self.numbers(path, f"number {n}", a, b, atol, fail)

    def file(self, path: str, before: Path, after: Path) -> None:
        self.report.files += 1
        name, suffix = before.name, before.suffix.lower()
        if name == "rc.txt":
            a, b = before.read_text().strip(), after.read_text().strip()
            if a != b:
                self.report.add(path, f"exit status {a} -> {b}")
        elif suffix == ".json":
            self.json_files(path, before, after)
        elif suffix == ".csv":
            self.csv_files(path, before, after)
        elif name == "stdout.txt" or suffix in REPORT_ONLY:
            self.text_numbers(path, before, after, fail=self.strict_stdout)
        else:
            self.text_numbers(path, before, after, fail=True)


def is_float(s: str | None) -> bool:
    return s is not None and FLOAT.fullmatch(s.strip()) is not None


def keyed(header: list[str], rows: list[list[str]]) -> dict[str, list[str]]:
    """Rows by their key: a trial's (object, trial, method, swept values), else the row's number."""
    cols = [i for i, c in enumerate(header) if "." in c or c in ("object", "trial", "method")]
    if "trial" not in header:
        return {str(n): r for n, r in enumerate(rows, start=1)}
    return {"/".join(r[i] for i in cols if i < len(r)): r for r in rows}


def read_table(path: Path) -> list[list[str]]:
    """A CSV's rows (comma-separated, or whitespace where the header has no comma)."""
    text = path.read_text(errors="replace")
    first = text.split("\n", 1)[0]
    if "," in first:
        return [r for r in csv.reader(text.splitlines()) if r]
    return [line.split() for line in text.splitlines() if line.strip()]


def numbers_in(path: Path) -> list[float]:
    """Every number of a text file in order, comment lines and XML comments left out."""
    text = XML_COMMENT.sub("", path.read_text(errors="replace"))
    lines = [ln for ln in text.splitlines() if not ln.lstrip().startswith(COMMENT_LINE)]
    return [float(m) for ln in lines for m in NUMBER.findall(ln)]


def files_of(root: Path) -> set[str]:
    return {p.relative_to(root).as_posix() for p in root.rglob("*") if p.is_file()}


def parse_renames(args: argparse.Namespace) -> list[tuple[str, str, str]]:
    """(path glob or "", OLD, NEW) in the order given."""
    pairs = list(args.rename or [])
    if args.renames:
        lines = Path(args.renames).read_text().splitlines()
        pairs += [ln.strip() for ln in lines if ln.strip() and not ln.lstrip().startswith("#")]
    out = []
    for p in pairs:
        old, sep, new = p.partition("=")
        if not sep:
            raise SystemExit(f"--rename wants [GLOB:]OLD=NEW, got {p!r}")
        glob, _, old = old.rpartition(":")
        out.append((glob.strip(), old.strip(), new.strip()))
    return out


def compare_trees(before: Path, after: Path, cmp: Comparer) -> None:
    fa, fb = files_of(before), files_of(after)
    matched = set()
    for rel in sorted(fa):
        if Path(rel).name in NOT_COMPARED or cmp.ignored(rel, ""):
            continue
        new_rel = cmp.key_in(rel, fb)
        if new_rel not in fb:
            cmp.report.add(rel, "missing in AFTER")
            continue
        matched.add(new_rel)
        if Path(rel).suffix.lower() in BINARY:
            continue
        cmp.file(rel, before / rel, after / new_rel)
    for rel in sorted(fb - matched - fa):
        if Path(rel).name not in NOT_COMPARED:
            cmp.report.add(rel, "new in AFTER", False)


def print_report(r: Report) -> None:
    for title, group in (("notes (not failing)", r.notes), ("DIFFERENCES", r.errors)):
        if not group:
            continue
        print(f"\n== {title}: {sum(map(len, group.values()))} in {len(group)} files")
        for path, msgs in sorted(group.items()):
            print(f"  {path}")
            for m in msgs[:MAX_SHOWN]:
                print(f"    {m}")
            if len(msgs) > MAX_SHOWN:
                print(f"    ... and {len(msgs) - MAX_SHOWN} more")
    n_err = sum(map(len, r.errors.values()))
    verdict = "IDENTICAL" if not n_err else f"DIFFERENT ({n_err} differences)"
    print(f"\n{r.files} files, {r.numbers} numbers compared: {verdict}")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("before", type=Path)
    ap.add_argument("after", type=Path)
    ap.add_argument("--rtol", type=float, default=1e-12)
    ap.add_argument("--atol-scale", type=float, default=1e-15,
                    help="absolute tolerance, times the file's largest number")  # fmt: skip
    ap.add_argument("--rename", action="append", metavar="[GLOB:]OLD=NEW")
    ap.add_argument("--renames", metavar="FILE", help="[GLOB:]OLD=NEW per line")
    ap.add_argument("--ignore", action="append", metavar="GLOB", help="path:key to leave out")
    ap.add_argument("--no-default-ignore", action="store_true", help="compare timings too")
    ap.add_argument("--strict-text", action="store_true", help="text values must match too")
    ap.add_argument("--strict-stdout", action="store_true", help="stdout's, reports' numbers match")
    args = ap.parse_args()
    if not (args.before.is_dir() and args.after.is_dir()):
        raise SystemExit(f"not two folders: {args.before} {args.after}")
    cmp = Comparer(args, parse_renames(args))
    compare_trees(args.before, args.after, cmp)
    print_report(cmp.report)
    return 1 if cmp.report.errors else 0


if __name__ == "__main__":
    sys.exit(main())
