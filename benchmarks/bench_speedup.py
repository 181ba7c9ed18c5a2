"""An episode's phases before and after a change, in one run: the older code against today's.

    python benchmarks/bench_speedup.py --before 49b14e3 [--objects obj1,obj3,obj5]
        [--trials 1] [--rounds 2] [--sensors ideal,realistic] [--threads 1]
        [--out benchmarks/results/speedup.json]

The older code is checked out as a git worktree (``--before``, a commit) beside this one;
each round runs ``bench_episode_phases.py`` of both versions on the same trials, in turn
(the order swapped every round, so that the machine's drift falls on both alike), each in
its own process with its own package on ``PYTHONPATH``. Per sensor preset and kind of
episode (accuracy trial, pick-and-place episode with the regrasp method) it writes the
wall time per episode, the simulated time, the real-time factor (simulated / wall) and the
seconds per phase of each version, and the ratios before / after. The rows themselves are
compared by ``compare_runs.py``, not here. ``--threads``: the libraries' threads in each
process (``experiments.threads``; default 1, as each worker of ``--workers 2`` on 2 cores).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from comgrasp_pin.experiments.threads import THREAD_VARIABLES

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
KINDS = ("accuracy", "regrasp")


def worktree(ref: str) -> Path:
    """A checkout of ``ref`` beside the temp files (made once, reused)."""
    sha = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--short", ref],
                         check=True, capture_output=True, text=True).stdout.strip()  # fmt: skip
    path = Path(tempfile.gettempdir()) / f"comgrasp-before-{sha}"
    if not (path / "comgrasp_pin").is_dir():
        subprocess.run(["git", "-C", str(ROOT), "worktree", "add", "--detach", "-f", str(path),
                        sha], check=True, capture_output=True)  # fmt: skip
    return path


def run_phases(root: Path, args: argparse.Namespace, sensors: str, out: Path) -> dict:
    """One ``bench_episode_phases.py`` run of the code in ``root``; its JSON."""
    threads = {name: str(args.threads) for name in THREAD_VARIABLES}
    env = {**os.environ, **threads, "PYTHONPATH": str(root), "MUJOCO_GL": "egl"}
    cmd = [sys.executable, str(root / "benchmarks" / "bench_episode_phases.py"),
           "--objects", args.objects, "--trials", str(args.trials), "--sensors", sensors,
           "--out", str(out)]  # fmt: skip
    subprocess.run(cmd, check=True, env=env, cwd=root, stdout=subprocess.DEVNULL)
    return json.loads(out.read_text())


def summary(runs: list[dict]) -> dict:
    """Per kind of episode: mean wall and simulated seconds, real-time factor, phases."""
    out = {}
    for kind in KINDS:
        episodes = [e for r in runs for e in r["episodes"][kind]]
        wall = sum(e["wall_s"] for e in episodes)
        sim = sum(e["sim_s"] for e in episodes)
        phases = sorted({p for e in episodes for p in e["seconds"]})
        seconds = {p: sum(e["seconds"].get(p, 0.0) for e in episodes) / len(episodes)
                   for p in phases}  # fmt: skip
        out[kind] = {
            "episodes": len(episodes),
            "wall_s": wall / len(episodes),
            "sim_s": sim / len(episodes),
            "realtime_factor": sim / wall,
            "seconds": seconds,
            "share": {p: v * len(episodes) / wall for p, v in seconds.items()},
        }
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--before", required=True, help="the older commit (e.g. 49b14e3)")
    parser.add_argument("--objects", default="obj1,obj3,obj5")
    parser.add_argument("--trials", type=int, default=1)
    parser.add_argument("--rounds", type=int, default=2)
    parser.add_argument("--sensors", default="ideal,realistic")
    parser.add_argument("--threads", type=int, default=1)
    parser.add_argument("--out", default=str(HERE / "results" / "speedup.json"))
    args = parser.parse_args()
    before_root = worktree(args.before)
    roots = {"before": before_root, "after": ROOT}
    result: dict = {"before": args.before, "presets": {}}
    with tempfile.TemporaryDirectory() as tmp:
        for sensors in args.sensors.split(","):
            runs: dict[str, list[dict]] = {"before": [], "after": []}
            for r in range(args.rounds):
                order = ("before", "after") if r % 2 == 0 else ("after", "before")
                for version in order:
                    out = Path(tmp) / f"{sensors}-{version}-{r}.json"
                    runs[version].append(run_phases(roots[version], args, sensors, out))
                    print(f"{sensors} round {r + 1}/{args.rounds}: {version} done", flush=True)
            both = {v: summary(runs[v]) for v in runs}
            both["ratio_before_over_after"] = {
                kind: {
                    "wall": both["before"][kind]["wall_s"] / both["after"][kind]["wall_s"],
                    "phases": {
                        p: both["before"][kind]["seconds"][p] / v
                        for p, v in both["after"][kind]["seconds"].items()
                        if v > 0 and p in both["before"][kind]["seconds"]
                    },
                }
                for kind in KINDS
            }
            result["presets"][sensors] = both
    result["settings"] = {"objects": args.objects, "trials": args.trials,
                          "rounds": args.rounds, "threads": args.threads}  # fmt: skip
    result["environment"] = {"cpus": os.cpu_count(), "load_avg_1min": os.getloadavg()[0],
                             "date": time.strftime("%Y-%m-%d %H:%M:%S UTC", time.gmtime())}  # fmt: skip
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    Path(args.out).write_text(json.dumps(result, indent=2) + "\n")
    for sensors, both in result["presets"].items():
        for kind in KINDS:
            b, a = both["before"][kind], both["after"][kind]
            print(f"{sensors} {kind}: x{b['realtime_factor']:.1f} -> x{a['realtime_factor']:.1f} "
                  f"real time ({b['wall_s']:.2f} -> {a['wall_s']:.2f} s per episode)")  # fmt: skip
    print(f"written to {args.out}")


if __name__ == "__main__":
    main()
