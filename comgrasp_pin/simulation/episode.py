"""Episodes in the simulated world: a scored trial grasp, and one pick and place.

``measure_and_score`` runs the trial grasp (``procedures.trial_grasp``) in a ``World`` and
scores it against the truth at the moment the rod was measured; ``run_episode`` runs one
pick and place (``procedures.pick_and_place``) with ``baseline`` or ``regrasp`` and lets the
physics decide whether the rod arrives. Ground truth is read only to score, never to act.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from comgrasp_pin.config import EpisodeConfig
from comgrasp_pin.errors import IKError, InvalidInputError, PerceptionError, RodDroppedError
from comgrasp_pin.geometry import invert_transform
from comgrasp_pin.procedures import phases, pick_and_place
from comgrasp_pin.procedures.measurement import TrialMeasurement
from comgrasp_pin.procedures.phases import phase_of
from comgrasp_pin.procedures.trial_grasp import MEASURED, trial_grasp
from comgrasp_pin.simulation.cell import SimCell
from comgrasp_pin.simulation.recorder import ComOnRod
from comgrasp_pin.simulation.scene import Scene, World
from comgrasp_pin.simulation.scoring import TrialScore, in_drop_box, score_trial, where_is

METHODS = ("baseline", "regrasp")


def score(cell: SimCell, trial: TrialMeasurement) -> TrialScore:
    """``trial`` against the truth the cell kept when the rod was measured."""
    snap = cell.snapshots[MEASURED]
    return score_trial(trial, snap.truth, snap.grasp_offset, cell.world.scene.length)


def measure_and_score(world: World, offset: float = 0.0) -> tuple[TrialMeasurement, TrialScore]:
    """One trial grasp ``offset`` m along the rod from its perceived centre, scored."""
    cell = SimCell(world)
    trial = trial_grasp(cell, world.config, offset)
    return trial, score(cell, trial)


def estimate_on_rod(trial: TrialMeasurement | None, cell: SimCell) -> ComOnRod | None:
    """The trial's CoM estimate fixed in the rod (its true frame when the rod was measured),
    known from the end of the last measurement phase on; None without a trial."""
    if trial is None or MEASURED not in cell.snapshots:
        return None
    p_world = trial.T_world_ee @ trial.T_ee_obj @ np.array([trial.x_com_obj, 0.0, 0.0, 1.0])
    T_world_obj = cell.snapshots[MEASURED].truth.T_world_obj
    p_obj = invert_transform(T_world_obj) @ p_world
    kinds = [phase_of(c) for _, c in cell.phases]
    last = max((k for k, kind in enumerate(kinds) if kind == phases.MEASURING), default=None)
    since = cell.phases[last + 1][0] if last is not None and last + 1 < len(kinds) else np.inf
    return ComOnRod(p_obj[:3], float(trial.x_com_std), float(since), T_world_obj.copy())


@dataclass(frozen=True)
class EpisodeResult:
    """Outcome of ``run_episode`` (frozen; ``row()`` flattens it for a CSV).

    Attributes:
        scene: the trial's scene. method: "baseline" or "regrasp".
        success: the rod ended inside the drop box.
        regrasped: the planner put the rod down and grasped it at the estimated CoM.
        reason: the planner's reason (or the baseline's), and where a lost rod ended.
        trial: the trial grasp's measurement (regrasp only); trial_score: it, scored.
        final_grasp_offset: where the carrying grasp held the rod, from its centre (true, m).
        timings: wall-clock seconds per phase.
        sim_s: simulated seconds of the episode (from the world's construction on).
        phases: (simulated time (s), announcement) of each phase the procedures announced
            (``procedures.phases``), in order.
    """

    scene: Scene
    method: str
    success: bool
    regrasped: bool
    reason: str
    trial: TrialMeasurement | None
    trial_score: TrialScore | None
    final_grasp_offset: float
    timings: dict
    sim_s: float = float("nan")
    phases: tuple = ()

    def row(self) -> dict:
        t, s = self.trial, self.trial_score
        nan = float("nan")
        return {
            "length_m": self.scene.length,
            "pos_real_m": self.scene.pos_real,
            "pos_esti_m": s.pos_esti if s else nan,
            "theta_deg": np.degrees(t.theta) if t else nan,
            "accuracy": s.accuracy if s else nan,
            "mass_real_kg": s.mass_real if s else nan,
            "mass_esti_kg": t.mass_esti if t else nan,
            "success": int(self.success),
            "regrasped": int(self.regrasped),
            "reason": self.reason,
            "final_grasp_offset_m": self.final_grasp_offset,
            "pos_std_m": t.x_com_std if t else nan,
            "extra_pose": int(t.extra_pose) if t else 0,
            "sim_s": self.sim_s,
            "wall_s": sum(self.timings.values()),
        }


def run_episode(
    obj: str,
    seed: int,
    method: str = "regrasp",
    pos_real: float | None = None,
    config: EpisodeConfig | None = None,
    video: Path | None = None,
    viewer: bool = False,
    rerun: Path | None = None,
) -> EpisodeResult:
    """One pick-and-place of ``obj`` on the scene drawn from ``seed`` (same seed, same
    scene and same sensor noise: the result is reproducible). ``video``: write an MP4 and a
    key-frame strip (PNG) of the episode there. ``viewer``: show it in MuJoCo's interactive
    viewer (needs a display), in real time. ``rerun``: write a Rerun recording (.rrd) there
    (needs the ``rerun`` extra)."""
    config = _checked(method, config)
    if rerun is not None:
        from comgrasp_pin.simulation.rerun_log import import_rerun

        import_rerun()  # MissingExtraError before anything is built
    scene = Scene.sample(obj, seed, pos_real)
    world = World(scene, config, seed)
    recorder, rerun_log = _observers(world, video, viewer, rerun)
    cell = SimCell(world, recorder)
    timings: dict[str, float] = {}
    start = time.perf_counter()
    grasped, final_offset = None, float("nan")
    try:
        grasped, success, reason = _pick_and_place(cell, method, config, timings, start)
        if pick_and_place.CARRYING in cell.snapshots:
            final_offset = cell.snapshots[pick_and_place.CARRYING].grasp_offset
        title = f"{obj}, seed {seed}, {method}: {'delivered' if success else 'not delivered'}"
        _finish_recordings(cell, grasped, recorder, rerun_log, video, title)
    finally:
        sim_s = world.sim.time
        for observer in (recorder, rerun_log):
            if observer is not None:
                observer.close()
        world.close()
    timings["total"] = time.perf_counter() - start - sum(timings.values())
    trial = grasped.trial if grasped is not None else None
    trial_score = score(cell, trial) if trial is not None else None
    return EpisodeResult(scene, method, success, grasped is not None and grasped.regrasped,
                         reason, trial, trial_score, final_offset, timings, sim_s,
                         tuple(cell.phases))  # fmt: skip


def _checked(method: str, config: EpisodeConfig | None) -> EpisodeConfig:
    """``config`` (default ``EpisodeConfig()``) once ``method`` and it are valid."""
    if method not in METHODS:
        raise InvalidInputError(f"method must be one of {METHODS}, got {method!r}")
    if config is not None and not isinstance(config, EpisodeConfig):
        raise InvalidInputError(f"config must be an EpisodeConfig, got {type(config).__name__}")
    return config or EpisodeConfig()


def _observers(world: World, video: Path | None, viewer: bool, rerun: Path | None) -> tuple:
    """(recorder, rerun log), each None unless asked for, attached to ``world``'s simulation
    with the live viewer (``viewer``)."""
    recorder = rerun_log = None
    if viewer:
        from comgrasp_pin.simulation.viewer import LiveViewer

        world.sim.observers.append(LiveViewer(world.sim))
    if video is not None:
        from comgrasp_pin.simulation.recorder import EpisodeRecorder

        recorder = EpisodeRecorder(world.sim, world.truth)
        world.sim.observers.append(recorder)
    if rerun is not None:
        from comgrasp_pin.simulation.rerun_log import RerunLog

        rerun_log = RerunLog(world.sim, rerun, world.truth)
        world.sim.observers.append(rerun_log)
    return recorder, rerun_log


def _pick_and_place(cell: SimCell, method: str, config: EpisodeConfig, timings: dict,
                    start: float) -> tuple:  # fmt: skip
    """(the grasp that lifted the rod or None, delivered, why): ``method``'s pick and place,
    the physics deciding. ``timings`` gets the trial's and the carry's wall time (s, from
    ``start``)."""
    grasped = None
    truth = cell.world.truth
    try:
        run = pick_and_place.regrasp if method == "regrasp" else pick_and_place.baseline
        grasped = run(cell, config)
        timings["trial"] = time.perf_counter() - start
        mark = time.perf_counter()
        pick_and_place.deliver(cell, config)
        timings["carry"] = time.perf_counter() - mark
    except (RodDroppedError, PerceptionError, IKError) as exc:
        # The robot lost the rod, or cannot see or reach it any more: a failed episode.
        return (
            grasped,
            False,
            (f"{type(exc).__name__}: {exc}; the rod ended {where_is(truth().p_world_com)}"),
        )
    success = in_drop_box(truth().p_world_com)
    reason = grasped.reason
    if not success:
        reason += f"; the rod ended {where_is(truth().p_world_com)}"
    return grasped, success, reason


def _finish_recordings(cell: SimCell, grasped, recorder, rerun_log, video, title: str) -> None:
    """Write the episode's video and key-frame strip (``title`` on it) and finish its Rerun
    log, where they were asked for, with the CoM estimate on the rod."""
    if recorder is None and rerun_log is None:
        return
    trial = grasped.trial if grasped is not None else None
    estimate = estimate_on_rod(trial, cell)
    if recorder is not None:
        video.parent.mkdir(parents=True, exist_ok=True)
        recorder.finish(estimate, cell.phases)
        recorder.write_video(video)
        recorder.write_strip(video.with_suffix(".png"), title=title)
    if rerun_log is not None:
        rerun_log.finish(estimate, cell.phases, trial)
