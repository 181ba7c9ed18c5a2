"""The accuracy experiment's design: grasps placed for target tilts.

A rod grasped a lever e from its CoM turns in the jaws once its weight's moment m g e
exceeds what the jaws hold (``planning.holding``); it settles where m g e cos(theta) meets
that moment, give or take the lift's dynamics. Random grasps therefore either hold level or
turn far, and the paper's 0-30 deg range stays nearly empty. The design instead

1. measures, once per object and side of its centre the CoM lies on, the TRUE settled
   tilt against the lever ratio r = e / (the nominal holding lever) in trial grasps
   (``tilt_calibration.measure_tilt_curve``; ``tilt_calibration.calibrate`` writes the
   curves of the median tilt, pooled over neighbouring levers and made monotone, to
   ``sim/tilt_calibration.json``). The side
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
``python -m comgrasp_pin.experiments.tilt_calibration --out sim/tilt_calibration.json``
(``experiments.tilt_calibration``).
"""

from __future__ import annotations

import json
import os
from collections.abc import Sequence
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
# The calibration's grid (``tilt_curves``): coarse lever ratios (e / holding lever), then
# DENSE_LEVERS across each curve's rise, then each step bisected; CALIBRATION_SEEDS grasps
# per lever and side, each in its own scene.
CALIBRATION_LEVERS = (0.35, 0.45, 0.55, 0.65, 0.75, 0.85, 1.0)
CALIBRATION_SEEDS = (0, 1)
DENSE_LEVERS = 10
SIDES = {"+x": 1.0, "-x": -1.0}  # the CoM on the heavy end's half of the rod, or the other
GAP_DEG = 20.0  # a rise this steep between calibrated neighbours is a step (no tilts inside)
# The lever error of a grasp (its share of the holding lever): perception and the scene
# put the achieved tilt where the curve is 0.01-0.02 further on or back (measured, ideal
# preset; the realistic preset's perceived grasp point scatters 2-3 mm, 0.05-0.1).
LEVER_SCATTER = 0.015
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
        raise MissingAssetError(
            f"no tilt calibration at {file}; run python -m "
            f"comgrasp_pin.experiments.tilt_calibration --out {file}"
        )
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
    ``side`` (+1 or -1) of the centre (measured with the ideal preset's procedure, the
    paper's; used under every preset)."""
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
