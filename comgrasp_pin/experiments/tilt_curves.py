"""The tilt calibration's curves as measured and as written (``tilt_calibration``): the
levers to measure, the curves made from the grasps' tilts, and the calibration file.

The calibration: coarse lever ratios (e / holding lever) find where each curve rises (the
rods start to turn at 0.45-0.8 and settle at 50-77 deg beyond 0.9), then dense levers
evenly spaced cover that rise, from the last coarse lever below RISE_DEG[0] to the first
above RISE_DEG[1], then each step (a rise of more than ``design.GAP_DEG`` between
neighbours) is bisected; every lever has one grasp per seed and side, each in its own scene,
and the curve is the median over the grasps within POOL_WIDTH of each lever, made monotone.
"""

from __future__ import annotations

import json
from collections.abc import Sequence

import numpy as np

from comgrasp_pin.experiments.design import GAP_DEG, LEVER_SCATTER

RISE_DEG = (1.0, 32.0)
# A step is bisected REFINE times (``step_levers``), down to MIN_STEP (0.1 of a grasp's
# usual lever error): the coarse and dense grids leave 0.01-0.1 wide steps (obj2, obj3 at
# 18-20 -> 56-70 deg), and whether a tilt inside them is stable shows only inside them.
REFINE = 3
MIN_STEP = 0.1 * LEVER_SCATTER
POOL_WIDTH = LEVER_SCATTER + 1e-6  # grasps this close in lever pool into one median


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


def dense_levers(levers: Sequence[float], tilts: Sequence[float], n: int) -> list[float]:
    """``n`` lever ratios evenly inside the rise of the (sorted, monotone) coarse curve:
    from its last lever below RISE_DEG[0] to its first above RISE_DEG[1]."""
    r, t = np.asarray(levers, dtype=float), np.asarray(tilts, dtype=float)
    below, above = np.flatnonzero(t < RISE_DEG[0]), np.flatnonzero(t > RISE_DEG[1])
    lo = r[below[-1]] if below.size else r[0]
    hi = r[above[0]] if above.size else r[-1]
    return [round(float(v), 5) for v in np.linspace(lo, hi, n + 2)[1:-1]]


def step_levers(levers: Sequence[float], tilts: Sequence[float], gap_deg: float = GAP_DEG,
                min_step: float = MIN_STEP) -> list[float]:  # fmt: skip
    """The midpoints of the neighbouring levers (sorted) between which the (monotone) curve
    rises by more than ``gap_deg``, while they lie more than ``min_step`` apart: where a
    step's inside is measured next, to find whether the rod settles anywhere in it."""
    r, t = np.asarray(levers, dtype=float), np.asarray(tilts, dtype=float)
    i = np.flatnonzero((np.diff(t) > gap_deg) & (np.diff(r) > min_step))
    return [round(float(v), 5) for v in 0.5 * (r[i] + r[i + 1])]


def lever_shares(levers: Sequence[float], x: float, width: float = POOL_WIDTH) -> np.ndarray:
    """Per lever (sorted), the share of [x - width, x + width] nearer to it than to any
    other lever (its cell, clipped to the window): the chance that a grasp aimed at x with a
    uniform lever error lands nearest to it. Levers refined densely inside a step share its
    window instead of outvoting the levers on its other side."""
    r = np.asarray(levers, dtype=float)
    mid = 0.5 * (r[1:] + r[:-1])
    lo = np.clip(np.concatenate([[-np.inf], mid]), x - width, x + width)
    hi = np.clip(np.concatenate([mid, [np.inf]]), x - width, x + width)
    return (hi - lo) / (2.0 * width)


def weighted_median(values: Sequence[float], weights: Sequence[float]) -> float:
    """The value at which the cumulative weight of the sorted values reaches half (the
    mean of the two values where it is exactly half)."""
    v, w = np.asarray(values, dtype=float), np.asarray(weights, dtype=float)
    order = np.argsort(v)
    v, c = v[order], np.cumsum(w[order]) / np.sum(w)
    i = int(np.searchsorted(c, 0.5 - 1e-12))
    return float(0.5 * (v[i] + v[i + 1]) if abs(c[i] - 0.5) < 1e-12 else v[i])


def pooled_median(levers: Sequence[float], tilts: Sequence[Sequence[float]]) -> np.ndarray:
    """Per lever (sorted), the median |tilt| over the grasps at levers within POOL_WIDTH of
    it, each lever weighted by its share of that window (``lever_shares``) split among its
    grasps: the tilt a grasp aimed there lands at, its usual lever error included."""
    r = np.asarray(levers, dtype=float)
    out = []
    for x in r:
        share = lever_shares(r, x)
        j = np.flatnonzero(share > 0)
        values = np.concatenate([np.ravel(tilts[k]) for k in j])
        weights = np.concatenate([np.full(np.size(tilts[k]), share[k] / np.size(tilts[k]))
                                  for k in j])  # fmt: skip
        out.append(weighted_median(values, weights))
    return np.array(out)


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


ABOUT = (
    "Tilt calibration of the accuracy experiment (comgrasp_pin.experiments.design). "
    "Per object and side of the centre its true CoM lies on (+x: the heavy end's "
    "half, -x: the other) and per lever ratio (grasp-to-CoM distance over the "
    "nominal holding lever holding_lever_m): abs_tilt_deg, the TRUE tilt (deg, from "
    "the simulator, wrapped to [-90, 90) and made absolute) at which the rod "
    "settled in the jaws, one trial grasp per calibration seed, each in its own "
    "scene (90 = it dropped); median_abs_tilt_deg their median; pooled_median_deg "
    f"the median over the grasps within {LEVER_SCATTER} of the lever; tilt_deg that "
    "made monotone (pool adjacent violators), the curve the design inverts. Measured "
    "with the ideal sensor preset's procedure (the paper's); the design uses these curves "
    "under every preset. runs lists every run that measured some of them."
)


def merged(old: dict, curves: dict, made: dict) -> dict:
    """The calibration ``old`` with the ``curves`` of a run ``made`` put in ("objects",
    "made"); objects not measured again keep their curves, and every run stays listed in
    "runs"."""
    data = {"about": ABOUT, **{k: v for k, v in old.items() if k != "about"}}
    data["made"] = made
    data["objects"] = {**data.get("objects", {}), **curves}
    data["runs"] = [*old.get("runs", [old["made"]] if "made" in old else []), made]
    return data


def dumps(data, indent: int = 0) -> str:
    """JSON with every list of numbers (or of such lists) on one line."""
    pad = " " * (indent + 1)
    if isinstance(data, dict) and data:
        items = (f"{pad}{json.dumps(k)}: {dumps(v, indent + 1)}" for k, v in data.items())
        return "{\n" + ",\n".join(items) + "\n" + " " * indent + "}"
    if isinstance(data, list) and any(isinstance(v, dict) for v in data):
        return "[\n" + ",\n".join(pad + dumps(v, indent + 1) for v in data) + "\n]"
    return json.dumps(data)
