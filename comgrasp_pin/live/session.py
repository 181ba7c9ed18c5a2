"""One live measurement: the empty run, the payload attached, the loaded run; one log.

The arm visits the poses (``protocol.stops``: each from both sides), holds and records at
each arrival, first empty and then holding the payload. Every state read (moves, settling,
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
from comgrasp_pin.live.protocol import EMPTY, LOADED, stops, windows_text
from comgrasp_pin.robot_io.log_files.log_types import JointLog


@dataclass(frozen=True)
class Recording:
    """What a live measurement recorded.

    Attributes:
        log: every state read, time from the first read (s), the arm's joints.
        wrench: (N, 6) the robot's own external-wrench estimate ``O_F_ext_hat_K`` per read
            (N, N m; base frame), or None where it stayed zero.
        spans: {"empty"|"loaded": per pose, the recorded (t0, t1) windows (s)}, one per side.
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
        pairs = [(b, a) for b, a in zip(self.spans[EMPTY], self.spans[LOADED])
                 if len(b) == 2 and len(a) == 2]  # fmt: skip
        return [b for b, _ in pairs], [a for _, a in pairs]

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

    Never raises for the robot's sake: a failure ends the recording early, named in
    ``stopped_by``.

    ``attach``: called between the runs (a prompt, or the simulator attaching the payload).
    KeyboardInterrupt (Ctrl-C) also ends it early, after the arm is stopped.
    """
    spans: dict = {EMPTY: [[] for _ in Q], LOADED: [[] for _ in Q]}
    plan = stops(Q, config.approach_rad)
    stopped_by = ""
    bar = tqdm(total=2 * len(plan), desc="live", unit="move", disable=not show_progress)
    try:
        for run in (EMPTY, LOADED):
            if run == LOADED:
                attach()  # a prompt: Ctrl-C there is Python's own
                arm.check_ready()
            with arm.ctrl_c_stops():
                for stop in plan:
                    bar.set_postfix_str(f"{run} pose {stop.pose} side {stop.side:+.0f}")
                    arm.move(stop.q)
                    if stop.record:
                        spans[run][stop.pose].append(arm.record_still(config.record_s))
                    bar.update()
    except KeyboardInterrupt:
        stopped_by = "interrupted (Ctrl-C): the arm was stopped"
    except Exception as exc:  # RobotError, or anything else: keep what was recorded
        stopped_by = str(exc)
    finally:
        bar.close()
    complete = not stopped_by
    return _recording(arm, joint_names, spans, complete, stopped_by)


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
