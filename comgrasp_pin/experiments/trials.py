"""The two experiments' trials: one function each, run in worker processes by the runner.

Seeds: a trial's seed depends on the run's seed, the object and the trial index only, so
the ``baseline`` and ``regrasp`` trials of the same index see the same scene (rod pose and
true CoM) and ``--resume`` reproduces what an uninterrupted run would have done.
"""

from __future__ import annotations

from dataclasses import asdict

import numpy as np

ACCURACY_COLUMNS = [
    "object", "trial", "method", "seed", "length_m", "pos_real_m", "pos_esti_m", "theta_deg",
    "accuracy", "mass_real_kg", "mass_esti_kg", "theta_true_deg", "grasp_offset_m",
    "com_std_m", "residual_rms_Nm", "slip_seen", "pos_esti_line_m", "accuracy_line",
    "rolled_slip", "wall_s",
]  # fmt: skip
REGRASP_COLUMNS = [
    "object", "trial", "method", "seed", "success", "regrasped", "reason", "length_m",
    "pos_real_m", "pos_esti_m", "theta_deg", "accuracy", "mass_real_kg", "mass_esti_kg",
    "final_grasp_offset_m", "wall_s",
]  # fmt: skip
ACCURACY_COM_RANGE = (0.0, 0.3)  # true CoM |pos_real| / length, uniform
ACCURACY_GRASP_OFFSET = 0.25  # grasp offsets from the rectangle's centre, |offset| / length


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


def _episode_config(task: dict):
    from comgrasp_pin.simulation.episode import EpisodeConfig
    from comgrasp_pin.simulation.torque_sensor import TorqueSensorConfig

    return EpisodeConfig(sensor=TorqueSensorConfig(noise_std=float(task.get("noise", 0.05))))


def accuracy_trial(task: dict) -> dict:
    """One grasp of the accuracy experiment: random rod pose, random true CoM, grasp at the
    rectangle's centre plus a random offset along the rod; measure and estimate."""
    from comgrasp_pin.simulation.episode import Scene, World, trial_grasp

    seed = int(task["seed"])
    scene = Scene.sample(task["object"], seed, com_range=ACCURACY_COM_RANGE)
    rng = np.random.default_rng(seed + 17)
    offset = rng.uniform(-ACCURACY_GRASP_OFFSET, ACCURACY_GRASP_OFFSET) * scene.length
    world = World(scene, _episode_config(task), seed)
    try:
        import time

        start = time.perf_counter()
        t = trial_grasp(world, offset)
        wall = time.perf_counter() - start
    finally:
        world.close()
    std = t.estimate.std
    return {
        "length_m": scene.length,
        "pos_real_m": t.pos_real,
        "pos_esti_m": t.pos_esti,
        "theta_deg": float(np.degrees(t.theta)),
        "accuracy": t.accuracy,
        "mass_real_kg": t.mass_real,
        "mass_esti_kg": t.mass_esti,
        "theta_true_deg": float(np.degrees(t.theta_true)),
        "grasp_offset_m": t.grasp_offset,
        "com_std_m": float(np.linalg.norm(std[1:])) if std is not None else float("nan"),
        "residual_rms_Nm": t.estimate.residual_rms,
        "slip_seen": int(t.slip_seen),
        "pos_esti_line_m": t.pos_esti_line,
        "accuracy_line": t.accuracy_line,
        "rolled_slip": int(t.rolled_slip),
        "wall_s": wall,
    }


def regrasp_trial(task: dict) -> dict:
    """One pick-and-place trial with ``task['method']`` ("baseline" or "regrasp")."""
    from comgrasp_pin.simulation.episode import run_episode

    result = run_episode(task["object"], int(task["seed"]), task["method"],
                         config=_episode_config(task))  # fmt: skip
    return result.row()


def settings_summary() -> dict:
    """The settings an experiment ran with, for the report."""
    from comgrasp_pin.simulation.episode import EpisodeConfig

    config = EpisodeConfig()
    out = asdict(config)
    out["accuracy_com_range"] = ACCURACY_COM_RANGE
    out["accuracy_grasp_offset"] = ACCURACY_GRASP_OFFSET
    return out
