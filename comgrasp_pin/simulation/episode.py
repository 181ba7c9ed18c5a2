"""One pick-and-place episode of the paper's second experiment, in the simulated world.

``baseline`` carries the rod from the top view's geometric-centre grasp; ``regrasp`` makes
careful trial grasps (``simulation.trial``), and when the planner says so lays the rod down
mid-table and grasps it again at the graspable point nearest the estimated CoM before
carrying it to the drop box. Physics decides whether the rod arrives. The names of
``simulation.scene`` and ``simulation.trial`` are re-exported here for convenience.

Ground truth (``World.truth``) is read only to score the result, never to act.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from comgrasp_pin.errors import PerceptionError
from comgrasp_pin.motion.ik import Q_PARK, IKError, grasp_height, solve_ik, top_down_frame
from comgrasp_pin.perception.top_down import nearest_graspable
from comgrasp_pin.planning.regrasp import com_grasp, decide
from comgrasp_pin.simulation import skills as motion
from comgrasp_pin.simulation.eyes import look_from_above
from comgrasp_pin.simulation.scene import (  # noqa: F401  (re-exported)
    EpisodeConfig,
    Scene,
    World,
    random_table_pose,
)
from comgrasp_pin.simulation.sim import Simulation
from comgrasp_pin.simulation.trial import (  # noqa: F401  (re-exported)
    RodDroppedError,
    TrialGrasp,
    trial_grasp,
    trial_with_retry,
)

METHODS = ("baseline", "regrasp")
PUT_DOWN_XY = (0.55, 0.0)  # where a rod is put down to be grasped again: mid-table (m)
PUT_DOWN_V_MAX, PUT_DOWN_A_MAX = 0.5, 0.5  # joint limits carrying a rod to be put down
PIVOT_GRIP = 4.0  # force of each finger while a rod pivots on its low end to lie flat (N)


@dataclass(frozen=True)
class EpisodeResult:
    """Outcome of ``run_episode`` (frozen; ``row()`` flattens it for a CSV).

    Attributes:
        scene: the trial's scene. method: "baseline" or "regrasp".
        success: the rod ended inside the drop box.
        regrasped: the planner put the rod down and grasped it at the estimated CoM.
        reason: the planner's reason (or the baseline's).
        trial: the trial grasp's measurement (regrasp only).
        final_grasp_offset: where the carrying grasp held the rod, from its centre (true, m).
        timings: wall-clock seconds per phase.
    """

    scene: Scene
    method: str
    success: bool
    regrasped: bool
    reason: str
    trial: TrialGrasp | None
    final_grasp_offset: float
    timings: dict

    def row(self) -> dict:
        t = self.trial
        nan = float("nan")
        return {
            "length_m": self.scene.length,
            "pos_real_m": self.scene.pos_real,
            "pos_esti_m": t.pos_esti if t else nan,
            "theta_deg": np.degrees(t.theta) if t else nan,
            "accuracy": t.accuracy if t else nan,
            "mass_real_kg": t.mass_real if t else nan,
            "mass_esti_kg": t.mass_esti if t else nan,
            "success": int(self.success),
            "regrasped": int(self.regrasped),
            "reason": self.reason,
            "final_grasp_offset_m": self.final_grasp_offset,
            "wall_s": sum(self.timings.values()),
        }


def _carry(world: World) -> bool:
    motion.carry_to_drop_box(world.sim, world.robot)
    motion.move_to(world.sim, Q_PARK)
    world.sim.hold(0.3)
    return world.in_drop_box()


def run_episode(
    obj: str,
    seed: int,
    method: str = "regrasp",
    pos_real: float | None = None,
    config: EpisodeConfig | None = None,
    video: Path | None = None,
    viewer: bool = False,
) -> EpisodeResult:
    """One pick-and-place of ``obj`` on the scene drawn from ``seed`` (same seed, same
    scene and same sensor noise: the result is reproducible). ``video``: write an MP4 and a
    key-frame strip (PNG) of the episode there. ``viewer``: show it in MuJoCo's interactive
    viewer (needs a display), in real time."""
    if method not in METHODS:
        raise ValueError(f"method must be one of {METHODS}, got {method!r}")
    config = config or EpisodeConfig()
    scene = Scene.sample(obj, seed, pos_real)
    world = World(scene, config, seed)
    recorder = None
    if viewer:
        world.sim.observers.append(_LiveViewer(world.sim))
    if video is not None:
        from comgrasp_pin.simulation.recorder import EpisodeRecorder

        recorder = EpisodeRecorder(world.sim)
        world.sim.observers.append(recorder)
    timings: dict[str, float] = {}
    start = time.perf_counter()
    trial, regrasped, success, final_offset = None, False, False, float("nan")
    try:
        try:
            if method == "baseline":
                _caption(recorder, "baseline: grasp at the geometric centre")
                rod = look_from_above(world.rig, world.sim.data).grasp
                motion.pick(world.sim, world.robot, rod, grip_force=config.grip_force)
                reason = "geometric-centre grasp"
            else:
                trial, regrasped, reason = _measure_and_regrasp(world, recorder)
                timings["trial"] = time.perf_counter() - start
            final_offset = world.grasp_offset_true()
            mark = time.perf_counter()
            _caption(recorder, "carrying to the drop box")
            success = _carry(world)
            timings["carry"] = time.perf_counter() - mark
            if not success:
                reason += f"; the rod ended {world.where_is_the_rod()}"
        except (RodDroppedError, PerceptionError, IKError) as exc:
            # The robot lost the rod, or cannot see or reach it any more: a failed episode.
            reason = f"{type(exc).__name__}: {exc}; the rod ended {world.where_is_the_rod()}"
        if recorder is not None:
            video.parent.mkdir(parents=True, exist_ok=True)
            recorder.write_video(video)
            recorder.write_strip(video.with_suffix(".png"))
    finally:
        if recorder is not None:
            recorder.close()
        world.close()
    timings["total"] = time.perf_counter() - start - sum(timings.values())
    return EpisodeResult(scene, method, success, regrasped, reason, trial, final_offset, timings)


def _measure_and_regrasp(world: World, recorder) -> tuple[TrialGrasp, bool, str]:
    """The regrasp method up to the carrying grasp: (trial, regrasped, reason)."""
    _caption(recorder, "trial grasp at the geometric centre, measuring")
    trial = trial_with_retry(world)
    decision = decide(trial.theta, trial.slip_seen, trial.x_com_obj,
                      trial.side_view.grasp_offset, world.config.planner)  # fmt: skip
    if not decision.regrasp:
        return trial, False, decision.reason
    _caption(recorder, f"regrasp: {decision.reason}")
    p_pivot, low_is_plus = _put_down(world, trial)
    rod = look_from_above(world.rig, world.sim.data)
    # The low end stayed at the pivot as the rod lay down: seen from the rod's new centre,
    # it tells which way the rod's +x end points.
    centre = np.array([rod.grasp.x, rod.grasp.y])
    to_pivot = np.r_[p_pivot[:2] - centre, 0.0]
    axis_hint = to_pivot if low_is_plus else -to_pivot
    # The CoM lies x_com along the rod from its centre (the side view measures both within
    # millimetres), and the top view sees the centre where the rod now lies; measured from
    # where the jaws let go instead, the rod sliding in the jaws as it pivots flat would
    # carry over (centimetres).
    x_com_from_centre = decision.x_com_obj
    target = com_grasp(rod.grasp, axis_hint, x_com_from_centre,
                       lambda s: nearest_graspable(rod, s))  # fmt: skip
    motion.pick(world.sim, world.robot, target, grip_force=world.config.grip_force)
    return trial, True, decision.reason


def _put_down(world: World, trial: TrialGrasp) -> tuple[np.ndarray, bool]:
    """Lay the held rod down mid-table, along the table's long side (y), and go home.

    A rod hanging tilted in the jaws is laid down as a person would: lowered until its low
    end nearly touches the table, then the jaws move down and away from that end together,
    so that the rod pivots on it and comes to lie flat where it is (lowering it straight
    down would push it through the jaws and topple it). Uses only what the side camera
    measured (axis, centre, length from the top view). Returns where the rod's low end met
    the table (3,), the pivot it lay down about, and whether that end is its +x end."""
    sim, robot = world.sim, world.robot
    T_now = robot.ee_pose(sim.q_des)
    yaw = np.pi / 2 if T_now[1, 0] >= 0 else -np.pi / 2  # the nearer of the two
    x_axis, centre = trial.T_ee_obj[:3, 0], trial.T_ee_obj[:3, 3]
    ends = [centre + s * 0.5 * trial.rod_length * x_axis for s in (-1.0, 1.0)]
    low = max(ends, key=lambda e: e[2])  # ee z points down
    low_is_plus = bool((low - centre) @ x_axis > 0)
    reach = float(np.hypot(low[0], low[2]))  # TCP to the low end, in the jaws' plane
    shift = low[0] - np.sign(low[0]) * reach  # TCP move along ee-x that lays the rod flat
    # Flat, the rod's centre lies -grasp_offset along ee-x from the TCP: put it mid-table.
    e_x = np.array([np.cos(yaw), np.sin(yaw)])
    xy_touch = np.asarray(PUT_DOWN_XY) + (trial.side_view.grasp_offset - shift) * e_x
    T_above = top_down_frame(*xy_touch, T_now[2, 3], yaw)
    # Gently: the rod may be held close to its slip limit (that is why it is put down).
    motion.move_to(sim, solve_ik(robot, T_above, sim.q_des), v_max=PUT_DOWN_V_MAX,
                   a_max=PUT_DOWN_A_MAX, settle=0.2)  # fmt: skip
    # Flat, the rod's axis lies where it is now below the TCP (its point nearest the TCP):
    # the TCP ends that far above the axis' height on the table.
    near = centre - (centre @ x_axis) * x_axis
    # (never lower than a grasp of the rod lying there: the pads must not jam on the table)
    z_flat = max(trial.rod_axis_z + near[2] + 0.003, grasp_height(trial.rod_axis_z))
    T_touch = T_above.copy()
    T_touch[2, 3] = max(z_flat + low[2] + 0.01, z_flat)
    T_flat = T_above.copy()
    T_flat[:3, 3] += shift * T_above[:3, 0]
    T_flat[2, 3] = z_flat
    # Slowly: a rod held near its slip limit turns if the descent brakes hard (0.4 m in 3 s
    # peaks at 0.27 m/s^2).
    motion.move_linear(sim, robot, T_touch, 3.0)
    p_pivot = T_touch[:3, :3] @ low + T_touch[:3, 3]  # where the low end meets the table
    # Loosen the grip so that the rod turns in the jaws as it lays down, as a hand would;
    # held firmly, it would be pushed into the table until it slipped out.
    sim.grip_force = min(PIVOT_GRIP, sim.grip_force)
    motion.place(sim, robot, T_flat, lower_time=2.0)
    motion.move_to(sim, Q_PARK)
    sim.hold(0.5)
    return p_pivot, low_is_plus


class _LiveViewer:
    """A Simulation observer that mirrors the world in MuJoCo's passive viewer at 60 Hz,
    paced to real time."""

    def __init__(self, sim: Simulation):
        import mujoco.viewer

        self._handle = mujoco.viewer.launch_passive(sim.model, sim.data)
        self._next = sim.time
        self._start = (time.perf_counter(), sim.time)

    def __call__(self, sim: Simulation) -> None:
        if sim.time < self._next or not self._handle.is_running():
            return
        self._next += 1.0 / 60.0
        self._handle.sync()
        ahead = (sim.time - self._start[1]) - (time.perf_counter() - self._start[0])
        if ahead > 0:
            time.sleep(ahead)


def _caption(recorder, text: str) -> None:
    if recorder is not None:
        recorder.caption = text
