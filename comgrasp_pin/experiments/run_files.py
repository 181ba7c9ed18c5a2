"""The files of a run, kept whole: its results CSV and the settings recorded beside it.

- ``DIR/NAME.settings.json`` holds every setting of the run (seed, noise, estimator, the whole
  config tree, the package version, the objects and trials). ``--resume`` refuses a run
  whose settings differ, naming each setting; only ``objects`` and ``trials`` may grow, and
  ``backend`` (where the trials run) and ``trial_timeout_s`` may change: a run started
  locally may resume on Ray, a timed-out trial may be retried with a longer limit.
- Every row is one line, written whole: appended with one unbuffered write, flushed and
  fsynced (the rows a Ray driver collects in one pass: one write and one fsync for them
  all), so the CSV is readable while a run goes on. A write that fails (full disk) is
  undone and reported as ``OutputError``; the rows before it stay intact.
- A run killed while writing leaves a last line without its newline: ``read_results`` drops
  it with a warning (its trial runs again). A CSV with another header, or a damaged row
  before the last, is refused (``ResumeError``).
- Rewrites (a new file, a repaired one, failed rows removed) go through a temporary file and
  ``os.replace``: a reader sees the old file or the new one, never half of one.
- A run holds ``DIR/.NAME.csv.lock`` (``fcntl.flock``) while it writes: a second run on the
  same CSV is refused instead of interleaving its rows.
- A trial that ended in an internal error (a bug) keeps its traceback in
  ``DIR/NAME.tracebacks.txt`` (``internal_errors``).
"""

from __future__ import annotations

import csv
import errno
import io
import json
import os
import warnings
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path

from comgrasp_pin import file_checks
from comgrasp_pin.errors import OutputError, ResumeError

GROWABLE = ("objects", "trials")
"""Settings ``--resume`` lets change: a run may be extended with more trials or objects."""
FREE = ("backend", "ray_address", "trial_timeout_s")
"""Settings recorded but not compared: where the trials run, and how long one may take,
change none of the finished rows."""


def settings_path(csv_path: Path) -> Path:
    """Where the settings of the run writing ``csv_path`` are kept (``NAME.settings.json``)."""
    return csv_path.with_suffix(".settings.json")


def _normal(settings: dict) -> dict:
    """The settings as JSON would give them back (tuples as lists, other values as text)."""
    return json.loads(json.dumps(settings, default=str))


def _flat(tree: object, prefix: str = "") -> dict[str, object]:
    if not isinstance(tree, dict):
        return {prefix: tree}
    out: dict[str, object] = {}
    for key, value in tree.items():
        out.update(_flat(value, f"{prefix}.{key}" if prefix else str(key)))
    return out


def settings_differences(recorded: dict, wanted: dict) -> list[str]:
    """Every setting (dotted path) other than GROWABLE and FREE whose value differs, as text."""
    skip = (*GROWABLE, *FREE)
    old = {k: v for k, v in _flat(_normal(recorded)).items() if k not in skip}
    new = {k: v for k, v in _flat(_normal(wanted)).items() if k not in skip}
    missing = object()
    return [
        f"{key}: {old.get(key, 'not set')!r} in the run, {new.get(key, 'not set')!r} now"
        for key in sorted(set(old) | set(new))
        if old.get(key, missing) != new.get(key, missing)
    ]


def check_settings(csv_path: Path, wanted: dict) -> dict:
    """The settings to record for a resumed run: the recorded ones, grown to ``wanted``.

    Raises:
        ResumeError: no settings beside the CSV, or settings that differ (each one named).
    """
    path = settings_path(csv_path)
    if not path.exists():
        raise ResumeError(
            f"{csv_path} has no {path.name} beside it, so its settings are unknown and it "
            "cannot be continued safely; start again with --overwrite"
        )
    try:  # a regular file, of bounded size and nesting: a FIFO or a bomb in its place
        recorded = file_checks.read_json(path, "run settings", ResumeError)
    except ResumeError as exc:
        raise ResumeError(f"cannot read {path}: {exc}; start again with --overwrite") from None
    if not isinstance(recorded, dict):
        raise ResumeError(f"{path} does not hold a run's settings; start again with --overwrite")
    differences = settings_differences(recorded, wanted)
    if differences:
        raise ResumeError(
            f"{csv_path} was run with other settings; --resume would mix two runs in one CSV. "
            f"Different: {'; '.join(differences)}. Use the run's settings, or another --out, "
            "or --overwrite"
        )
    grown = dict(_normal(wanted))
    objects = list(recorded.get("objects", []))
    grown["objects"] = objects + [o for o in grown.get("objects", []) if o not in objects]
    grown["trials"] = max(int(recorded.get("trials", 0)), int(grown.get("trials", 0)))
    return grown


def write_settings(csv_path: Path, settings: dict) -> None:
    """Record ``settings`` beside ``csv_path`` (atomically)."""
    text = json.dumps(_normal(settings), indent=2, sort_keys=True) + "\n"
    _write_atomic(settings_path(csv_path), text.encode())


def _one_line(value: object) -> str:
    """A CSV value on one line: a row is a line, so a cut row is always the last line."""
    return str(value).replace("\r", " ").replace("\n", " ")


def format_row(row: dict, columns: Sequence[str]) -> bytes:
    """One CSV line (with its newline) of the ``columns`` of ``row``; missing ones empty."""
    buffer = io.StringIO()
    csv.writer(buffer).writerow([_one_line(row.get(c, "")) for c in columns])
    return buffer.getvalue().encode()


def _write_atomic(path: Path, data: bytes) -> None:
    tmp = path.with_name(f".{path.name}.tmp")
    try:
        with tmp.open("wb") as f:
            f.write(data)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except OSError as exc:
        tmp.unlink(missing_ok=True)
        raise OutputError(f"cannot write {path}: {exc.strerror or exc}") from None


def rewrite(csv_path: Path, columns: Sequence[str], rows: Sequence[dict]) -> None:
    """Replace ``csv_path`` by the header and ``rows``, atomically."""
    lines = [format_row(dict(zip(columns, columns)), columns)]
    lines += [format_row(row, columns) for row in rows]
    _write_atomic(csv_path, b"".join(lines))


def read_results(csv_path: Path, columns: Sequence[str]) -> tuple[list[dict], bool]:
    """(rows, repaired) of a results CSV written with ``columns``; ([], False) if absent.

    ``repaired``: the last line was cut (no newline) and was dropped, with a warning; the
    caller rewrites the file before appending to it.

    Raises:
        ResumeError: another header, or a damaged row before the last line.
    """
    if not csv_path.exists():
        return [], False
    data = file_checks.read_bytes(csv_path, "results CSV", file_checks.MAX_CSV_BYTES, ResumeError)
    text = data.decode("utf-8", errors="replace")
    if not text:
        return [], False
    repaired = not text.endswith("\n")
    if repaired:
        cut = text[text.rfind("\n") + 1 :]
        text = text[: text.rfind("\n") + 1]
        warnings.warn(
            f"{csv_path}: the last line was cut ({cut[:60]!r}...; the run was stopped while "
            "writing it): dropped, its trial runs again",
            stacklevel=2,
        )
    records = list(csv.reader(io.StringIO(text)))
    if not records:
        return [], repaired
    header, body = records[0], records[1:]
    if header != list(columns):
        extra = [c for c in header if c not in columns]
        missing = [c for c in columns if c not in header]
        raise ResumeError(
            f"{csv_path} has another header than this experiment writes (columns not "
            f"expected: {extra}, missing: {missing}, or another order); it cannot be "
            "continued: use another --out or --overwrite"
        )
    for line, record in enumerate(body, start=2):
        if len(record) != len(header):
            raise ResumeError(
                f"{csv_path} line {line} has {len(record)} fields, the header {len(header)}: "
                "the file is damaged; use another --out or --overwrite"
            )
    return [dict(zip(header, record)) for record in body], repaired


@contextmanager
def run_lock(csv_path: Path) -> Iterator[None]:
    """Held while a run reads and writes ``csv_path`` (its folder is created).

    Raises:
        OutputError: the folder cannot be created. ResumeError: another run holds the lock.
    """
    try:
        import fcntl
    except ImportError:  # not POSIX: no lock
        yield
        return
    try:
        csv_path.parent.mkdir(parents=True, exist_ok=True)
        f = open(csv_path.with_name(f".{csv_path.name}.lock"), "a")  # noqa: SIM115
    except OSError as exc:
        raise OutputError(f"cannot write in {csv_path.parent}: {exc.strerror or exc}") from None
    try:
        try:
            fcntl.flock(f, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            raise ResumeError(
                f"another run is writing {csv_path} now: wait for it to end, or use another --out"
            ) from None
        yield
    finally:
        f.close()  # releases the lock


class RowAppender:
    """Appends rows to a results CSV, each written whole (one write, flush, fsync)."""

    def __init__(self, csv_path: Path, columns: Sequence[str]):
        self.path, self.columns, self.written = csv_path, list(columns), 0
        try:
            self._file = open(csv_path, "ab", buffering=0)  # noqa: SIM115 (closed in close)
        except OSError as exc:
            raise OutputError(f"cannot open {csv_path}: {exc.strerror or exc}") from None

    def write(self, row: dict) -> None:
        """Append ``row``; on failure undo the partial line and raise OutputError."""
        self.write_rows([row])

    def write_rows(self, rows: Sequence[dict]) -> None:
        """Append ``rows``, each a whole line, with one fsync for them all (a driver that
        collects several finished trials at once); on failure undo the partial lines and
        raise OutputError."""
        data = b"".join(format_row(row, self.columns) for row in rows)
        f = self._file
        start = f.seek(0, os.SEEK_END)
        try:
            view = memoryview(data)
            while view:
                count = f.write(view)
                if not count:
                    raise OSError(errno.EIO, "the file took no bytes")
                view = view[count:]
            os.fsync(f.fileno())
        except OSError as exc:
            try:
                f.truncate(start)
            except OSError:
                pass
            raise OutputError(
                f"cannot write to {self.path}: {exc.strerror or exc}; the run stopped, the "
                f"{self.written} rows written by this run before are intact: make room and "
                "continue it with --resume"
            ) from None
        self.written += len(rows)

    def close(self) -> None:
        """Close the file."""
        self._file.close()

    def __enter__(self) -> RowAppender:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
