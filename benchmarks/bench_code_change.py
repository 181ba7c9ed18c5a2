"""A code change that moves the random stream: this checkout against a commit, same scenes.

    python benchmarks/bench_code_change.py BEFORE_COMMIT [--trials 10] [--workers 2]
        [--objects obj1,...,obj6] [--cases accuracy:ideal,...] [--runs /tmp/code_change]
        [--out benchmarks/results/code_change.json]

The paired protocol of ``bench_levers.py`` for two versions of the code instead of two values
of the config tree: BEFORE_COMMIT's package (``git archive`` of ``comgrasp_pin``, ``sim`` and
``urdf`` into a temporary folder) and this checkout's run the same experiments with the same
seed (the same scenes: objects, grasps, sensor offsets), one after the other in each case so
that the machine's drift is in both. Per case (experiment and sensor preset) the JSON gives
each version's wall seconds per trial and their ratio, the sweep's measures (mean accuracy,
success, coverage of the 95 % interval, each with its 95 % interval; rms z) and the paired
differences: accuracy below 30 deg (this checkout - before, t interval over the grasps both
measured), the tilt's moves, and for pick-and-place the scenes whose outcome flipped. Both
versions' runs are kept in ``--runs`` (resumed: a finished one is not run again).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

from bench_levers import OBJECTS, _outcome, _speed, paired, write

from comgrasp_pin.experiments.runner import read_rows

ROOT = Path(__file__).resolve().parents[1]
CASES = "accuracy:ideal,accuracy:realistic,regrasp:ideal,regrasp:realistic"
BELOW_DEG = 30.0  # the paper's range of tilts: the accuracy compared below it


def run(package_root: Path, experiment: str, sensors: str, args, out: Path) -> list[dict]:
    """``comgrasp EXPERIMENT`` with the package under ``package_root``; its rows."""
    csv_path = out / f"{experiment}.csv"
    cmd = [sys.executable, "-m", "comgrasp_pin.cli", experiment, "--sensors", sensors,
           "--objects", args.objects, "--trials", str(args.trials), "--workers",
           str(args.workers), "--seed", str(args.seed), "--out", str(out)]  # fmt: skip
    if csv_path.exists():
        cmd.append("--resume")  # a finished run has nothing left to do
    env = {**os.environ, "MUJOCO_GL": "egl", "PYTHONPATH": str(package_root)}
    subprocess.run(cmd, check=True, env=env, cwd=tempfile.gettempdir())
    return read_rows(csv_path)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("before", help="the commit to compare this checkout with")
    parser.add_argument("--trials", type=int, default=10)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--objects", default=OBJECTS)
    parser.add_argument("--cases", default=CASES)
    parser.add_argument("--runs", type=Path, default=Path("/tmp/comgrasp_code_change"))
    parser.add_argument("--out", type=Path, default=ROOT / "benchmarks/results/code_change.json")
    args = parser.parse_args()
    results: dict = {}
    with tempfile.TemporaryDirectory() as tmp:
        old = Path(tmp)
        archive = subprocess.run(["git", "-C", str(ROOT), "archive", args.before, "comgrasp_pin",
                                  "sim", "urdf"], check=True, capture_output=True).stdout  # fmt: skip
        subprocess.run(["tar", "-x", "-C", str(old)], input=archive, check=True)
        for case in args.cases.split(","):
            experiment, sensors = case.split(":")
            rows = {name: run(root, experiment, sensors, args, args.runs / f"{name}_{case}")
                    for name, root in (("before", old), ("after", ROOT))}  # fmt: skip
            kind = "accuracy" if experiment == "accuracy" else "regrasp"
            speed = {name: _speed(r) for name, r in rows.items()}
            results[case] = {
                "speed": speed,
                "wall_ratio_before_over_after": speed["before"]["wall_s_per_trial"]
                / speed["after"]["wall_s_per_trial"],
                "outcome": {name: _outcome(r, kind) for name, r in rows.items()},
                "paired_after_minus_before": paired(
                    rows["before"], rows["after"], kind, BELOW_DEG
                ),  # fmt: skip
            }
            print(case, json.dumps(results[case]["paired_after_minus_before"]), flush=True)
    write(results, {"before": args.before, "trials_per_object": args.trials,
                    "objects": args.objects, "seed": args.seed, "workers": args.workers},
          args.out)  # fmt: skip


if __name__ == "__main__":
    main()
