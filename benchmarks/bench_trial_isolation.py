"""What running each trial in a worker process costs a serial run, against in this process.

    python benchmarks/bench_trial_isolation.py [--trials 3] [--empty 300]
                                               [--out benchmarks/results/trial_isolation.json]

A serial run with a time limit (the command line's, ``--trial-timeout``) sends each trial to
a worker process and waits for its row (``experiments.workers``); without a limit the
Python API may still call it in this process. Two costs, each run both ways:
- ``--empty`` trials that return at once: the per-trial overhead alone (pickling the task
  and the row, the pipe, the wait), the worker's start-up included once;
- ``--trials`` real accuracy trials (obj1, seed 0): the overhead against a trial's work.
Wall seconds of the whole ``run_trials`` call (CSV appends and fsyncs included, the same
both ways); in-process runs first, so the worker's start-up also pays its own imports.
"""

from __future__ import annotations

import os

os.environ.setdefault("MUJOCO_GL", "egl")

import argparse  # noqa: E402
import json  # noqa: E402
import platform  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

from comgrasp_pin.experiments.runner import run_trials  # noqa: E402
from comgrasp_pin.experiments.trials import (  # noqa: E402
    ACCURACY_COLUMNS,
    accuracy_trial,
    make_tasks,
)

LIMIT_S = 600.0  # the command line's default: a limit makes a serial run use a worker


def empty_trial(task: dict) -> dict:
    """A trial with no work: what is left is the runner's own cost."""
    return {"value": task["trial"]}


def _wall(fn, tasks, path: Path, columns, limit_s) -> float:
    start = time.perf_counter()
    rows = run_trials(fn, tasks, path, columns, workers=1, overwrite=True,
                      trial_timeout_s=limit_s)  # fmt: skip
    wall = time.perf_counter() - start
    assert not any(r["error"] for r in rows), [r["error"] for r in rows if r["error"]]
    return wall


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=int, default=3)
    parser.add_argument("--empty", type=int, default=300)
    parser.add_argument("--out", default="benchmarks/results/trial_isolation.json")
    args = parser.parse_args()
    empty = [{"object": "obj1", "trial": k, "method": "m"} for k in range(args.empty)]
    real = make_tasks(["obj1"], args.trials, 0, ("trial",))
    out = {"python": platform.python_version(), "cores": os.cpu_count()}
    with tempfile.TemporaryDirectory() as folder:
        tmp = Path(folder)
        for name, fn, tasks, columns in (
            ("empty", empty_trial, empty, ["object", "trial", "method", "value"]),
            ("accuracy", accuracy_trial, real, ACCURACY_COLUMNS),
        ):
            here = _wall(fn, tasks, tmp / f"{name}_here.csv", columns, None)
            worker = _wall(fn, tasks, tmp / f"{name}_worker.csv", columns, LIMIT_S)
            out[name] = {
                "trials": len(tasks),
                "in_process_s": round(here, 3),
                "worker_s": round(worker, 3),
                "ratio": round(worker / here, 3),
                "extra_per_trial_ms": round(1e3 * (worker - here) / len(tasks), 2),
            }
            print(name, out[name], flush=True)
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    Path(args.out).write_text(json.dumps(out, indent=2) + "\n")
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
