"""What the levers that change the physics buy, and what they cost: paired sweeps.

    python benchmarks/bench_levers.py [--trials 10] [--workers 2] [--runs /tmp/levers]
                                      [--levers sim_dt,settle,noslip] [--cases CASES]
                                      [--out benchmarks/results/levers.json]

Issue 16 lists levers that would make an episode cheaper by changing what is simulated: a
coarser physics step, shorter fixed waits. Each is a value of the config tree, so each is
measured with ``comgrasp sweep`` (kept in ``--runs``, resumable): the paper's six objects,
``--trials`` trials each, at the current value and at the lever's, with the same seeds at
both (the same scenes and sensor noise: common random numbers). Per lever, experiment and
sensor preset the JSON gives

- the speed: wall seconds and simulated seconds per trial at each value, and their ratio
  (the two values' trials run one after the other in one process pool: the machine's drift
  from hour to hour, about 10 %, is in the ratio);
- what changes: at each value the sweep's own measures (ours' mean accuracy, the grasps that
  gave an estimate, the coverage of the 95 % interval) and the rms z; the paired difference of accuracy (lever - current, t interval) over the
  grasps measured at both, how far the tilt in the jaws moved; for pick-and-place, both
  methods' successes at each value and the scenes whose outcome flipped.

A lever "pays" when it is faster and its paired differences' intervals hold 0 (or lie within
a point of accuracy) with no more refusals or failures: nothing here decides that, the
README says what was kept and why.
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from comgrasp_pin.experiments.stats import calibration, paired_difference, z_scores
from comgrasp_pin.experiments.sweep import point_measures

OBJECTS = "obj1,obj2,obj3,obj4,obj5,obj6"
LEVERS = {
    "sim_dt": ("world.sim_dt", (0.002, 0.004), "the physics step (the servo and the torque "
               "sensor run every step, so their rate halves with it)"),
    "settle": ("trial.settle", (0.5, 0.2), "the wait before every torque window, empty arm "
               "and holding"),
    "noslip": ("world.noslip_iterations", (50, 20), "MuJoCo's no-slip solver iterations, "
               "which make static friction hold in the jaws"),
    "watch_stride": ("sensors.watch_stride", (3, 4), "the slip watch's frames: every 3rd or "
                     "every 4th pixel of each row and column rendered and read (the physics "
                     "unchanged)"),
}  # fmt: skip
CASES = "accuracy:ideal,accuracy:realistic,regrasp:ideal"  # --cases; regrasp:realistic too


def run_sweep(path: str, values, experiment: str, sensors: str, args, out: Path) -> Path:
    """``comgrasp sweep`` of ``path`` at ``values`` into ``out`` (resumed if there)."""
    cmd = [sys.executable, "-m", "comgrasp_pin.cli", "sweep", "--param",
           f"{path}={','.join(str(v) for v in values)}", "--experiment", experiment,
           "--sensors", sensors, "--objects", OBJECTS, "--trials", str(args.trials),
           "--workers", str(args.workers), "--out", str(out)]  # fmt: skip
    if (out / "sweep.csv").exists():
        cmd.append("--resume")
    subprocess.run(cmd, check=True, env={**os.environ, "MUJOCO_GL": "egl"})
    return out / "sweep.csv"


def _f(row: dict, key: str) -> float:
    try:
        return float(row[key])
    except (KeyError, ValueError):
        return float("nan")


def _speed(rows: list[dict]) -> dict:
    wall = [_f(r, "wall_s") for r in rows]
    sim = [_f(r, "sim_s") for r in rows]
    return {"trials": len(rows), "wall_s_per_trial": float(np.nanmean(wall)),
            "sim_s_per_trial": float(np.nanmean(sim)),
            "realtime_factor": float(np.nansum(sim) / np.nansum(wall))}  # fmt: skip


def _outcome(rows: list[dict], experiment: str) -> dict:
    """One value's outcome: the sweep's own measures (``sweep.point_measures``: mean
    accuracy, success, coverage of the 95 % interval, each as value, 95 % low, high, n),
    the rms z of the error bars, and for pick-and-place the baseline's successes too."""
    out: dict = dict(point_measures(rows, experiment))
    ok = [r for r in rows if not r.get("error")]
    z = z_scores(*(np.array([_f(r, c) for r in ok]) for c in
                   ("pos_esti_m", "pos_real_m", "pos_std_m")))  # fmt: skip
    out["rms_z"] = calibration(z).rms
    if experiment == "regrasp":
        baseline = [r for r in rows if r["method"] == "baseline"]
        out["baseline_successes"] = [sum(_f(r, "success") == 1 for r in baseline), len(baseline)]
    return out


def compare(csv_path: Path, path: str, values, experiment: str) -> dict:
    """The two values' speed and outcomes, and their paired differences."""
    with open(csv_path, newline="") as f:
        rows = list(csv.DictReader(f))
    at = {v: [r for r in rows if float(r[path]) == float(v)] for v in values}
    base, lever = values
    out = {"values": list(values), "speed": {str(v): _speed(at[v]) for v in values},
           "outcome": {str(v): _outcome(at[v], experiment) for v in values}}  # fmt: skip
    out["wall_ratio_current_over_lever"] = (out["speed"][str(base)]["wall_s_per_trial"]
                                            / out["speed"][str(lever)]["wall_s_per_trial"])  # fmt: skip
    out["paired"] = paired(at[base], at[lever], experiment)
    return out


def paired(base: list[dict], lever: list[dict], experiment: str, below_deg: float = 90.0) -> dict:
    """The paired differences of two runs of the same trials (matched by object, trial and
    method): accuracy (lever - base, points, t interval; over the grasps both measured whose
    base tilt is below ``below_deg``) and the tilt's moves, or pick-and-place's flips."""
    key = ("object", "trial", "method")
    pairs: dict = {}
    for name, rows in (("base", base), ("lever", lever)):
        for r in rows:
            pairs.setdefault(tuple(r[k] for k in key), {})[name] = r
    both = [p for p in pairs.values() if len(p) == 2]
    if experiment == "accuracy":
        both = [p for p in both if abs(_f(p["base"], "theta_deg")) < below_deg
                or not np.isfinite(_f(p["base"], "theta_deg"))]  # fmt: skip
        a = np.array([_f(p["lever"], "accuracy") for p in both])
        b = np.array([_f(p["base"], "accuracy") for p in both])
        d = paired_difference(100 * a, 100 * b)
        tilt = np.array([abs(_f(p["lever"], "theta_true_deg") - _f(p["base"], "theta_true_deg"))
                         for p in both])  # fmt: skip
        tilt = tilt[np.isfinite(tilt)]
        return {"accuracy_diff_pct": [d.diff.mean, d.diff.lo, d.diff.hi, d.diff.n],
                "lever_better": d.a_better, "current_better": d.b_better,
                "tilt_change_deg_median": float(np.median(tilt)) if len(tilt) else None,
                "tilt_changed_over_5deg": int(np.sum(tilt > 5.0))}  # fmt: skip
    flips = {m: [0, 0] for m in ("baseline", "regrasp")}
    for p in both:
        s0, s1 = _f(p["base"], "success"), _f(p["lever"], "success")
        if s0 != s1:
            flips[p["base"]["method"]][int(s1 == 1)] += 1
    return {"flipped_to_failure_and_to_success": flips, "pairs": len(both)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--trials", type=int, default=10)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--levers", default=",".join(LEVERS))
    parser.add_argument("--cases", default=CASES, help="experiment:sensors, comma-separated")
    parser.add_argument("--runs", type=Path, default=Path("/tmp/comgrasp_levers"))
    parser.add_argument("--out", type=Path, default=Path("benchmarks/results/levers.json"))
    args = parser.parse_args()
    results = {}
    for name in args.levers.split(","):
        path, values, what = LEVERS[name]
        results[name] = {"path": path, "what": what}
        for experiment, sensors in (c.split(":") for c in args.cases.split(",")):
            out = args.runs / f"{name}_{experiment}_{sensors}"
            csv_path = run_sweep(path, values, experiment, sensors, args, out)
            case = compare(csv_path, path, values, experiment)
            results[name][f"{experiment}_{sensors}"] = case
            print(name, experiment, sensors, json.dumps(case["speed"]), flush=True)
    write(results, {"trials_per_object": args.trials, "objects": OBJECTS,
                    "workers": args.workers, "cases": args.cases}, args.out)  # fmt: skip


def write(results: dict, environment: dict, out: Path) -> None:
    """``results`` with their ``environment`` (and the machine's cores and the date) as
    JSON in ``out``."""
    results["environment"] = {**environment, "cpus": os.cpu_count(),
                              "date": time.strftime("%Y-%m-%d %H:%M:%S UTC", time.gmtime())}  # fmt: skip
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(results, indent=2) + "\n")
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
