"""`comgrasp live` on the simulated FR3: 20 payloads, errors, interval coverage, wall time.

Each payload (mass 0.2-2.5 kg, CoM up to 10 cm off the flange's axis and 2-12 cm along it,
principal moments of a solid of that mass) is attached by franky-sim between the empty and
the loaded run; the command runs as a user runs it (``comgrasp live --sim --yes --set-load``,
a subprocess, static poses planned near the arm's pose, each approached from both sides).
Against the simulator's body it records the mass and CoM errors, whether each stated 95 %
interval (Student's t of its dof) holds the truth, whether the load was set, and the wall
time of one identification (connect, plan, both runs, estimate, set_load). Then ``--empty``
sessions with nothing attached: the load must never be set.

``--motion``: the same payloads measured along one planned motion instead (``comgrasp
plan-motion`` for the FR3 at the sim's pose, 8 s, ``MOTION_OPTIONS``: slow enough for
dynamics factor 0.2; planned once, its time given apart), written to ``live_franka_motion.json``.

    python benchmarks/live_franka.py [--n 20] [--empty 2] [--seed 0] [--n-poses K]
        [--dynamics-factor F] [--motion] [--out JSON]

Needs the franka extra (``pip install ".[franka]"``); connects only to 127.0.0.1.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

SIM_START = "0,0,0,-1.5708,0,1.5708,0.7854"  # franky-sim's FR3 at start (rad)
MOTION_OPTIONS = ["--duration", "8", "--velocity-scale", "0.3", "--acceleration", "3"]


def plan_motion(path: Path) -> float:
    """Plan the benchmark's motion into ``path``; the planning's wall time (s)."""
    from comgrasp_pin._paths import fr3_urdf

    cmd = [sys.executable, "-m", "comgrasp_pin.cli", "plan-motion", "--urdf", str(fr3_urdf()),
           "--ee-frame", "fr3_link8", "--start", SIM_START, *MOTION_OPTIONS, "--out", str(path)]  # fmt: skip
    start = time.monotonic()
    subprocess.run(cmd, check=True, capture_output=True, text=True, timeout=600)
    return time.monotonic() - start


def draw_payloads(n: int, seed: int) -> list[dict]:
    """``n`` payloads: mass (kg), CoM in the flange frame (m), principal moments (kg m^2)."""
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(n):
        mass = rng.uniform(0.2, 2.5)
        r, angle = 0.10 * np.sqrt(rng.uniform()), rng.uniform(0, 2 * np.pi)
        com = [r * np.cos(angle), r * np.sin(angle), rng.uniform(0.02, 0.12)]
        side = rng.uniform(0.04, 0.15, 3)  # a box's sides (m)
        moments = [mass * (side[1] ** 2 + side[2] ** 2) / 12, mass * (side[0] ** 2 + side[2] ** 2) / 12,
                   mass * (side[0] ** 2 + side[1] ** 2) / 12]  # fmt: skip
        out.append({"mass_kg": mass, "com_m": com, "moments_kgm2": moments})
    return out


def run_live(out: Path, payload: dict | None, options: list[str] = ()) -> tuple:
    """One `comgrasp live --sim` identification; (the process, its wall time in s)."""
    cmd = [sys.executable, "-m", "comgrasp_pin.cli", "live", "--sim", "--yes", "--set-load",
           "--out", str(out), *options]  # fmt: skip
    if payload is not None:
        values = [payload["mass_kg"], *payload["com_m"], *payload["moments_kgm2"]]
        cmd += ["--sim-payload", ",".join(f"{v:.9g}" for v in values)]
    start = time.monotonic()
    res = subprocess.run(cmd, capture_output=True, text=True, timeout=600,
                         stdin=subprocess.DEVNULL)  # fmt: skip
    return res, time.monotonic() - start


def score(payload: dict, out: Path, res, wall_s: float) -> dict:
    """One row: the estimate against the truth."""
    row = {"truth": payload, "exit_status": res.returncode, "wall_time_s": round(wall_s, 2)}
    info = json.loads((out / "live.json").read_text())
    row["set_load"] = info.get("set_load")
    result = out / "RESULT.json"
    if not result.exists():
        row["error"] = res.stderr.strip().splitlines()[-1]
        return row
    r = json.loads(result.read_text())
    mass, com = r["mass_kg"], np.array(r["com_m"])
    m_true, c_true = payload["mass_kg"], np.array(payload["com_m"])
    lo, hi = r["interval95_mass_kg"]
    c_iv = np.array(r["interval95_com_m"])
    row.update(
        verdict=r["verdict"],
        mass_kg=mass,
        mass_error_pct=100 * (mass - m_true) / m_true,
        com_error_mm=float(1e3 * np.linalg.norm(com - c_true)),
        mass_z=(mass - m_true) / r["std"]["mass_kg"],
        com_z=((com - c_true) / np.array(r["std"]["com_m"])).tolist(),
        mass_held=bool(lo <= m_true <= hi),
        com_held=[bool(a <= t <= b) for (a, b), t in zip(c_iv, c_true)],
        dof=r.get("dof"),
        inertia_verdict=(r.get("inertia") or {}).get("verdict"),
    )
    return row


def wilson(k: int, n: int) -> list[float]:
    """The binomial proportion's 95 % interval (Wilson)."""
    z = 1.959963984540054
    p = k / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * np.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    return [float(centre - half), float(centre + half)]


def summary(rows: list[dict], empty: list[dict]) -> dict:
    scored = [r for r in rows if "mass_error_pct" in r]
    held = [r["mass_held"] for r in scored] + [h for r in scored for h in r["com_held"]]
    return {
        "n_payloads": len(rows),
        "identified": sum(r.get("verdict") == "identified" for r in rows),
        "load_set": sum(bool(r["set_load"]) for r in rows),
        "max_abs_mass_error_pct": max(abs(r["mass_error_pct"]) for r in scored),
        "rms_mass_error_pct": float(np.sqrt(np.mean([r["mass_error_pct"] ** 2 for r in scored]))),
        "max_com_error_mm": max(r["com_error_mm"] for r in scored),
        "rms_com_error_mm": float(np.sqrt(np.mean([r["com_error_mm"] ** 2 for r in scored]))),
        "coverage_mass": sum(r["mass_held"] for r in scored) / len(scored),
        "coverage_mass_wilson95": wilson(sum(r["mass_held"] for r in scored), len(scored)),
        "coverage_all_intervals": sum(held) / len(held),
        "coverage_all_intervals_wilson95": wilson(sum(held), len(held)),
        "rms_z_mass": float(np.sqrt(np.mean([r["mass_z"] ** 2 for r in scored]))),
        "rms_z_com": float(np.sqrt(np.mean([np.square(r["com_z"]) for r in scored]))),
        "wall_time_s_mean": float(np.mean([r["wall_time_s"] for r in rows])),
        "wall_time_s_max": max(r["wall_time_s"] for r in rows),
        "empty_sessions": len(empty),
        "empty_sessions_load_set": sum(bool(r["set_load"]) for r in empty),
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=20)
    ap.add_argument("--empty", type=int, default=2)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--n-poses", type=int, default=None, help="comgrasp live's (its default)")
    ap.add_argument("--dynamics-factor", type=float, default=None, help="comgrasp live's")
    ap.add_argument("--motion", action="store_true", help="along a planned motion")
    ap.add_argument("--out", default=None, help="JSON (default benchmarks/results/"
                    "live_franka.json, or live_franka_motion.json with --motion)")  # fmt: skip
    ap.add_argument(
        "--keep",
        default=None,
        metavar="DIR",
        help="keep each session's folder (log, live.json, RESULT.json) in DIR",
    )
    args = ap.parse_args()
    options = [] if args.n_poses is None else ["--n-poses", str(args.n_poses)]
    if args.dynamics_factor is not None:
        options += ["--dynamics-factor", str(args.dynamics_factor)]
    args.out = args.out or "benchmarks/results/" + (
        "live_franka_motion.json" if args.motion else "live_franka.json"
    )
    rows, empty, plan_s = [], [], None
    with tempfile.TemporaryDirectory() as scratch:
        tmp = args.keep or scratch
        if args.motion:
            Path(tmp).mkdir(parents=True, exist_ok=True)
            plan_s = plan_motion(Path(tmp) / "motion.json")
            options += ["--motion", str(Path(tmp) / "motion.json")]
        for i, payload in enumerate(draw_payloads(args.n, args.seed)):
            out = Path(tmp) / f"p{i}"
            res, wall = run_live(out, payload, options)
            rows.append(score(payload, out, res, wall))
            r = rows[-1]
            print(f"{i:2d} {payload['mass_kg']:.3f} kg: {r.get('verdict', r.get('error'))}, "
                  f"mass {r.get('mass_error_pct', np.nan):+.2f} %, CoM "
                  f"{r.get('com_error_mm', np.nan):.2f} mm, {wall:.1f} s", flush=True)  # fmt: skip
        for i in range(args.empty):
            out = Path(tmp) / f"e{i}"
            res, wall = run_live(out, None, options)
            info = json.loads((out / "live.json").read_text())
            empty.append({"exit_status": res.returncode, "wall_time_s": round(wall, 2),
                          "set_load": info.get("set_load"),
                          "message": res.stderr.strip().splitlines()[-1]})  # fmt: skip
            print(f"empty {i}: exit {res.returncode}, {empty[-1]['message'][-90:]}", flush=True)
    result = {"args": vars(args), "summary": {**summary(rows, empty), "plan_motion_s": plan_s},
              "payloads": rows, "empty": empty}  # fmt: skip
    Path(args.out).write_text(json.dumps(result, indent=2) + "\n")
    print(json.dumps(result["summary"], indent=2))
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
