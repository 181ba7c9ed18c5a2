"""The accuracy experiment's design: grasps placed for target tilts.

A rod grasped a lever e from its CoM turns in the jaws once its weight's moment m g e
exceeds what the jaws hold (``planning.holding``); it settles where m g e cos(theta) meets
that moment, give or take the lift's dynamics. Random grasps therefore either hold level or
turn far, and the paper's 0-30 deg range stays nearly empty. The design instead

1. measures, once per object and side of its centre the CoM lies on, the TRUE settled
   tilt against the lever ratio r = e / (the nominal holding lever) in trial grasps
   (``measure_tilt_curve``; ``calibrate`` writes the curves of the median tilt, pooled
   over neighbouring levers and made monotone, to ``sim/tilt_calibration.json``). The side
   matters: the same lever turns a rod 3-6 deg further one way than the other (measured;
   a CoM below or above the axis and a bias of the perceived centre would both do it), and
   so does the scene (a few deg), so every calibration grasp has its own scene,
2. gives each trial a target tilt, stratified over 5 deg bins (``target_tilt``): of every 7
   consecutive trials one targets each bin of 0-30 deg and one 30-90 deg, so at the paper's
   50 trials per object each bin below 30 deg holds at least 7 targets,
3. picks the side whose curve reaches the target best (``side_and_lever``; at random when
   both do), inverts that side's curve to a lever ratio (``lever_for_tilt``) and places the
   grasp that lever from the true CoM on the centre's side (``grasp_for_lever``).

The truth only chooses where to grasp; the robot never sees it. Calibrate with
``python -m comgrasp_pin.experiments.design --out sim/tilt_calibration.json``.
"""

from __future__ import annotations

import argparse
import json
import multiprocessing
import os
import sys
import time
from collections.abc import Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from functools import cache
from pathlib import Path

import numpy as np

from comgrasp_pin._paths import sim_path
from comgrasp_pin.errors import InvalidInputError, MissingAssetError
from comgrasp_pin.planning.holding import holding_lever

CALIBRATION_FILE = "tilt_calibration.json"
CALIBRATION_ENV = "COMGRASP_TILT_CALIBRATION"
BIN_DEG = 5.0  # width of a tilt bin (deg)
LOW_DEG = 30.0  # the paper's range, 0-30 deg, split into bins of BIN_DEG
MAX_DEG = 90.0  # the rest of the targets lie in LOW_DEG-MAX_DEG
LOW_BINS = int(round(LOW_DEG / BIN_DEG))  # 6
STRATA = LOW_BINS + 1  # the six low bins and 30-90 deg, in turn
BIN_CORE = 0.7  # targets fill the middle 70 % of their bin (achieved tilts scatter 2-4 deg)
# The calibration: coarse lever ratios (e / holding lever) find where each curve rises (the
# rods start to turn at 0.45-0.8 and settle at 50-77 deg beyond 0.9), then DENSE_LEVERS
# evenly spaced levers cover that rise, from the last coarse lever below RISE_DEG[0] to
# the first above RISE_DEG[1]; every lever has one grasp per seed and side, each in its own
# scene, and the curve is the median over the grasps within POOL_WIDTH of each lever.
CALIBRATION_LEVERS = (0.35, 0.45, 0.55, 0.65, 0.75, 0.85, 1.0)
CALIBRATION_SEEDS = (0, 1)
DENSE_LEVERS = 10
RISE_DEG = (1.0, 32.0)
SIDES = {"+x": 1.0, "-x": -1.0}  # the CoM on the heavy end's half of the rod, or the other
GAP_DEG = 20.0  # a rise this steep between calibrated neighbours is a step (no tilts inside)
# The lever error of a grasp (its share of the holding lever): perception and the scene
# put the achieved tilt where the curve is 0.01-0.02 further on or back (measured).
LEVER_SCATTER = 0.015
POOL_WIDTH = LEVER_SCATTER + 1e-6  # grasps this close in lever pool into one median
SIDE_TIE_DEG = 2.0  # sides scoring within this (deg) of each other are drawn at random
CALIBRATION_SEED_BASE = 7_000_000  # far from the experiments' trial seeds
_GOLDEN = 0.5 * (np.sqrt(5.0) - 1.0)


def wrap_tilt(theta: float) -> float:
    """A tilt (rad) wrapped to [-pi/2, pi/2): a rod's axis has no direction, so a tilt is
    defined modulo pi."""
    return float((theta + 0.5 * np.pi) % np.pi - 0.5 * np.pi)


# --- where to grasp ----------------------------------------------------------------------


def grasp_for_lever(
    obj: str,
    lever_ratio: float,
    rng: np.random.Generator,
    config,
    com_range: tuple[float, float],
    grasp_limit: float,
    side: float | None = None,
) -> tuple[float, float]:
    """(true CoM, grasp offset) along the rod from its centre (m), the grasp ``lever_ratio``
    holding levers from the CoM on the centre's side.

    The true CoM lies on ``side`` (+1: towards +x, the heavy end; -1; None: drawn) of the
    centre, its distance uniform within ``com_range`` (fractions of the length) but no
    farther than the grasp can follow: the grasp stays within ``grasp_limit`` (a fraction of
    the length) of the centre, on the handle, at the requested lever (it is clipped there
    only against rounding).
    """
    from comgrasp_pin.simulation.objects import get_object

    spec = get_object(obj)
    lever = lever_ratio * holding_lever(
        spec.mass, config.motion.grip_force, config.world.pad_friction
    )
    limit = grasp_limit * spec.length
    lo, hi = com_range[0] * spec.length, com_range[1] * spec.length
    sign = float(rng.choice([-1.0, 1.0]) if side is None else np.sign(side))
    pos_real = sign * rng.uniform(lo, max(lo, min(hi, limit + lever)))
    offset = pos_real - sign * lever  # towards the centre, and past it for a long lever
    return float(pos_real), float(np.clip(offset, -limit, limit))


# --- target tilts ------------------------------------------------------------------------


def target_tilt(trial: int, run_seed: int = 0) -> float:
    """Target tilt (deg, in [0, 90)) of trial ``trial`` of a run with seed ``run_seed``.

    Trials take the strata in turn: bin b = trial % 7 targets the middle 70 % of
    [5 b, 5 b + 5) deg for b < 6 (achieved tilts scatter by a few degrees), and bin 6
    targets [30, 90) deg; within its stratum the j-th visit (j = trial // 7) sits at the
    golden-ratio sequence's j-th point from a start drawn from the run seed, so targets
    spread evenly over it (uniform in the limit). It depends on the trial
    index and run seed only: the same trial gets the same target in every run, with any
    number of trials, on every object, and under ``--resume``.
    """
    if trial < 0:
        raise InvalidInputError(f"trial must be >= 0, got {trial}")
    stratum, visit = trial % STRATA, trial // STRATA
    start = np.random.default_rng([int(run_seed), stratum, 11]).random()
    u = (start + visit * _GOLDEN) % 1.0
    if stratum < LOW_BINS:  # the middle of the bin: a tilt that scatters stays in it
        return float(BIN_DEG * (stratum + 0.5 + BIN_CORE * (u - 0.5)))
    return float(LOW_DEG + (MAX_DEG - LOW_DEG) * u)


def target_tilts(n_trials: int, run_seed: int = 0) -> np.ndarray:
    """(n_trials,) ``target_tilt`` of trials 0 .. n_trials - 1 (deg)."""
    return np.array([target_tilt(k, run_seed) for k in range(n_trials)])


# --- the calibrated curves ---------------------------------------------------------------


def monotone(y: Sequence[float]) -> np.ndarray:
    """The non-decreasing sequence nearest ``y`` in least squares (pool adjacent
    violators): the calibration's medians made monotone."""
    blocks: list[list[float]] = []  # [mean, count]
    for v in map(float, y):
        blocks.append([v, 1.0])
        while len(blocks) > 1 and blocks[-2][0] > blocks[-1][0]:
            (m1, n1), (m2, n2) = blocks.pop(-2), blocks.pop()
            blocks.append([(m1 * n1 + m2 * n2) / (n1 + n2), n1 + n2])
    return np.concatenate([np.full(int(n), m) for m, n in blocks])


def invert_curve(
    levers: Sequence[float], tilts: Sequence[float], tilt: float, gap_deg: float = GAP_DEG
) -> float:
    """The lever ratio at which the monotone curve (``levers`` increasing, ``tilts``
    non-decreasing, deg) first reaches ``tilt`` (deg), linear between calibrated points.

    A rise of more than ``gap_deg`` between neighbouring points is a step: the rod either
    stays below it or swings past it, so a target inside it gets the nearer end's lever.
    Targets beyond the curve's ends get its end levers; on a flat stretch the first point.
    """
    r, t = np.asarray(levers, dtype=float), np.asarray(tilts, dtype=float)
    if r.ndim != 1 or r.shape != t.shape or r.size < 2:
        raise InvalidInputError(f"levers and tilts must be two equal 1-D sequences of >= 2 "
                                f"points, got shapes {r.shape}, {t.shape}")  # fmt: skip
    if np.any(np.diff(r) <= 0) or np.any(np.diff(t) < 0):
        raise InvalidInputError("levers must increase and tilts must not decrease")
    if tilt <= t[0]:
        return float(r[0])
    if tilt >= t[-1]:
        return float(r[np.argmax(t >= t[-1])])
    i = int(np.searchsorted(t, tilt, side="left"))  # t[i - 1] < tilt <= t[i]
    if t[i] - t[i - 1] > gap_deg:
        return float(r[i - 1] if tilt - t[i - 1] < t[i] - tilt else r[i])
    return float(r[i - 1] + (r[i] - r[i - 1]) * (tilt - t[i - 1]) / (t[i] - t[i - 1]))


@cache
def load_calibration(path: str | None = None) -> dict:
    """The calibration: ``path``, else the file named by the environment variable
    COMGRASP_TILT_CALIBRATION (to try a new one; worker processes inherit it), else
    ``sim/tilt_calibration.json``."""
    path = path or os.environ.get(CALIBRATION_ENV) or None
    file = Path(path) if path is not None else sim_path(CALIBRATION_FILE)
    if not file.exists():
        raise MissingAssetError(f"no tilt calibration at {file}; run python -m "
                                "comgrasp_pin.experiments.design --out " + str(file))  # fmt: skip
    return json.loads(file.read_text())


def side_key(side: float) -> str:
    """The calibration's key for the CoM's side of the centre: "+x" or "-x"."""
    if side not in (1, -1):
        raise InvalidInputError(f"side must be +1 or -1, got {side}")
    return "+x" if side > 0 else "-x"


def tilt_curve(
    obj: str, side: float = 1.0, path: str | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """(levers, tilts_deg): the calibrated monotone curve of ``obj`` with its CoM on
    ``side`` (+1 or -1) of the centre."""
    objects = load_calibration(path)["objects"]
    if obj not in objects:
        raise InvalidInputError(f"{obj!r} is not calibrated; calibrated are {sorted(objects)}")
    curve = objects[obj][side_key(side)]
    return np.array(curve["lever_ratio"]), np.array(curve["tilt_deg"])


def lever_for_tilt(obj: str, tilt_deg: float, side: float = 1.0, path: str | None = None) -> float:
    """The lever ratio (e / holding lever) at which ``obj``, its CoM on ``side`` of the
    centre, settles at ``tilt_deg``."""
    return invert_curve(*tilt_curve(obj, side, path), tilt_deg)


def curve_at(levers: Sequence[float], tilts: Sequence[float], lever: float) -> float:
    """The monotone curve's tilt (deg) at ``lever``, linear between calibrated points."""
    return float(np.interp(lever, levers, tilts))


def side_and_lever(obj: str, tilt_deg: float, u: float, path: str | None = None) -> tuple:
    """(side, lever ratio) for a grasp of ``obj`` aimed at ``tilt_deg``: the side of the
    centre to put the true CoM on, and that side's lever for the target.

    The two sides' curves differ (one may jump where the other climbs steadily), so the
    side whose curve lands nearest the target and least steeply there is taken: its score
    is the miss |curve(r) - target| plus half the curve's rise over r +- LEVER_SCATTER (how
    far a grasp's usual lever error moves the tilt). Sides that score within SIDE_TIE_DEG
    of each other are chosen between by ``u`` (uniform in [0, 1)), half and half.
    """
    scores, levers = {}, {}
    for key, side in SIDES.items():
        r, t = tilt_curve(obj, side, path)
        lever = invert_curve(r, t, tilt_deg)
        rise = curve_at(r, t, lever + LEVER_SCATTER) - curve_at(r, t, lever - LEVER_SCATTER)
        scores[key] = abs(curve_at(r, t, lever) - tilt_deg) + 0.5 * rise
        levers[key] = lever
    if abs(scores["+x"] - scores["-x"]) <= SIDE_TIE_DEG:
        key = "+x" if u < 0.5 else "-x"
    else:
        key = min(scores, key=scores.get)
    return SIDES[key], levers[key]


# --- measuring the curves ----------------------------------------------------------------


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
    config = trials.episode_config()
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
        if self.workers > 1:
            context = multiprocessing.get_context("spawn")
            self._pool = ProcessPoolExecutor(max_workers=self.workers, mp_context=context)
        return self

    def __exit__(self, *exc) -> None:
        if self._pool is not None:
            self._pool.shutdown(cancel_futures=True)

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


def dense_levers(levers: Sequence[float], tilts: Sequence[float], n: int) -> list[float]:
    """``n`` lever ratios evenly inside the rise of the (sorted, monotone) coarse curve:
    from its last lever below RISE_DEG[0] to its first above RISE_DEG[1]."""
    r, t = np.asarray(levers, dtype=float), np.asarray(tilts, dtype=float)
    below, above = np.flatnonzero(t < RISE_DEG[0]), np.flatnonzero(t > RISE_DEG[1])
    lo = r[below[-1]] if below.size else r[0]
    hi = r[above[0]] if above.size else r[-1]
    return [round(float(v), 5) for v in np.linspace(lo, hi, n + 2)[1:-1]]


def pooled_median(levers: Sequence[float], tilts: Sequence[Sequence[float]]) -> np.ndarray:
    """Per lever (sorted), the median |tilt| of every grasp at a lever within POOL_WIDTH of
    it: the tilt a grasp aimed there lands at, its usual lever error included."""
    r = np.asarray(levers, dtype=float)
    return np.array([np.median(np.concatenate([np.ravel(tilts[j]) for j in
                     np.flatnonzero(np.abs(r - x) <= POOL_WIDTH)])) for x in r])  # fmt: skip


def curve_entry(levers: Sequence[float], tilt: Sequence, dropped: Sequence) -> dict:
    """One calibration curve: per lever ratio (sorted) the |tilt| of each grasp, their
    median, the median pooled over neighbouring levers (``pooled_median``) and that made
    monotone (``tilt_deg``, the curve the design inverts)."""
    order = np.argsort(levers)
    r = [float(levers[i]) for i in order]
    tilt = [list(map(float, tilt[i])) for i in order]
    pooled = pooled_median(r, tilt)
    return {
        "lever_ratio": r,
        "tilt_deg": [round(float(v), 3) for v in monotone(pooled)],
        "pooled_median_deg": [round(float(v), 3) for v in pooled],
        "median_abs_tilt_deg": [round(float(np.median(v)), 3) for v in tilt],
        "abs_tilt_deg": [[round(v, 3) for v in row] for row in tilt],
        "dropped": [[bool(v) for v in dropped[i]] for i in order],
    }


def calibrate(
    objects: Sequence[str],
    out: Path,
    levers: Sequence[float] = CALIBRATION_LEVERS,
    seeds: Sequence[int] = CALIBRATION_SEEDS,
    workers: int = 2,
    dense: int = DENSE_LEVERS,
) -> dict:
    """Measure every object's two curves (its CoM either side of the centre) at the coarse
    ``levers``, then at ``dense`` levers across each curve's rise (``dense_levers``), and
    write the calibration JSON to ``out``. Grasps are logged beside it as they finish
    (``<out>.partial.jsonl``), so that a run that was stopped resumes."""
    from comgrasp_pin.experiments import trials
    from comgrasp_pin.simulation.objects import get_object

    config = trials.episode_config()
    seeds = list(seeds)
    start = time.perf_counter()
    curves_of = [(o, key) for o in objects for key in SIDES]
    results: dict[tuple, dict[float, tuple]] = {c: {} for c in curves_of}

    def measure(pool: _Pool, todo: list[tuple]) -> None:
        tasks = [t for (o, key), r in todo for t in _tasks(o, [r], seeds, SIDES[key])]
        rows = pool.map(tilt_trial, tasks)
        for k, (c, r) in enumerate(todo):
            tilt, dropped = _tilts(rows[k * len(seeds) : (k + 1) * len(seeds)], [r], len(seeds))
            results[c][r] = (tilt[0], dropped[0])

    log = out.with_name(out.stem + ".partial.jsonl")
    out.parent.mkdir(parents=True, exist_ok=True)
    with _Pool(workers, log) as pool:
        measure(pool, [(c, float(r)) for c in curves_of for r in levers])
        todo = []
        for c in curves_of:
            rs = sorted(results[c])
            coarse = monotone([np.median(results[c][r][0]) for r in rs])
            todo += [(c, r) for r in dense_levers(rs, coarse, dense) if r not in results[c]]
        measure(pool, todo)
    curves: dict[str, dict] = {}
    for o, key in curves_of:
        spec = get_object(o)
        entry = curves.setdefault(o, {"holding_lever_m": round(holding_lever(
            spec.mass, config.motion.grip_force, config.world.pad_friction), 6)})  # fmt: skip
        rs = sorted(results[(o, key)])
        entry[key] = curve_entry(rs, [results[(o, key)][r][0] for r in rs],
                                 [results[(o, key)][r][1] for r in rs])  # fmt: skip
    n_grasps = sum(len(v) for v in results.values()) * len(seeds)
    data = {
        "about": (
            "Tilt calibration of the accuracy experiment (comgrasp_pin.experiments.design). "
            "Per object and side of the centre its true CoM lies on (+x: the heavy end's "
            "half, -x: the other) and per lever ratio (grasp-to-CoM distance over the "
            "nominal holding lever holding_lever_m): abs_tilt_deg, the TRUE tilt (deg, from "
            "the simulator, wrapped to [-90, 90) and made absolute) at which the rod "
            "settled in the jaws, one trial grasp per calibration seed, each in its own "
            "scene (90 = it dropped); median_abs_tilt_deg their median; pooled_median_deg "
            f"the median over the grasps within {LEVER_SCATTER} of the lever; tilt_deg that "
            "made monotone (pool adjacent violators), the curve the design inverts."
        ),
        "made": {
            "command": f"python -m comgrasp_pin.experiments.design --out {out}",
            "how": (
                f"coarse levers {list(levers)}, then {dense} levers evenly across each "
                f"curve's rise (from the last coarse lever below {RISE_DEG[0]} deg to the "
                f"first above {RISE_DEG[1]} deg); {len(seeds)} grasps per lever and side; "
                f"{n_grasps} grasps in all"
            ),
            "scene_seeds": "design.calibration_seed(object, lever, seed, side)",
            "config": "trials.episode_config() (the defaults; torque noise 0.05 N m)",
            "grip_force_N": config.motion.grip_force,
            "pad_friction": list(config.world.pad_friction),
            "com_range": list(trials.ACCURACY_COM_RANGE),
            "grasp_limit": trials.ACCURACY_GRASP_OFFSET,
            "workers": workers,
            "wall_s": round(time.perf_counter() - start, 1),
        },
        "objects": curves,
    }
    out.write_text(_dumps(data) + "\n")
    log.unlink(missing_ok=True)
    load_calibration.cache_clear()
    return data


def _dumps(data, indent: int = 0) -> str:
    """JSON with every list of numbers (or of such lists) on one line."""
    pad = " " * (indent + 1)
    if isinstance(data, dict) and data:
        items = (f"{pad}{json.dumps(k)}: {_dumps(v, indent + 1)}" for k, v in data.items())
        return "{\n" + ",\n".join(items) + "\n" + " " * indent + "}"
    if isinstance(data, list) and any(isinstance(v, dict) for v in data):
        return "[\n" + ",\n".join(pad + _dumps(v, indent + 1) for v in data) + "\n]"
    return json.dumps(data)


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m comgrasp_pin.experiments.design``: measure and write the calibration."""
    from comgrasp_pin.simulation.objects import OBJECTS

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default=str(sim_path("scene.xml").parent / CALIBRATION_FILE))
    parser.add_argument("--objects", default=",".join(OBJECTS))
    parser.add_argument("--levers", default=",".join(map(str, CALIBRATION_LEVERS)))
    parser.add_argument("--seeds", type=int, default=len(CALIBRATION_SEEDS))
    parser.add_argument("--dense", type=int, default=DENSE_LEVERS)
    parser.add_argument("--workers", type=int, default=2)
    args = parser.parse_args(argv)
    objects = [o.strip() for o in args.objects.split(",") if o.strip()]
    levers = [float(v) for v in args.levers.split(",")]
    data = calibrate(objects, Path(args.out), levers, range(args.seeds), args.workers,
                     args.dense)  # fmt: skip
    for obj, entry in data["objects"].items():
        for key in SIDES:
            c = entry[key]
            pairs = " ".join(f"{r:g}:{t:.1f}" for r, t in zip(c["lever_ratio"], c["tilt_deg"]))
            print(f"{obj} {key}: {pairs}")
    print(f"written to {args.out} in {data['made']['wall_s']} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
