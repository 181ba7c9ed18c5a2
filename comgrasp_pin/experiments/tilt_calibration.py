"""Measuring the tilt calibration of the accuracy experiment's design (``design``).

Trial grasps in the simulator, per object, side and lever ratio, their TRUE settled tilt
(the design may use the truth: it only chooses where to grasp). Run with
``python -m comgrasp_pin.experiments.tilt_calibration --out sim/tilt_calibration.json``.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from collections.abc import Sequence
from concurrent.futures import as_completed
from contextlib import ExitStack
from pathlib import Path

import numpy as np

from comgrasp_pin._paths import sim_path
from comgrasp_pin.errors import InvalidInputError
from comgrasp_pin.experiments.design import (
    CALIBRATION_FILE,
    CALIBRATION_LEVERS,
    CALIBRATION_SEED_BASE,
    CALIBRATION_SEEDS,
    DENSE_LEVERS,
    GAP_DEG,
    MAX_DEG,
    SIDES,
    grasp_for_lever,
    load_calibration,
    wrap_tilt,
)
from comgrasp_pin.experiments.runner import spawn_pool
from comgrasp_pin.experiments.tilt_curves import (
    MIN_STEP,
    REFINE,
    RISE_DEG,
    curve_entry,
    dense_levers,
    dumps,
    merged,
    monotone,
    step_levers,
)
from comgrasp_pin.planning.holding import holding_lever


def calibration_seed(obj: str, lever: float, seed: int, side: float) -> int:
    """The scene seed of one calibration grasp: its own for every object, lever, seed (< 5)
    and side, and unlike any trial's."""
    if not 0 <= int(seed) < 5:
        raise InvalidInputError(f"calibration seeds are 0-4, got {seed}")
    k = int(seed) + (0 if side > 0 else 5)
    return (CALIBRATION_SEED_BASE + int(obj.removeprefix("obj") or 0) * 100_000
            + int(round(float(lever) * 10_000)) * 10 + k)  # fmt: skip


def tilt_trial(task: dict) -> dict:
    """One calibration grasp: ``task`` has object, lever (ratio), side (+1, -1) and seed (the
    scene's); returns the true settled tilt (deg, wrapped to [-90, 90)), or ``dropped``
    when the rod fell."""
    from comgrasp_pin.errors import ComGraspError
    from comgrasp_pin.experiments import trials
    from comgrasp_pin.simulation.episode import measure_and_score
    from comgrasp_pin.simulation.scene import Scene, World

    obj, lever, seed = task["object"], float(task["lever"]), int(task["seed"])
    config = trials.episode_config(None, "ipopt")
    rng = np.random.default_rng(seed + 17)
    pos_real, offset = grasp_for_lever(obj, lever, rng, config, trials.ACCURACY_COM_RANGE,
                                       trials.ACCURACY_GRASP_OFFSET, task["side"])  # fmt: skip
    world = World(Scene.sample(obj, seed, pos_real=pos_real), config, seed)
    out = {**task, "pos_real_m": pos_real, "offset_m": offset}
    try:
        _, score = measure_and_score(world, offset)
        out.update(tilt_deg=float(np.degrees(wrap_tilt(score.theta_true))), dropped=False,
                   grasp_offset_m=score.grasp_offset)  # fmt: skip
    except ComGraspError as exc:  # dropped, or lost from view: beyond the usable levers
        out.update(tilt_deg=float("nan"), dropped=True, error=f"{type(exc).__name__}: {exc}")
    finally:
        world.close()
    return out


class _Pool:
    """``map`` over spawned worker processes (each with its own MuJoCo and OpenGL context),
    or in this process for one worker. With a ``log`` (a JSON-lines file) every result is
    appended as it comes, and a task already in the log is not run again: an interrupted
    calibration resumes where it stopped."""

    def __init__(self, workers: int, log: Path | None = None):
        self.workers = int(workers)
        self.log = log
        self.done: dict[str, dict] = {}
        if log is not None and log.exists():
            for line in log.read_text().splitlines():
                if line.strip():
                    row = json.loads(line)
                    self.done[_task_key(row)] = row
        self._pool = None

    def __enter__(self) -> _Pool:
        self._stack = ExitStack()
        if self.workers > 1:
            self._pool = self._stack.enter_context(spawn_pool(self.workers))
        return self

    def __exit__(self, *exc) -> None:
        self._stack.close()

    def _record(self, row: dict) -> None:
        self.done[_task_key(row)] = row
        if self.log is not None:
            with self.log.open("a") as f:
                f.write(json.dumps(row) + "\n")

    def map(self, fn, tasks: list[dict]) -> list[dict]:
        todo = [t for t in tasks if _task_key(t) not in self.done]
        if self._pool is None:
            for t in todo:
                self._record(fn(t))
        else:
            for future in as_completed([self._pool.submit(fn, t) for t in todo]):
                self._record(future.result())
        return [self.done[_task_key(t)] for t in tasks]


def _task_key(task: dict) -> str:
    return f"{task['object']}|{float(task['lever']):.5f}|{float(task['side']):+.0f}|{task['seed']}"


def _tasks(obj: str, levers: Sequence[float], seeds: Sequence[int], side: float) -> list[dict]:
    return [{"object": obj, "lever": float(r), "side": float(side),
             "seed": calibration_seed(obj, r, s, side)} for r in levers for s in seeds]  # fmt: skip


def _tilts(rows: list[dict], levers: Sequence[float], n_seeds: int) -> tuple[np.ndarray, ...]:
    """(|tilt| (levers, seeds) deg with 90 for a drop, dropped (levers, seeds))."""
    shape = (len(levers), n_seeds)
    dropped = np.array([r["dropped"] for r in rows], dtype=bool).reshape(shape)
    tilt = np.abs(np.array([r["tilt_deg"] for r in rows], dtype=float)).reshape(shape)
    tilt[dropped] = MAX_DEG
    return tilt, dropped


def measure_tilt_curve(
    obj: str,
    levers: Sequence[float],
    seeds: Sequence[int],
    side: float = 1.0,
    workers: int = 1,
) -> dict:
    """Trial grasps of ``obj``, its true CoM on ``side`` of the centre, at each lever ratio
    and calibration seed (each grasp in its own scene); their TRUE settled tilts. Returns
    {"lever_ratio", "abs_tilt_deg" (levers x seeds; 90 for a drop), "dropped" (levers x
    seeds), "trials" (every grasp's record)}."""
    with _Pool(workers) as pool:
        rows = pool.map(tilt_trial, _tasks(obj, levers, seeds, side))
    tilt, dropped = _tilts(rows, levers, len(seeds))
    return {"lever_ratio": [float(r) for r in levers], "abs_tilt_deg": tilt.tolist(),
            "dropped": dropped.tolist(), "trials": rows}  # fmt: skip


def calibrate(
    objects: Sequence[str],
    out: Path,
    levers: Sequence[float] = CALIBRATION_LEVERS,
    seeds: Sequence[int] = CALIBRATION_SEEDS,
    workers: int = 2,
    dense: int = DENSE_LEVERS,
    refine: int = REFINE,
) -> dict:
    """Measure every object's two curves (its CoM either side of the centre) at the coarse
    ``levers``, then at ``dense`` levers across each curve's rise (``dense_levers``), then
    ``refine`` times inside each step (``step_levers``), with the ideal preset's procedure
    (``trials.episode_config``, the paper's), and write them into the calibration JSON at
    ``out`` (``merged``: other objects there are kept). Grasps are logged beside it as they
    finish (``<out>.partial.jsonl``), so that a stopped run resumes."""
    from comgrasp_pin.experiments import trials

    config = trials.episode_config(None, "ipopt")
    seeds = list(seeds)
    start = time.perf_counter()
    results: dict[tuple, dict[float, tuple]] = {(o, key): {} for o in objects for key in SIDES}
    log = out.with_name(out.stem + ".partial.jsonl")
    out.parent.mkdir(parents=True, exist_ok=True)
    with _Pool(workers, log) as pool:
        _measure(pool, results, [(c, float(r)) for c in results for r in levers], seeds)
        rise = _next_levers(results, lambda rs, tilts: dense_levers(rs, tilts, dense))
        _measure(pool, results, rise, seeds)
        for _ in range(int(refine)):
            _measure(pool, results, _next_levers(results, step_levers), seeds)
    curves = _curves(results, config)
    n_grasps = sum(len(v) for v in results.values()) * len(seeds)
    how = (
        f"coarse levers {list(levers)}, then {dense} levers evenly across each curve's rise "
        f"(from the last coarse lever below {RISE_DEG[0]} deg to the first above {RISE_DEG[1]} "
        f"deg), then {refine} rounds of bisecting each step (a rise of more than {GAP_DEG} deg, "
        f"down to {MIN_STEP:g}); {len(seeds)} grasps per lever and side; {n_grasps} grasps in all"
    )
    made = _provenance(objects, out, how, config, workers, round(time.perf_counter() - start, 1))
    data = merged(json.loads(out.read_text()) if out.exists() else {}, curves, made)
    out.write_text(dumps(data) + "\n")
    log.unlink(missing_ok=True)
    load_calibration.cache_clear()
    return data


def _measure(pool: _Pool, results: dict, todo: list[tuple], seeds: list[int]) -> None:
    """Grasp every (curve, lever) of ``todo`` once per seed; put each lever's |tilts| and
    drops into ``results[curve][lever]``."""
    tasks = [t for (o, key), r in todo for t in _tasks(o, [r], seeds, SIDES[key])]
    rows = pool.map(tilt_trial, tasks)
    for k, (c, r) in enumerate(todo):
        tilt, dropped = _tilts(rows[k * len(seeds) : (k + 1) * len(seeds)], [r], len(seeds))
        results[c][r] = (tilt[0], dropped[0])


def _next_levers(results: dict, choose) -> list[tuple]:
    """The (curve, lever) pairs to measure next: per curve of ``results``, what
    ``choose(levers, tilts)`` picks from its measured levers and monotone median tilts (per
    lever, not pooled: pooling smears a step out), less the levers measured already."""
    todo = []
    for c, by_lever in results.items():
        rs = sorted(by_lever)
        curve = monotone([np.median(by_lever[r][0]) for r in rs])
        todo += [(c, r) for r in choose(rs, curve) if r not in by_lever]
    return todo


def _provenance(objects, out: Path, how: str, config, workers: int, wall_s: float) -> dict:
    """How the curves were made, kept beside them in the calibration JSON."""
    from comgrasp_pin.experiments import trials

    return {
        "sensors": "ideal",
        "objects": list(objects),
        "utc": time.strftime("%Y-%m-%d %H:%M", time.gmtime()),
        "command": (
            f"python -m comgrasp_pin.experiments.tilt_calibration --objects "
            f"{','.join(objects)} --out {out}"
        ),  # fmt: skip
        "how": how,
        "scene_seeds": "tilt_calibration.calibration_seed(object, lever, seed, side)",
        "config": "trials.episode_config(None, 'ipopt'): the ideal preset's procedure",
        "grip_force_N": config.motion.grip_force,
        "pad_friction": list(config.world.pad_friction),
        "com_range": list(trials.ACCURACY_COM_RANGE),
        "grasp_limit": trials.ACCURACY_GRASP_OFFSET,
        "workers": workers,
        "wall_s": wall_s,
    }


def _curves(results: dict[tuple, dict[float, tuple]], config) -> dict[str, dict]:
    """Per object its holding lever and each side's curve (``curve_entry``), from the grasps'
    ``results[(object, side key)][lever] = (|tilts|, dropped)``."""
    from comgrasp_pin.simulation.objects import get_object

    curves: dict[str, dict] = {}
    for (o, key), by_lever in results.items():
        lever = holding_lever(get_object(o).mass, config.motion.grip_force,
                              config.world.pad_friction)  # fmt: skip
        entry = curves.setdefault(o, {"holding_lever_m": round(lever, 6)})
        rs = sorted(by_lever)
        entry[key] = curve_entry(rs, [by_lever[r][0] for r in rs], [by_lever[r][1] for r in rs])
    return curves


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m comgrasp_pin.experiments.tilt_calibration``: measure and write it."""
    from comgrasp_pin.simulation.objects import OBJECTS

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default=str(sim_path("scene.xml").parent / CALIBRATION_FILE))
    parser.add_argument("--objects", default=",".join(OBJECTS))
    parser.add_argument("--levers", default=",".join(map(str, CALIBRATION_LEVERS)))
    parser.add_argument("--seeds", type=int, default=len(CALIBRATION_SEEDS))
    parser.add_argument("--dense", type=int, default=DENSE_LEVERS)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--refine", type=int, default=REFINE, help="rounds of bisecting steps")
    args = parser.parse_args(argv)
    objects = [o.strip() for o in args.objects.split(",") if o.strip()]
    levers = [float(v) for v in args.levers.split(",")]
    data = calibrate(objects, Path(args.out), levers, range(args.seeds), args.workers,
                     args.dense, args.refine)  # fmt: skip
    for obj, entry in data["objects"].items():
        for key in SIDES:
            c = entry[key]
            pairs = " ".join(f"{r:g}:{t:.1f}" for r, t in zip(c["lever_ratio"], c["tilt_deg"]))
            print(f"{obj} {key}: {pairs}")
    print(f"written to {args.out} in {data['runs'][-1]['wall_s']} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
