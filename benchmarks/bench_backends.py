"""Trial throughput of the Ray backend with 1 and 2 workers (and the local one), same run.

    python benchmarks/bench_backends.py [--objects obj1,obj2] [--trials 2] [--repeats 1]
                                        [--out benchmarks/results/backends.json]

One local Ray of 2 CPUs is started once; both of its workers are warmed up (package import,
MuJoCo, the OpenGL renderer) by a first round of trials. Then the same accuracy trials (same
seeds: the same work) run with 1 and with 2 Ray tasks in flight, and on the local backend
with 1 and 2 processes, ``--repeats`` times in turn; throughput is trials per wall second
of the whole run_trials call (driver, CSV appends and fsyncs included). The JSON also holds
the per-trial costs the README's cluster estimate uses: trial seconds, the bytes a trial
moves through Ray (its task and its row, pickled), and how many rows per second the driver's
CSV appender (one write + fsync per row) sustains.
"""

from __future__ import annotations

import os

os.environ.setdefault("MUJOCO_GL", "egl")

import argparse  # noqa: E402
import json  # noqa: E402
import pickle  # noqa: E402
import platform  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

from comgrasp_pin.experiments.run_files import RowAppender  # noqa: E402
from comgrasp_pin.experiments.runner import run_trials  # noqa: E402
from comgrasp_pin.experiments.trials import (  # noqa: E402
    ACCURACY_COLUMNS,
    accuracy_trial,
    make_tasks,
)

APPEND_ROWS = 300  # rows written to measure the driver's append + fsync rate
APPEND_BATCHES = (10, 100)  # rows per fsync when a Ray pass brings several


def _run(tasks, folder: Path, name: str, backend: str, workers: int) -> tuple[float, list]:
    start = time.perf_counter()
    rows = run_trials(accuracy_trial, tasks, folder / f"{name}.csv", ACCURACY_COLUMNS, workers,
                      overwrite=True, desc=name, backend=backend)  # fmt: skip
    return time.perf_counter() - start, rows


def _append_rate(rows: list[dict], folder: Path, batch: int = 1) -> float:
    """Rows per second RowAppender writes of real rows, ``batch`` rows per write and fsync."""
    columns = [*ACCURACY_COLUMNS, "error"]
    with RowAppender(folder / f"append{batch}.csv", columns) as out:
        start = time.perf_counter()
        for k in range(0, APPEND_ROWS, batch):
            out.write_rows([rows[(k + i) % len(rows)] for i in range(batch)])
        return APPEND_ROWS / (time.perf_counter() - start)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--objects", default="obj1,obj2")
    parser.add_argument("--trials", type=int, default=2)
    parser.add_argument("--repeats", type=int, default=1)
    parser.add_argument("--out", default=str(Path(__file__).parent / "results" / "backends.json"))
    args = parser.parse_args()
    import ray

    tasks = make_tasks(args.objects.split(","), args.trials, 0, ("trial",))
    for task in tasks:
        task.update(noise=0.05, estimator="ipopt")
    start = time.perf_counter()
    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False)
    ray_init_s = time.perf_counter() - start
    cases = {"ray_1": ("ray", 1), "ray_2": ("ray", 2), "local_1": ("local", 1),
             "local_2": ("local", 2)}  # fmt: skip
    seconds: dict[str, list[float]] = {name: [] for name in cases}
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        warm_s, rows = _run(tasks[:2], folder, "warm", "ray", 2)
        for _ in range(args.repeats):
            for name, (backend, workers) in cases.items():
                elapsed, rows = _run(tasks, folder, name, backend, workers)
                assert all(not r["error"] for r in rows), [r["error"] for r in rows]
                seconds[name].append(elapsed)
        append_rows_per_s = _append_rate(rows, folder)
        append_batched = {n: _append_rate(rows, folder, n) for n in APPEND_BATCHES}
    ray.shutdown()
    best = {name: min(s) for name, s in seconds.items()}
    throughput = {name: len(tasks) / s for name, s in best.items()}
    wall = [float(r["wall_s"]) for r in rows]
    sim = [float(r["sim_s"]) for r in rows]
    result = {
        "trials_per_run": len(tasks),
        "seconds": seconds,
        "throughput_trials_per_s": throughput,
        "ratio_ray_2_over_1": throughput["ray_2"] / throughput["ray_1"],
        "ratio_local_2_over_1": throughput["local_2"] / throughput["local_1"],
        "ratio_ray_over_local_2": throughput["ray_2"] / throughput["local_2"],
        "target_ratio_ray_2_over_1": 1.8,
        "ray_init_s": ray_init_s,
        "ray_warm_up_s": warm_s,
        "per_trial": {
            "wall_s_mean": float(np.mean(wall)),
            "sim_s_mean": float(np.mean(sim)),
            "realtime_factor": float(np.sum(sim) / np.sum(wall)),
            "task_bytes": len(pickle.dumps(tasks[0])),
            "row_bytes": len(pickle.dumps(rows[0])),
            "csv_row_bytes": len(",".join(str(rows[0].get(c, "")) for c in ACCURACY_COLUMNS)),
        },
        "driver_append_rows_per_s": append_rows_per_s,
        "driver_append_rows_per_s_by_batch": append_batched,
        "environment": {
            "python": platform.python_version(),
            "ray": ray.__version__,
            "cpus": os.cpu_count(),
            "load_avg_1min": os.getloadavg()[0],
            "date": time.strftime("%Y-%m-%d %H:%M:%S UTC", time.gmtime()),
        },  # fmt: skip
    }
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    Path(args.out).write_text(json.dumps(result, indent=2) + "\n")
    print(
        json.dumps(
            {
                k: result[k]
                for k in (
                    "throughput_trials_per_s",
                    "ratio_ray_2_over_1",
                    "ratio_local_2_over_1",
                    "per_trial",
                )
            },
            indent=2,
        )
    )
    print(f"written to {args.out}")


if __name__ == "__main__":
    main()
