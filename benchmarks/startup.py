"""Start-up of the robot side: `comgrasp estimate --help` and a static estimate from a CSV.

    python benchmarks/startup.py --before-tree PATH [--after-tree PATH] [--rounds 10]

Each command runs as a whole process (``python -m comgrasp_pin.cli ...``, Python's start-up
and every import included), once with the package of ``--after-tree`` (default: this
checkout) and once with the one in ``--before-tree`` (a checkout of older code, e.g. ``git worktree add /tmp/base 94d678b``), in
turn (after, before, after, before ...: the machine's drift falls on both), each from an
empty folder with its tree first on ``PYTHONPATH``. Per version: the wall seconds (median,
min, max over ``--rounds``), the ratio after / before taken pair by pair (median), and which
of MuJoCo, OpenCV (cv2) and matplotlib the command had loaded when it ended.

The log is the README's: the Panda (example-robot-data) at three static poses, 1 s each at
200 Hz, empty then holding 0.8 kg at (20, -10, 50) mm in panda_hand_tcp, efforts from
Pinocchio's RNEA with 0.05 N m noise per sample, written as a CSV.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import pinocchio as pin

from comgrasp_pin._paths import example_robot_urdf
from comgrasp_pin.robot_io import JointLog, load_robot, write_csv

HERE = Path(__file__).resolve().parent
URDF = str(example_robot_urdf("panda_description/urdf/panda.urdf"))
EE = "panda_hand_tcp"
Q = np.array([[0.0, -0.3, 0.0, -2.2, 0.0, 2.0, 0.8], [0.5, -0.6, 0.3, -1.8, 1.2, 1.2, -0.6],
              [-0.4, 0.2, -0.2, -2.4, -1.0, 2.6, 1.5]])  # fmt: skip
MASS, COM = 0.8, np.array([0.02, -0.01, 0.05])
RATE, NOISE = 200, 0.05
LIBRARIES = ("mujoco", "cv2", "matplotlib")
_PROBE = (
    "import json, runpy, sys\n"
    "sys.argv = ['comgrasp', *json.loads(sys.argv[1])]\n"
    "try:\n    runpy.run_module('comgrasp_pin.cli', run_name='__main__')\n"
    "except SystemExit:\n    pass\n"
    f"print(json.dumps([m for m in {LIBRARIES!r} if m in sys.modules]), file=sys.stderr)\n"
)


def make_log(folder: Path) -> Path:
    """The README's log as ``folder/log.csv``: 3 poses empty, then 3 holding, 1 s each."""
    robot = load_robot(URDF, EE)
    loaded = pin.Model(robot.model)
    frame = loaded.frames[robot.ee_frame_id]
    loaded.appendBodyToJoint(
        frame.parentJoint, pin.Inertia(MASS, COM, 1e-4 * np.eye(3)), frame.placement
    )
    rng = np.random.default_rng(0)
    efforts = []
    for model in (robot.model, loaded):
        for q in Q:
            tau = pin.computeGeneralizedGravity(model, model.createData(), q)
            efforts.append(tau + NOISE * rng.standard_normal((RATE, robot.nq)))
    t = np.arange(2 * len(Q) * RATE) / RATE
    log = JointLog(t, tuple(robot.joint_names), np.repeat(np.vstack([Q, Q]), RATE, axis=0),
                   np.concatenate(efforts))  # fmt: skip
    return write_csv(log, folder / "log.csv")


def commands(log: Path, out: Path) -> dict[str, list[str]]:
    """The two commands' arguments after ``comgrasp``."""
    windows = ["--before", "0.1:0.9,1.1:1.9,2.1:2.9", "--after", "3.1:3.9,4.1:4.9,5.1:5.9"]
    return {
        "estimate_help": ["estimate", "--help"],
        "estimate_static_csv": [
            "estimate",
            "--urdf",
            URDF,
            "--ee-frame",
            EE,
            "--csv",
            str(log),
            *windows,
            "--out",
            str(out),
        ],  # fmt: skip
    }


def _env(tree: Path) -> dict[str, str]:
    return {**os.environ, "PYTHONPATH": str(tree), "MUJOCO_GL": os.environ.get("MUJOCO_GL", "egl")}


def run_once(tree: Path, argv: list[str], cwd: Path) -> float:
    """Wall seconds of ``python -m comgrasp_pin.cli argv`` with ``tree``'s package."""
    t0 = time.perf_counter()
    res = subprocess.run([sys.executable, "-m", "comgrasp_pin.cli", *argv], cwd=cwd,
                         env=_env(tree), capture_output=True, text=True)  # fmt: skip
    seconds = time.perf_counter() - t0
    if res.returncode != 0:
        raise SystemExit(f"{' '.join(argv)} with {tree} failed:\n{res.stderr}")
    return seconds


def libraries_loaded(tree: Path, argv: list[str], cwd: Path) -> list[str]:
    """Which of LIBRARIES the command had loaded when it ended."""
    res = subprocess.run([sys.executable, "-c", _PROBE, json.dumps(argv)], cwd=cwd,
                         env=_env(tree), capture_output=True, text=True)  # fmt: skip
    return json.loads(res.stderr.strip().splitlines()[-1])


def _spread(values: list[float]) -> dict:
    return {"median_s": round(statistics.median(values), 4), "min_s": round(min(values), 4),
            "max_s": round(max(values), 4), "runs_s": [round(v, 4) for v in values]}  # fmt: skip


def measure(trees: dict[str, Path], argv: list[str], rounds: int, cwd: Path) -> dict:
    """Both versions in turn, one warm-up each; per version its spread, and the ratio."""
    for tree in trees.values():
        run_once(tree, argv, cwd)
    times = {name: [] for name in trees}
    for _ in range(rounds):
        for name, tree in trees.items():
            times[name].append(run_once(tree, argv, cwd))
    ratios = [a / b for a, b in zip(times["after"], times["before"], strict=True)]
    return {
        **{
            name: {**_spread(t), "loaded": libraries_loaded(trees[name], argv, cwd)}
            for name, t in times.items()
        },  # fmt: skip
        "ratio_after_over_before": round(statistics.median(ratios), 3),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--before-tree", required=True, type=Path,
                        help="a checkout of the older code (its comgrasp_pin/ and sim/)")  # fmt: skip
    parser.add_argument("--after-tree", type=Path, default=HERE.parent,
                        help="the newer code (default: this checkout)")  # fmt: skip
    parser.add_argument("--rounds", type=int, default=10)
    parser.add_argument("--out", type=Path, default=HERE / "results" / "startup.json")
    args = parser.parse_args()
    trees = {"after": args.after_tree.resolve(), "before": args.before_tree.resolve()}
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        log = make_log(folder)
        cmds = commands(log, folder / "RESULT.json")
        results = {name: measure(trees, argv, args.rounds, folder) for name, argv in cmds.items()}
    data = {
        "about": __doc__.split("\n\n")[2].replace("\n", " "),
        "commands": {
            name: "python -m comgrasp_pin.cli "
            + " ".join(argv).replace(tmp, "TMP").replace(URDF, "PANDA_URDF")
            for name, argv in cmds.items()
        },
        "PANDA_URDF": "example-robot-data's robots/panda_description/urdf/panda.urdf",
        "trees": {name: str(tree) for name, tree in trees.items()},
        "results": results,
        "environment": {
            "python": platform.python_version(),
            "cpus": os.cpu_count(),
            "rounds": args.rounds,
            "date": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()),
            "load_avg_1min": round(os.getloadavg()[0], 2),
        },  # fmt: skip
    }
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(data, indent=2) + "\n")
    for name, r in results.items():
        a, b = r["after"], r["before"]
        print(f"{name}: {a['median_s']:.3f} s (loads {a['loaded'] or 'none'}) against "
              f"{b['median_s']:.3f} s (loads {b['loaded'] or 'none'}): "
              f"x{r['ratio_after_over_before']:.2f}")  # fmt: skip
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
