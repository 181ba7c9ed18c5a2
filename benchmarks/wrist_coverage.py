"""The error bars of the CoM position (``pos_std_m``) on seeds never used in tuning.

    python benchmarks/wrist_coverage.py --label after               # run and summarise
        [--seeds 914,916] [--presets ideal,realistic] [--objects obj1,...,obj6]
        [--trials 10] [--workers 1] [--runs /tmp/wrist_coverage]
        [--code DIR]    # another checkout's code (e.g. the branch before a change: 'before')
    python benchmarks/wrist_coverage.py --label before --read-only  # summarise runs made

Why (issue 34, item 5): the wrist camera's depth line is part of the CoM position's error
model (``procedures.uncertainty.motion_stds``, its ``shift`` part). Its targets, on seeds no
coefficient was tuned on (the depth line's error was measured on seeds 913 and 915 by
``depth_line_error.py``; 914 and 916 are kept for this check):
- both presets: the 95 % interval (1.96 ``pos_std_m``) holds the truth in 90-97 % of the
  grasps, rms z 0.85-1.2 (z = (pos_esti_m - pos_real_m) / pos_std_m, as the report's
  calibration computes it: ``experiments.report.calibration.calibration_z``);
- realistic: mean accuracy below 30 deg >= 98 % pooled (``experiments.report.sensors``);
- obj1 and obj3, realistic: at most 1 grasp in 16 without an estimate.

How: ``comgrasp accuracy`` runs (one CSV per seed and preset under ``--runs/LABEL``), with
the code on ``PYTHONPATH`` (``--code``: this checkout by default). Rows with an error are
grasps without an estimate, counted per object with their error's kind.

Writes (merges) ``benchmarks/results/wrist_coverage.json``: per label ("before", "after"),
per preset and seed and pooled per preset: n, coverage 68/95, rms and mean z, accuracy
below 30 deg, the grasps without an estimate per object and their errors; the settings.
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import subprocess
import sys
import time
from collections import Counter
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "benchmarks" / "results" / "wrist_coverage.json"
Z95, Z68 = 1.959964, 1.0
UP_TO_DEG = 30.0  # experiments.report.sensors.UP_TO_DEG


def _float(row: dict, key: str) -> float:
    try:
        return float(row.get(key, "nan"))
    except ValueError:
        return float("nan")


def summarise_rows(rows: list[dict]) -> dict:
    """Coverage, rms z, accuracy below 30 deg and the grasps without an estimate."""
    ok = [r for r in rows if not r.get("error")]
    z = np.array([
        (_float(r, "pos_esti_m") - _float(r, "pos_real_m")) / _float(r, "pos_std_m")
        for r in ok
    ])  # fmt: skip
    z = z[np.isfinite(z)]
    theta = np.abs([_float(r, "theta_deg") for r in ok])
    acc = np.array([_float(r, "accuracy") for r in ok])
    low = (theta < UP_TO_DEG) & np.isfinite(acc)
    failed: dict[str, dict] = {}
    for r in rows:
        obj = r["object"]
        entry = failed.setdefault(obj, {"grasps": 0, "no_estimate": 0, "errors": Counter()})
        entry["grasps"] += 1
        if r.get("error"):
            entry["no_estimate"] += 1
            entry["errors"][str(r["error"]).split(":")[0]] += 1
    for entry in failed.values():
        entry["errors"] = dict(entry["errors"])
    parts = ("estimator", "tilt", "shift", "out_of_plane", "slide", "creep", "calibration")
    med = {}
    for part in parts:
        values = np.array([_float(r, f"pos_std_{part}_m") for r in ok])
        if np.isfinite(values).any():
            med[part] = float(np.nanmedian(values) * 1e3)
    return {
        "grasps": len(rows),
        "estimated": len(ok),
        "n_z": int(len(z)),
        "coverage_95": float(np.mean(np.abs(z) <= Z95)) if len(z) else float("nan"),
        "coverage_68": float(np.mean(np.abs(z) <= Z68)) if len(z) else float("nan"),
        "rms_z": float(np.sqrt(np.mean(z * z))) if len(z) else float("nan"),
        "mean_z": float(np.mean(z)) if len(z) else float("nan"),
        "accuracy_below_30_deg_pct": float(100 * np.mean(acc[low])) if low.any() else None,
        "n_below_30_deg": int(low.sum()),
        "median_pos_std_mm": float(np.nanmedian([_float(r, "pos_std_m") for r in ok]) * 1e3)
        if ok
        else None,
        "median_pos_std_parts_mm": med,
        "by_object": failed,
    }


def read_csv(path: Path) -> list[dict]:
    with path.open() as f:
        return list(csv.DictReader(f))


def run_one(code: Path, out: Path, seed: int, preset: str, objects: str, trials: int,
            workers: int) -> float:  # fmt: skip
    """One ``comgrasp accuracy`` run (wall time, s)."""
    env = {**os.environ, "PYTHONPATH": str(code), "MUJOCO_GL": "egl"}
    cmd = [sys.executable, "-m", "comgrasp_pin.cli", "accuracy", "--seed", str(seed),
           "--objects", objects, "--trials", str(trials), "--sensors", preset,
           "--workers", str(workers), "--overwrite", "--out", str(out)]  # fmt: skip
    start = time.perf_counter()
    subprocess.run(cmd, env=env, check=True, stdout=subprocess.DEVNULL)
    return time.perf_counter() - start


def code_commit(code: Path) -> str:
    """The commit of ``code``: its COMMIT file (an exported tree) or its git HEAD."""
    if (code / "COMMIT").exists():
        return (code / "COMMIT").read_text().strip()
    head = subprocess.run(["git", "-C", str(code), "rev-parse", "HEAD"], capture_output=True,
                          text=True, check=False)  # fmt: skip
    return head.stdout.strip() or "unknown"


def summarise_label(runs: Path, seeds: list[int], presets: list[str]) -> dict:
    """Per preset: per seed and pooled over the seeds."""
    out: dict = {}
    for preset in presets:
        pooled: list[dict] = []
        entry: dict = {}
        for seed in seeds:
            path = runs / f"s{seed}_{preset}" / "accuracy.csv"
            if not path.exists():
                continue
            rows = read_csv(path)
            pooled += rows
            entry[f"seed {seed}"] = summarise_rows(rows)
        if pooled:
            entry["pooled"] = summarise_rows(pooled)
        out[preset] = entry
    return out


def print_table(label: str, summary: dict) -> None:
    print(f"\n{label}: {'preset':<10} {'seed':<9} {'n':>4} {'cov95':>6} {'rms z':>6} "
          f"{'acc<30':>7} {'no est. obj1':>12} {'obj3':>5}")  # fmt: skip
    for preset, entry in summary.items():
        for key, s in entry.items():
            acc = s["accuracy_below_30_deg_pct"]
            no = {o: f"{s['by_object'][o]['no_estimate']}/{s['by_object'][o]['grasps']}"
                  for o in ("obj1", "obj3") if o in s["by_object"]}  # fmt: skip
            print(f"{'':<{len(label) + 2}}{preset:<10} {key:<9} {s['n_z']:>4} "
                  f"{100 * s['coverage_95']:>5.1f}% {s['rms_z']:>6.2f} "
                  f"{'-' if acc is None else f'{acc:.1f}':>7} {no.get('obj1', '-'):>12} "
                  f"{no.get('obj3', '-'):>5}")  # fmt: skip


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--label", default="after", help="before / after (a key of the JSON)")
    p.add_argument("--seeds", default="914,916", help="run seeds never used in tuning")
    p.add_argument("--presets", default="ideal,realistic")
    p.add_argument("--objects", default="obj1,obj2,obj3,obj4,obj5,obj6")
    p.add_argument("--trials", type=int, default=10)
    p.add_argument("--workers", type=int, default=1)
    p.add_argument("--runs", type=Path, default=Path("/tmp/wrist_coverage"))
    p.add_argument("--code", type=Path, default=ROOT, help="the checkout whose code runs")
    p.add_argument("--read-only", action="store_true", help="summarise the CSVs already run")
    p.add_argument("--out", type=Path, default=OUT)
    opts = p.parse_args()
    seeds = [int(s) for s in opts.seeds.split(",")]
    presets = opts.presets.split(",")
    runs = opts.runs / opts.label
    walls = {}
    if not opts.read_only:
        for seed in seeds:
            for preset in presets:
                walls[f"{preset} {seed}"] = run_one(opts.code, runs / f"s{seed}_{preset}",
                                                    seed, preset, opts.objects, opts.trials,
                                                    opts.workers)  # fmt: skip
    summary = summarise_label(runs, seeds, presets)
    data = json.loads(opts.out.read_text()) if opts.out.exists() else {}
    data["about"] = ("Calibration of pos_std_m (95 % coverage, rms z), accuracy below 30 deg "
                     "and grasps without an estimate, on seeds never tuned on "
                     "(benchmarks/wrist_coverage.py).")  # fmt: skip
    data[opts.label] = {
        "settings": {"seeds": seeds, "presets": presets, "objects": opts.objects.split(","),
                     "trials": opts.trials, "code": str(opts.code),
                     "code_commit": code_commit(opts.code), "wall_s": walls},
        "summary": summary,
    }  # fmt: skip
    opts.out.parent.mkdir(parents=True, exist_ok=True)
    opts.out.write_text(json.dumps(data, indent=1) + "\n")
    print_table(opts.label, summary)
    print(f"\nwrote {opts.out}")


if __name__ == "__main__":
    main()
