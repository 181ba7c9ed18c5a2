"""What a physics step costs, and what moving the servo into MuJoCo could save at most.

    python benchmarks/bench_step.py [--steps 5000] [--out benchmarks/results/step.json]

One world (ideal sensors, obj2 on the table, the arm at rest above it), three ways to
advance it by the same number of 2 ms steps:

- ``simulation_step_us``: ``Simulation.step``, as every trial runs: the Python servo
  (integral and gravity feed-forward), the torque sensor's sample and the observers' dispatch
  around each ``mj_step``;
- ``mj_step_loop_us``: ``mujoco.mj_step`` alone in a Python loop, the controls held (what is
  left with the servo and sensor in MuJoCo: an upper bound on that lever's gain);
- ``mj_step_nstep_us``: one ``mujoco.mj_step(m, d, nstep)`` call (several steps per call).

Per step, median of 5 blocks; ``ratios`` compares them. The physics of the two bare variants
is not the trials' (no servo): they bound what the lever could buy, they are not a result.
``mj_step_stages_us``: where ``mj_step`` itself spends its time (MuJoCo's own timers, mean
per step over the ``Simulation.step`` blocks): collision, constraint making and projection,
the solver; nested stages are inside their parents (FORWARD inside STEP, COL_* inside
POS_COLLISION inside POSITION).
"""

from __future__ import annotations

import os

os.environ.setdefault("MUJOCO_GL", "egl")

import argparse  # noqa: E402
import json  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import mujoco  # noqa: E402
import numpy as np  # noqa: E402

from comgrasp_pin.experiments.trials import episode_config  # noqa: E402
from comgrasp_pin.simulation.scene import Scene, World  # noqa: E402


def _per_step_us(advance, steps: int, blocks: int = 5) -> float:
    times = []
    for _ in range(blocks):
        start = time.perf_counter()
        advance(steps)
        times.append((time.perf_counter() - start) / steps * 1e6)
    return float(np.median(times))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=5000)
    parser.add_argument("--out", default=str(Path(__file__).parent / "results" / "step.json"))
    args = parser.parse_args()
    world = World(Scene.sample("obj2", 3), episode_config(sensors="ideal"), 3)
    sim = world.sim
    m, d = sim.model, sim.data
    sim.step(500)  # settle

    def bare_loop(n: int) -> None:
        for _ in range(n):
            mujoco.mj_step(m, d)

    def nstep(n: int) -> None:
        mujoco.mj_step(m, d, nstep=n)

    stages = [n for n in dir(mujoco.mjtTimer) if n.startswith("mjTIMER_")]
    before = {n: (d.timer[getattr(mujoco.mjtTimer, n)].duration,
                  d.timer[getattr(mujoco.mjtTimer, n)].number) for n in stages}  # fmt: skip
    simulation_step_us = _per_step_us(sim.step, args.steps)
    mj_stages = {}
    for n in stages:
        timer = d.timer[getattr(mujoco.mjtTimer, n)]
        calls = timer.number - before[n][1]
        if calls:
            mj_stages[n.removeprefix("mjTIMER_").lower()] = (
                1e6 * (timer.duration - before[n][0]) / calls
            )
    result = {
        "simulation_step_us": simulation_step_us,
        "mj_step_loop_us": _per_step_us(bare_loop, args.steps),
        "mj_step_nstep_us": _per_step_us(nstep, args.steps),
        "mj_step_stages_us": mj_stages,
        "steps": args.steps,
        "timestep_s": float(m.opt.timestep),
        "model": {"nv": int(m.nv), "ngeom": int(m.ngeom), "noslip_iterations":
                  int(m.opt.noslip_iterations), "iterations": int(m.opt.iterations)},
    }  # fmt: skip
    world.close()
    r = result
    r["ratios"] = {
        "simulation_over_mj_step_loop": r["simulation_step_us"] / r["mj_step_loop_us"],
        "mj_step_loop_over_nstep": r["mj_step_loop_us"] / r["mj_step_nstep_us"],
        "simulation_over_nstep": r["simulation_step_us"] / r["mj_step_nstep_us"],
    }
    r["realtime_factor_physics_only"] = {
        k: 1e6 * r["timestep_s"] / r[k]
        for k in ("simulation_step_us", "mj_step_loop_us", "mj_step_nstep_us")
    }
    r["environment"] = {"cpus": os.cpu_count(), "load_avg_1min": os.getloadavg()[0],
                        "mujoco": mujoco.__version__,
                        "date": time.strftime("%Y-%m-%d %H:%M:%S UTC", time.gmtime())}  # fmt: skip
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    Path(args.out).write_text(json.dumps(r, indent=2) + "\n")
    print(json.dumps({k: r[k] for k in ("simulation_step_us", "mj_step_loop_us",
                                         "mj_step_nstep_us", "ratios")}, indent=2))  # fmt: skip
    print(f"written to {args.out}")


if __name__ == "__main__":
    main()
