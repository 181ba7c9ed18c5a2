"""The two experiments' trials: one function each, run in worker processes by the runner.

Seeds: a trial's seed depends on the run's seed, the object and the trial index only, so
the ``baseline`` and ``regrasp`` trials of the same index see the same scene (rod pose and
true CoM) and ``--resume`` reproduces what an uninterrupted run would have done.
"""

from __future__ import annotations

import time
from dataclasses import asdict, replace

import numpy as np

from comgrasp_pin.config import EpisodeConfig, TrialConfig, hardware_trial, sensor_preset
from comgrasp_pin.config.paths import with_values
from comgrasp_pin.experiments.design import grasp_for_lever, side_and_lever, target_tilt

ACCURACY_COLUMNS = [
    "object", "trial", "method", "seed", "length_m", "pos_real_m", "pos_esti_m", "theta_deg",
    "accuracy", "mass_real_kg", "mass_esti_kg", "theta_true_deg", "grasp_offset_m",
    "com_std_m", "residual_rms_Nm", "slip_seen", "pos_esti_line_m", "accuracy_line",
    "rolled_slip", "dropped_at_roll", "pos_std_m", "com_path", "extra_pose", "estimator",
    *(f"pos_std_{part}_m" for part in
      ("estimator", "tilt", "shift", "out_of_plane", "slide", "creep", "off_axis",
       "calibration")),
    *(f"{c}_{source}{unit}" for source in ("wrench", "both") for c, unit in
      (("pos_esti", "_m"), ("pos_std", "_m"), ("accuracy", ""), ("mass_esti", "_kg"))),
    "wrench_share_mass", "wrench_share_com", "wrench_error", "both_error",
    "sim_s", "wall_s",
]  # fmt: skip
"""The columns of accuracy.csv. The ``_wrench`` and ``_both`` ones: the same grasp's CoM from
the wrist sensor's readings of the same windows, and from both sensors stacked (recorded
beside the joint torques' estimate, which the robot used); ``wrench_share_*``: the wrench's
share of the information on the mass and on the CoM along the rod with both;
``*_error``: why that source gave no estimate (empty: it gave one)."""
REGRASP_COLUMNS = [
    "object", "trial", "method", "seed", "success", "regrasped", "reason", "length_m",
    "pos_real_m", "pos_esti_m", "theta_deg", "accuracy", "mass_real_kg", "mass_esti_kg",
    "final_grasp_offset_m", "pos_std_m", "extra_pose", "sim_s", "wall_s",
]  # fmt: skip
REGRASP_TASK_METHODS = ("regrasp", "baseline")
"""The pick-and-place experiment's methods in the order each scene's tasks are handed out:
the longer first (2.7 s against 0.5 s a trial), so that a part ends on a short trial and
the other worker is not left waiting on a long one."""
ACCURACY_COM_RANGE = (0.0, 0.3)  # true CoM |pos_real| / length, uniform (capped, see below)
ACCURACY_GRASP_OFFSET = 0.25  # grasp offsets from the rectangle's centre, |offset| / length
# Grasp-to-CoM distance as a fraction of the nominal holding lever (``holding_lever``): the
# span the tilt calibration covers (sim/tilt_calibration.json) and the grasps keep to. Each
# grasp gets a target tilt (``design.target_tilt``: each 5 deg bin of 0-30 deg and 30-90 deg
# in turn) and the lever at which the calibration saw its object settle there.
ACCURACY_LEVER_RANGE = (0.35, 1.0)


MAX_TRIALS = 1000
"""Trials per object and method at most: ``trial_seed`` keeps 3 digits for the trial index
(more would give two objects the same seeds)."""


def trial_seed(run_seed: int, obj: str, trial: int) -> int:
    return int(run_seed) * 100_000 + int(obj.removeprefix("obj") or 0) * 1_000 + int(trial)


def make_tasks(objects: list[str], trials: int, seed: int, methods: tuple[str, ...]) -> list[dict]:
    """Every (object, trial, method), interleaved so that early results cover all objects."""
    return [
        {"object": obj, "trial": k, "method": method, "seed": trial_seed(seed, obj, k)}
        for k in range(trials)
        for obj in objects
        for method in methods
    ]


def episode_config(
    noise: float | None = None, estimator: str = "ipopt", sensors: str = "ideal"
) -> EpisodeConfig:
    """The configuration every trial runs with: the defaults, with the sensor preset
    ``sensors`` (``config.sensor_preset``), its torque sensor's white noise set to ``noise``
    (N m per sample; None: the preset's), and the trial grasp's ``estimator``. A realistic
    preset's trial grasp measures as a real arm needs (``config.hardware_trial``: the same
    approach to every pose, windows sized from the measured noise); the ideal preset's is
    the paper's procedure, as in docs/results."""
    preset = sensor_preset(sensors)
    if noise is not None:
        preset = replace(preset, torque=replace(preset.torque, noise_std=float(noise)))
    trial = TrialConfig(estimator=estimator)
    if sensors != "ideal":
        trial = hardware_trial(trial)
    return EpisodeConfig(trial=trial, sensors=preset)


def _episode_config(task: dict) -> EpisodeConfig:
    """The task's config: ``episode_config`` of its noise, estimator and sensor preset,
    with the values of ``task["overrides"]`` (dotted path -> number, a sweep's grid point)
    put in."""
    config = episode_config(task.get("noise", 0.05), task.get("estimator", "ipopt"),
                            task.get("sensors", "ideal"))  # fmt: skip
    return with_values(config, task["overrides"]) if task.get("overrides") else config


def accuracy_grasp(obj: str, seed: int, config) -> tuple[float, float]:
    """(true CoM, grasp offset) along the rod from its centre (m) for one accuracy grasp.

    The grasp targets a tilt (``design.target_tilt`` of the trial index, ``seed`` % 1000,
    and the run seed, ``seed`` // 100000, as ``trial_seed`` composes them). The object's
    tilt calibration gives the side of the centre the true CoM lies on and the lever ratio
    for the target (``design.side_and_lever``, within ACCURACY_LEVER_RANGE). Its distance from the
    centre is uniform within ACCURACY_COM_RANGE of the length, capped so that the grasp that
    lever away on the centre's side stays within ACCURACY_GRASP_OFFSET of the length from
    the centre (on the handle). The experiment designer uses the truth to spread the tilts;
    the robot never sees it.
    """
    trial, run_seed = int(seed) % 1_000, int(seed) // 100_000
    rng = np.random.default_rng(seed + 17)
    side, ratio = side_and_lever(obj, target_tilt(trial, run_seed), rng.random())
    ratio = float(np.clip(ratio, *ACCURACY_LEVER_RANGE))
    return grasp_for_lever(obj, ratio, rng, config, ACCURACY_COM_RANGE, ACCURACY_GRASP_OFFSET,
                           side)  # fmt: skip


def accuracy_trial(task: dict) -> dict:
    """One grasp of the accuracy experiment: random rod pose, random true CoM, grasp at the
    rectangle's centre plus an offset (``accuracy_grasp``); measure and estimate."""
    from comgrasp_pin.simulation.episode import measure_and_score
    from comgrasp_pin.simulation.scene import Scene, World

    seed = int(task["seed"])
    config = _episode_config(task)
    pos_real, offset = accuracy_grasp(task["object"], seed, config)
    scene = Scene.sample(task["object"], seed, pos_real=pos_real)
    world = World(scene, config, seed)
    try:
        start = time.perf_counter()
        t, score = measure_and_score(world, offset)
        wall = time.perf_counter() - start
        sim_s = world.sim.time
    finally:
        world.close()
    std = t.estimate.std
    return {
        "length_m": scene.length,
        "pos_real_m": score.pos_real,
        "pos_esti_m": score.pos_esti,
        "theta_deg": float(np.degrees(t.theta)),
        "accuracy": score.accuracy,
        "mass_real_kg": score.mass_real,
        "mass_esti_kg": t.mass_esti,
        "theta_true_deg": float(np.degrees(score.theta_true)),
        "grasp_offset_m": score.grasp_offset,
        "com_std_m": float(np.linalg.norm(std[1:])) if std is not None else float("nan"),
        "residual_rms_Nm": t.estimate.residual_rms,
        "slip_seen": int(t.slip_seen),
        "pos_esti_line_m": score.pos_esti_line,
        "accuracy_line": score.accuracy_line,
        "rolled_slip": int(t.rolled_slip),
        "dropped_at_roll": int(t.dropped_at_roll),
        "pos_std_m": t.x_com_std,
        "com_path": t.com_path,
        "extra_pose": int(t.extra_pose),
        "estimator": config.trial.estimator,
        **{f"pos_std_{k.replace(' ', '_')}_m": v for k, v in t.std_parts.items()},
        **_by_source(t, score),
        "sim_s": sim_s,
        "wall_s": wall,
    }


def _by_source(t, score) -> dict:
    """The accuracy row's columns of the other sources (``ACCURACY_COLUMNS``' docstring)."""
    row: dict = {}
    for source in ("wrench", "both"):
        loc = t.by_source.get(source, "no wrist sensor")
        ok = not isinstance(loc, str)
        row[f"pos_esti_{source}_m"] = score.pos_esti_by_source.get(source, float("nan"))
        row[f"pos_std_{source}_m"] = loc.std if ok else float("nan")
        row[f"accuracy_{source}"] = score.accuracy_of(source) if ok else float("nan")
        row[f"mass_esti_{source}_kg"] = loc.estimate.mass if ok else float("nan")
        row[f"{source}_error"] = "" if ok else loc
    both = t.by_source.get("both")
    shares = None if both is None or isinstance(both, str) else both.shares["wrench"]
    row["wrench_share_mass"] = float("nan") if shares is None else shares["mass"]
    row["wrench_share_com"] = float("nan") if shares is None else shares["com_along_rod"]
    return row


def regrasp_trial(task: dict) -> dict:
    """One pick-and-place trial with ``task['method']`` ("baseline" or "regrasp")."""
    from comgrasp_pin.simulation.episode import run_episode

    result = run_episode(task["object"], int(task["seed"]), task["method"],
                         config=_episode_config(task))  # fmt: skip
    return result.row()


def settings_summary(noise: float = 0.05, estimator: str = "ipopt", sensors: str = "ideal") -> dict:
    """Every setting an experiment ran with (the whole config tree, with its sensor preset's
    name, and the experiment design), for ``run.json`` and the report."""
    out = asdict(episode_config(noise, estimator, sensors))
    out["accuracy_com_range"] = ACCURACY_COM_RANGE
    out["accuracy_grasp_offset"] = ACCURACY_GRASP_OFFSET
    out["accuracy_lever_range"] = ACCURACY_LEVER_RANGE
    return out
