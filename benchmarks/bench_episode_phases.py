"""Where an episode's time goes, phase by phase: mj_step, renders, perception, Python per step.

    python benchmarks/bench_episode_phases.py [--objects obj1,obj2] [--trials 1]
                                              [--out benchmarks/results/episode_phases.json]

Runs real accuracy trials (``accuracy_trial``) and pick-and-place episodes (``regrasp_trial``,
method regrasp) in this process with timers wrapped around the functions each phase runs in;
each phase's time is exclusive (a render inside the slip watch counts as a render, not as the
watch). Phases:

- ``mj_step``: MuJoCo's physics step (C).
- ``step_python``: the Python of ``Simulation.step``/``track`` (their ``_advance``) and
  ``measure_torques`` around it: servo, torque sensor, observer dispatch, instability check
  (per step: ``per_step_us``).
- ``render``: offscreen renders (depth for perception, RGB/segmentation where asked).
- ``perception_top``, ``perception_side``: the top view and the side view (OpenCV + NumPy) on
  the rendered images.
- ``slip_watch_python``: the side camera's watch around its renders and perception
  (kinematics, arm capsules, slip monitor).
- ``estimation``: ``estimate_com`` (IPOPT or the closed form), the uncertainty propagation's
  re-estimates, the next-pose planner.
- ``ik``: inverse kinematics of the skills and procedures.
- ``world_build``: compiling the MJCF world, the robot model, the renderer (not the settling
  steps, nor the MjData).
- ``other``: the rest (trajectories, procedures, scoring).

Wrapping a function costs about a microsecond per call (``timer_overhead_us``, measured);
``mj_step`` is called every 2 ms of simulated time, so its share is inflated by that much.
"""

from __future__ import annotations

import os

os.environ.setdefault("MUJOCO_GL", "egl")

import argparse  # noqa: E402
import json  # noqa: E402
import time  # noqa: E402
from collections import Counter, defaultdict  # noqa: E402
from pathlib import Path  # noqa: E402

import mujoco  # noqa: E402

from comgrasp_pin.experiments.trials import accuracy_trial, make_tasks, regrasp_trial  # noqa: E402
from comgrasp_pin.procedures import com_location, pick_and_place, trial_plan  # noqa: E402
from comgrasp_pin.simulation import eyes, scene, skills  # noqa: E402
from comgrasp_pin.simulation import sim as sim_module  # noqa: E402
from comgrasp_pin.simulation.cameras import CameraRig  # noqa: E402

PHASES = {
    "mj_step": [(mujoco, "mj_step")],
    "step_python": [(sim_module.Simulation, "_advance"), (sim_module.Simulation, "measure_torques")],
    "render": [(CameraRig, "_render")],
    "perception_top": [(eyes, "detect_rod_top_down")],
    "perception_side": [(eyes, "observe_held_rod")],
    "slip_watch_python": [(eyes.SlipWatcher, "__call__")],
    "estimation": [(com_location, "estimate_com"), (trial_plan, "best_next_pose")],
    "ik": [(skills, "solve_ik"), (skills, "solve_top_down"), (pick_and_place, "solve_ik"),
           (trial_plan, "solve_ik"), (trial_plan, "solve_top_down")],
    "world_build": [(scene, "build_model"), (scene.RobotModel, "ur5"), (CameraRig, "__init__")],
}  # fmt: skip


class Profile:
    """Exclusive wall time and call count per label of the wrapped functions."""

    def __init__(self) -> None:
        self.seconds: dict[str, float] = defaultdict(float)
        self.calls: Counter = Counter()
        self._children: list[float] = []

    def wrap(self, label: str, fn):
        def timed(*args, **kwargs):
            start = time.perf_counter()
            self._children.append(0.0)
            try:
                return fn(*args, **kwargs)
            finally:
                elapsed = time.perf_counter() - start
                self.seconds[label] += elapsed - self._children.pop()
                self.calls[label] += 1
                if self._children:
                    self._children[-1] += elapsed

        return timed

    def install(self) -> None:
        for label, targets in PHASES.items():
            for owner, name in targets:
                setattr(owner, name, self.wrap(label, getattr(owner, name)))

    def reset(self) -> None:
        self.seconds.clear()
        self.calls.clear()


def _overhead_us(profile: Profile, n: int = 200_000) -> float:
    noop = profile.wrap("_noop", lambda: None)
    start = time.perf_counter()
    for _ in range(n):
        noop()
    overhead = (time.perf_counter() - start) / n * 1e6
    profile.reset()
    return overhead


def _phases(profile: Profile, total: float, sim_s: float) -> dict:
    seconds = {label: profile.seconds.get(label, 0.0) for label in PHASES}
    seconds["other"] = total - sum(seconds.values())
    steps = profile.calls["mj_step"]
    return {
        "wall_s": total,
        "sim_s": sim_s,
        "seconds": seconds,
        "share": {k: v / total for k, v in seconds.items()},
        "calls": {label: profile.calls.get(label, 0) for label in PHASES},
        "per_call_ms": {
            label: 1e3 * seconds[label] / profile.calls[label]
            for label in PHASES
            if profile.calls.get(label)
        },  # fmt: skip
        "per_step_us": {
            "mj_step": 1e6 * seconds["mj_step"] / max(steps, 1),
            "step_python": 1e6 * seconds["step_python"] / max(steps, 1),
        },  # fmt: skip
    }


def _episode(profile: Profile, fn, task: dict) -> dict:
    profile.reset()
    start = time.perf_counter()
    row = fn(task)
    total = time.perf_counter() - start
    return {"task": {k: task[k] for k in ("object", "trial", "method", "seed")},
            **_phases(profile, total, float(row["sim_s"]))}  # fmt: skip


def _mean(episodes: list[dict]) -> dict:
    labels = episodes[0]["seconds"]
    total = sum(e["wall_s"] for e in episodes)
    return {
        "episodes": len(episodes),
        "wall_s": total / len(episodes),
        "sim_s": sum(e["sim_s"] for e in episodes) / len(episodes),
        "share": {k: sum(e["seconds"][k] for e in episodes) / total for k in labels},
        "seconds": {k: sum(e["seconds"][k] for e in episodes) / len(episodes) for k in labels},
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--objects", default="obj1,obj2")
    parser.add_argument("--trials", type=int, default=1)
    parser.add_argument("--sensors", default="ideal", help="sensor preset (config.sensors)")
    parser.add_argument("--out", default=str(Path(__file__).parent / "results" /
                                             "episode_phases.json"))  # fmt: skip
    args = parser.parse_args()
    objects = args.objects.split(",")
    profile = Profile()
    overhead = _overhead_us(profile)
    profile.install()
    accuracy_trial(make_tasks(objects[:1], 1, 99, ("trial",))[0])  # warm-up: imports, renderer

    def tasks(method: str) -> list[dict]:
        return [{**t, "sensors": args.sensors}
                for t in make_tasks(objects, args.trials, 0, (method,))]  # fmt: skip

    accuracy = [_episode(profile, accuracy_trial, t) for t in tasks("trial")]
    regrasp = [_episode(profile, regrasp_trial, t) for t in tasks("regrasp")]
    result = {
        "accuracy_trial": _mean(accuracy),
        "regrasp_episode": _mean(regrasp),
        "episodes": {"accuracy": accuracy, "regrasp": regrasp},
        "sensors": args.sensors,
        "timer_overhead_us": overhead,
        "environment": {"cpus": os.cpu_count(), "load_avg_1min": os.getloadavg()[0],
                        "mujoco": mujoco.__version__,
                        "date": time.strftime("%Y-%m-%d %H:%M:%S UTC", time.gmtime())},
    }  # fmt: skip
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    Path(args.out).write_text(json.dumps(result, indent=2) + "\n")
    for name in ("accuracy_trial", "regrasp_episode"):
        r = result[name]
        shares = ", ".join(f"{k} {100 * v:.0f} %" for k, v in r["share"].items())
        print(f"{name}: {r['wall_s']:.2f} s wall for {r['sim_s']:.1f} s simulated: {shares}")
    print(f"written to {args.out}")


if __name__ == "__main__":
    main()
