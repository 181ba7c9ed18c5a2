"""Running many independent trials that survive failures and interruptions.

Every finished trial is appended to the CSV at once (and flushed), so an interrupted run
loses nothing and ``resume=True`` continues where it stopped. A trial that raises is
recorded with its error and does not stop the run. ``workers > 1`` runs trials in separate
processes (spawned, so each has its own MuJoCo and OpenGL context).
"""

from __future__ import annotations

import csv
import multiprocessing
import traceback
from collections.abc import Callable, Sequence
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from pathlib import Path

from tqdm import tqdm

KEY_COLUMNS = ("object", "trial", "method")


def task_key(row: dict) -> tuple[str, ...]:
    """Identity of a trial: its object, trial index and method."""
    return tuple(str(row.get(k, "")) for k in KEY_COLUMNS)


def read_rows(csv_path: Path) -> list[dict]:
    """All rows of a results CSV (empty when the file does not exist)."""
    if not csv_path.exists():
        return []
    with csv_path.open(newline="") as f:
        return list(csv.DictReader(f))


def _safe_call(fn: Callable[[dict], dict], task: dict) -> dict:
    try:
        return {**task, **fn(task), "error": ""}
    except Exception as exc:  # a failed trial is data, not the end of the run
        last = traceback.format_exception_only(type(exc), exc)[-1].strip()
        return {**task, "error": last}


def run_trials(
    fn: Callable[[dict], dict],
    tasks: Sequence[dict],
    csv_path: Path,
    columns: Sequence[str],
    workers: int = 1,
    resume: bool = False,
    overwrite: bool = False,
    desc: str = "trials",
) -> list[dict]:
    """Run ``fn(task)`` for every task not already in ``csv_path``; return all rows.

    Args:
        fn: a picklable top-level function returning a dict of result columns.
        tasks: dicts with at least the KEY_COLUMNS; their items are copied into the row.
        csv_path: results file; rows are appended as trials finish.
        columns: the CSV header (an ``error`` column is added).
        resume: keep the rows already in ``csv_path`` and run only the missing tasks.
        overwrite: start a new file even if one exists.
    """
    columns = [*columns, "error"] if "error" not in columns else list(columns)
    existing = read_rows(csv_path)
    if existing and not (resume or overwrite):
        raise FileExistsError(
            f"{csv_path} already holds {len(existing)} trials: pass resume to continue it "
            "or overwrite to start again"
        )
    if overwrite or not resume:
        existing = []
    done = {task_key(row) for row in existing}
    todo = [task for task in tasks if task_key(task) not in done]
    csv_path.parent.mkdir(parents=True, exist_ok=True)
    new_file = not existing
    with csv_path.open("w" if new_file else "a", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=columns, extrasaction="ignore")
        if new_file:
            writer.writeheader()
            f.flush()
        rows = list(existing)
        bar = tqdm(total=len(tasks), initial=len(tasks) - len(todo), desc=desc, unit="trial")

        def record(row: dict) -> None:
            writer.writerow(row)
            f.flush()
            rows.append(row)
            bar.update(1)
            if row.get("error"):
                bar.write(f"trial {task_key(row)} failed: {row['error']}")

        try:
            if workers <= 1:
                for task in todo:
                    record(_safe_call(fn, task))
            else:
                _run_parallel(fn, todo, workers, record)
        finally:
            bar.close()
    return rows


def _run_parallel(fn, todo, workers, record) -> None:
    context = multiprocessing.get_context("spawn")
    with ProcessPoolExecutor(max_workers=workers, mp_context=context) as pool:
        pending = {pool.submit(_safe_call, fn, task) for task in todo}
        try:
            while pending:
                finished, pending = wait(pending, return_when=FIRST_COMPLETED)
                for future in finished:
                    record(future.result())
        except BaseException:
            for future in pending:
                future.cancel()
            raise
