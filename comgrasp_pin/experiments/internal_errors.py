"""Trials that ended in an internal error: their rows, their tracebacks, the command's failure.

A trial that raises a ``ComGraspError`` failed in the world (or the harness stopped it): its
row is an outcome, a failed trial. One that raises anything else (``TypeError``,
``KeyError``, ``MemoryError``, ...) hit a bug: it has no outcome. Chosen for such a trial:

- its row stays in the CSV, its ``error`` beginning ``internal error:`` (``INTERNAL_ERROR``;
  ``workers.internal_error_row``), so the run goes on and the other trials (hours of them,
  perhaps) are kept;
- its whole traceback is appended to ``DIR/NAME.tracebacks.txt`` beside the CSV, headed by
  the trial's name, before its row is written (``append_traceback``; the worker sends it
  with the row under ``TRACEBACK``, never a CSV column);
- the report and the sweep's measures count it in no count, rate or mean, and the run
  summary names it (``report.common``);
- ``--resume`` runs it again, with or without ``--retry-failed`` (``runner``);
  ``--overwrite`` removes the old tracebacks;
- the experiment commands run inside ``fail_on_internal_errors``: they go to their end
  (figures and report written) and then raise ``InternalTrialError``, which the command
  line turns into exit status 1 and a message naming the trials and the traceback files.

Stopping the run at the first bug was the other choice; it would lose the trials not yet
run for a report that the exit status refuses anyway.
"""

from __future__ import annotations

import os
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from datetime import datetime, timezone
from pathlib import Path

from comgrasp_pin.errors import InternalTrialError, OutputError

INTERNAL_ERROR = "internal error"
"""How the ``error`` of a trial that ended in an internal error begins (``internal error:
TypeError: ...``)."""
TRACEBACK = "traceback"
"""The key of a row (never a CSV column) that carries an internal error's traceback from the
worker to the driver, which moves it to ``tracebacks_path``."""
NO_TRACEBACK = "(no traceback: the trial's process sent none)"
SHOWN_TRIALS = 10
"""``InternalTrialError`` names at most this many trials (and counts the others)."""


def is_internal_error(row: dict) -> bool:
    """Whether ``row`` is a trial that ended in an internal error."""
    return str(row.get("error") or "").startswith(INTERNAL_ERROR)


def tracebacks_path(csv_path: Path) -> Path:
    """Where the tracebacks of the internal errors of the run writing ``csv_path`` are kept
    (``NAME.tracebacks.txt``)."""
    return Path(csv_path).with_suffix(".tracebacks.txt")


def append_traceback(csv_path: Path, trial: str, text: str | None) -> None:
    """Append the traceback ``text`` of ``trial`` (its name) to ``tracebacks_path``, flushed
    and fsynced (before its row is written).

    Raises:
        OutputError: the file cannot be written.
    """
    path = tracebacks_path(csv_path)
    stamp = datetime.now(timezone.utc).isoformat(timespec="seconds")
    entry = f"=== {trial} ({stamp}) ===\n{(text or NO_TRACEBACK).rstrip()}\n\n"
    try:
        with path.open("a", encoding="utf-8") as f:
            f.write(entry)
            f.flush()
            os.fsync(f.fileno())
    except OSError as exc:
        raise OutputError(f"cannot write {path}: {exc.strerror or exc}") from None


_WATCHING: list[list[tuple[Path, str, str]]] = []
"""The open ``fail_on_internal_errors`` blocks' lists of (CSV, trial, error)."""


def found(csv_path: Path, trials: Sequence[tuple[str, str]]) -> None:
    """Tell the open ``fail_on_internal_errors`` blocks that a run on ``csv_path`` ended with
    ``trials`` ((name, error), ...) in an internal error."""
    for watch in _WATCHING:
        watch += [(Path(csv_path), name, error) for name, error in trials]


@contextmanager
def fail_on_internal_errors() -> Iterator[list[tuple[Path, str, str]]]:
    """Within the block, the trials of every run (``runner.run_trials``) that end in an
    internal error are listed (CSV, the trial's name, its error) in the list it yields; when
    the block ends without an exception of its own and the list is not empty, it raises
    ``InternalTrialError`` naming them and the files with their tracebacks.

    Raises:
        InternalTrialError: a trial ended in an internal error.
    """
    watch: list[tuple[Path, str, str]] = []
    _WATCHING.append(watch)
    try:
        yield watch
    finally:
        _WATCHING.remove(watch)
    if watch:
        raise internal_trial_error(watch)


def internal_trial_error(trials: Sequence[tuple[Path, str, str]]) -> InternalTrialError:
    """The ``InternalTrialError`` of the (CSV, trial, error) listed in ``trials``."""
    paths = list(dict.fromkeys(tracebacks_path(csv) for csv, _, _ in trials))
    named = "; ".join(f"{name} in {csv} ({error})" for csv, name, error in trials[:SHOWN_TRIALS])
    more = len(trials) - SHOWN_TRIALS
    return InternalTrialError(
        f"{len(trials)} trial(s) ended in an internal error: an exception that is not a "
        "ComGraspError, a bug and not the world's failure. Their rows are marked 'internal "
        "error' and left out of every rate and mean: "
        f"{named}{f'; and {more} more' if more > 0 else ''}. Tracebacks: "
        f"{', '.join(map(str, paths))}. Fix the cause, then run the same command with "
        "--resume: those trials run again",
        [name for _, name, _ in trials],
        paths,
    )
