"""One live measurement: the empty run, the payload attached, the loaded run; one log.

At rest (``measure``), the arm visits the poses (``protocol.stops``: each from both sides),
holds and records at each arrival, first empty and then holding the payload, going back
along the same path. Along a planned motion (``measure_motion``), it waits at the motion's
start, plays it and waits again, empty and then loaded. Every state read (moves, settling,
holds) goes into one log on the robot's clock, written as the CSV that ``comgrasp estimate``
reads, with the windows that pair the runs: the live estimate and an offline one of the same
file are the same computation. A run cut short (Ctrl-C, a reflex, a lost connection) keeps
what was recorded (``Recording.complete`` False).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from tqdm import tqdm

from comgrasp_pin.config import LiveConfig
from comgrasp_pin.live.franka import FrankaArm
from comgrasp_pin.live.protocol import EMPTY, LOADED, Waypoints, stops, visit_order, windows_text
from comgrasp_pin.robot_io.log_files.log_types import JointLog


@dataclass(frozen=True)
class Recording:
    """What a live measurement recorded.

    Attributes:
        log: every state read, time from the first read (s), the arm's joints.
        wrench: (N, 6) the robot's own external-wrench estimate ``O_F_ext_hat_K`` per read
            (N, N m; base frame), or None where it stayed zero.
        spans: {"empty"|"loaded": per pose, the recorded (t0, t1) windows (s)}, one per side;
            along a motion, one "pose" with one window (the motion and its holds).
        complete: every window of both runs was recorded.
        stopped_by: why the session ended early ("" when complete).
    """

    log: JointLog
    wrench: np.ndarray | None
    spans: dict
    complete: bool
    stopped_by: str = ""

    @property
    def before(self) -> str:
        """The ``--before`` windows (the poses recorded in both runs, both sides)."""
        return windows_text(self._paired()[0])

    @property
    def after(self) -> str:
        """The ``--after`` windows, paired with ``before``."""
        return windows_text(self._paired()[1])

    def _paired(self):
        """The poses with both sides in both runs."""
        pairs = [(b, a) for b, a in zip(self.spans.get(EMPTY, []), self.spans[LOADED])
                 if len(b) == 2 and len(a) == 2]  # fmt: skip
        return [b for b, _ in pairs], [a for _, a in pairs]

    @property
    def motion_windows(self) -> tuple[str | None, str] | None:
        """Along a motion: the ``--empty-window`` and ``--window`` texts.

        The first is None without an empty run (an arm model stands for it); None where
        the loaded run is missing.
        """
        empty, loaded = self.spans.get(EMPTY, [[]])[0], self.spans[LOADED][0]
        if len(loaded) != 1:
            return None
        return (windows_text([empty]) if len(empty) == 1 else None), windows_text([loaded])

    @property
    def n_pairs(self) -> int:
        """The number of poses recorded from both sides in both runs."""
        return len(self._paired()[0])


def measure(
    arm: FrankaArm,
    joint_names: tuple[str, ...],
    Q: np.ndarray,
    attach: Callable[[], None],
    config: LiveConfig,
    show_progress: bool = True,
) -> Recording:
    """Run the empty and the loaded runs over the poses ``Q`` (k, n).

    The empty run visits the poses in ``visit_order`` from the arm's pose, the loaded run
    in the reverse order. Never raises for the robot's sake: a failure ends the recording
    early, named in ``stopped_by``.

    ``attach``: called between the runs (a prompt, or the simulator attaching the payload).
    KeyboardInterrupt (Ctrl-C) also ends it early, after the arm is stopped.
    """
    spans: dict = {EMPTY: [[] for _ in Q], LOADED: [[] for _ in Q]}
    arm.read()
    order = visit_order(arm.samples.q[-1], Q)
    plans = {EMPTY: stops(Q, config.approach_rad, order),
             LOADED: stops(Q, config.approach_rad, order[::-1])}  # fmt: skip

    def one_run(run: str, bar) -> None:
        for stop in plans[run]:
            bar.set_postfix_str(f"{run} pose {stop.pose} side {stop.side:+.0f}")
            arm.move(stop.q)
            if stop.record:
                spans[run][stop.pose].append(arm.record_still(config.record_s))
            bar.update()

    return _both_runs(arm, joint_names, attach, spans, one_run, 4 * len(Q), show_progress)


def measure_motion(
    arm: FrankaArm,
    joint_names: tuple[str, ...],
    motion: Waypoints,
    attach: Callable[[], None],
    config: LiveConfig,
    show_progress: bool = True,
    empty_run: bool = True,
) -> Recording:
    """Play a planned motion empty and then loaded; failures as ``measure``'s.

    Each run's window holds the motion and ``config.motion_hold_s`` still before and after.
    ``empty_run`` False: the loaded run alone (an arm model stands for the empty arm).
    """
    spans: dict = {run: [[]] for run in ((EMPTY, LOADED) if empty_run else (LOADED,))}

    def one_run(run: str, bar) -> None:
        bar.set_postfix_str(f"{run}: to the start")
        arm.move(motion.start)
        t0, _ = arm.hold(config.motion_hold_s)
        bar.set_postfix_str(f"{run}: the motion")
        arm.play(motion)
        _, t1 = arm.hold(config.motion_hold_s)
        spans[run][0].append((t0, t1))
        bar.update()

    return _both_runs(arm, joint_names, attach, spans, one_run, 1, show_progress)


def _both_runs(arm: FrankaArm, joint_names, attach, spans: dict, one_run, moves: int,
               show_progress: bool) -> Recording:  # fmt: skip
    """What was recorded by ``one_run(run, bar)`` for each run of ``spans`` in turn.

    The runs are ``spans``' keys (empty, loaded); ``attach()`` comes before the loaded one.
    """
    stopped_by = ""
    bar = tqdm(total=len(spans) * moves, desc="live", unit="move", disable=not show_progress)
    try:
        for run in spans:
            if run == LOADED:
                attach()  # a prompt: Ctrl-C there is Python's own
                arm.check_ready()
            with arm.ctrl_c_stops():
                one_run(run, bar)
    except KeyboardInterrupt:
        stopped_by = "interrupted (Ctrl-C): the arm was stopped"
    except Exception as exc:  # RobotError, or anything else: keep what was recorded
        stopped_by = str(exc)
    finally:
        bar.close()
    return _recording(arm, joint_names, spans, not stopped_by, stopped_by)


def _recording(arm: FrankaArm, joint_names, spans: dict, complete: bool, stopped_by: str):
    """The Recording of the arm's samples, times from the first (s)."""
    s = arm.samples
    if not len(s):
        return Recording(JointLog(np.zeros(0), tuple(joint_names), np.zeros((0, len(joint_names))),
                                  np.zeros((0, len(joint_names))), "live"), None, spans, False,
                         stopped_by or "nothing was recorded")  # fmt: skip
    t = np.asarray(s.time)
    t0 = t[0]
    shifted = {run: [[(a - t0, b - t0) for a, b in pose] for pose in poses]
               for run, poses in spans.items()}  # fmt: skip
    wrench = np.array(s.wrench)
    log = JointLog(t - t0, tuple(joint_names), np.array(s.q), np.array(s.tau_J), "live",
                   velocity=np.array(s.dq))  # fmt: skip
    return Recording(log, wrench if np.any(wrench) else None, shifted, complete, stopped_by)
