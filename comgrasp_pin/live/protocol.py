"""The live measurement's rules, as pure functions: what to visit, what to send, what to trust.

A measurement is two runs, the empty arm's and then the payload's, over the same poses or
along the same planned motion. At rest, each pose is reached twice, from q + approach and
from q - approach on every joint, and each arrival is held and recorded: a joint's stuck
friction has opposite signs on the two sides and cancels in the mean of the two windows
(``--before T0:T1+T2:T3``). The poses are visited in the order of the shortest path from the
arm's pose, and the loaded run goes back along it. A planned motion is played as joint
waypoints, slower than planned where it would exceed the dynamics factor. The robot is told
the load (``set_load``) only for an ``identified`` verdict, and what it reports back is
checked.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np

from comgrasp_pin.config import LiveConfig
from comgrasp_pin.errors import InvalidInputError
from comgrasp_pin.estimation.trust import IDENTIFIED

EMPTY, LOADED = "empty", "loaded"
SIDES = (1.0, -1.0)


@dataclass(frozen=True)
class Stop:
    """One target of a run: move there; ``record``: then hold and record a window.

    Attributes:
        q: (n,) the target configuration (rad).
        pose: the index of the measurement pose it serves.
        side: +1 or -1, the side the pose is approached from (0: the approach's start).
        record: whether the arm holds and records there.
    """

    q: np.ndarray
    pose: int
    side: float
    record: bool


def check_dynamics_factor(factor: float, config: LiveConfig) -> float:
    """``factor`` if within (0, config.max_dynamics_factor], else InvalidInputError."""
    cap = config.max_dynamics_factor
    if not (np.isfinite(factor) and 0 < factor <= cap):
        raise InvalidInputError(
            f"--dynamics-factor {factor:g}: must be in (0, {cap:g}]; measurement moves are "
            f"slow on purpose (a person may be beside the arm; the torques at rest should not "
            f"carry the moves' after-effects)"
        )
    return float(factor)


@dataclass(frozen=True)
class Waypoints:
    """A planned motion as the arm plays it.

    Attributes:
        t: (k,) time of each waypoint in the planned motion slowed by ``slow_down`` (s),
            increasing (the robot passes them as fast as its dynamics factor allows).
        q: (k, n) joint positions (rad); the motion starts at ``start``.
        qd: (k, n) joint velocities at the waypoints (rad/s).
        start: (n,) the motion's first configuration (rad), where the arm waits.
        slow_down: played time / planned time (1: as planned).
    """

    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    start: np.ndarray
    slow_down: float

    @property
    def duration_s(self) -> float:
        """The planned motion's length slowed by ``slow_down`` (s)."""
        return float(self.t[-1])


def visit_order(q_start: np.ndarray, Q: np.ndarray) -> list[int]:
    """The order of the poses ``Q`` (k, n) with the shortest path from ``q_start`` (n,).

    A move's length is its largest joint excursion (rad): every joint moves at the same
    share of its limits. Every order is tried up to 7 poses; beyond, the nearest pose next.
    """
    Q = np.asarray(Q, dtype=float)

    def length(order) -> float:
        path = np.vstack([q_start, Q[list(order)]])
        return float(np.abs(np.diff(path, axis=0)).max(axis=1).sum())

    if len(Q) <= 7:
        return list(min(itertools.permutations(range(len(Q))), key=length))
    order, left, q = [], set(range(len(Q))), np.asarray(q_start, dtype=float)
    while left:
        nxt = min(left, key=lambda i: float(np.abs(Q[i] - q).max()))
        order.append(nxt)
        left.remove(nxt)
        q = Q[nxt]
    return order


def stops(Q: np.ndarray, approach_rad: float, order=None) -> list[Stop]:
    """The targets of one run over the poses ``Q`` (k, n): each pose from both sides.

    For each pose, in ``order`` (pose indices; default as given): q + approach, q
    (recorded), q - approach, q (recorded).
    """
    Q = np.asarray(Q, dtype=float)
    out = []
    for i in range(len(Q)) if order is None else order:
        q = Q[i]
        for side in SIDES:
            out.append(Stop(q + side * approach_rad, i, side, False))
            out.append(Stop(q.copy(), i, side, True))
    return out


def motion_waypoints(t, q, qd, qdd, limits, factor: float, config: LiveConfig) -> Waypoints:
    """A planned motion's samples as waypoints the arm can play at ``factor``.

    Args:
        t: (k,) the motion's sample times (plan-motion's), from 0 (s).
        q: (k, n) its joint positions (rad).
        qd: (k, n) its joint velocities (rad/s).
        qdd: (k, n) its joint accelerations (rad/s^2).
        limits: the robot's (velocity, acceleration, jerk) limits, each (n,).
        factor: the dynamics factor the arm moves at.
        config: ``motion_limit_share`` and ``waypoint_period_s``.

    Played ``slow_down`` times slower than planned, the smallest factor >= 1 that keeps
    velocity, acceleration and jerk (which scale as 1/s, 1/s^2 and 1/s^3) within
    ``motion_limit_share * factor`` of the limits.
    """
    t, q, qd, qdd = (np.asarray(a, dtype=float) for a in (t, q, qd, qdd))
    jerk = np.gradient(qdd, t, axis=0)
    allowed = [config.motion_limit_share * factor * np.asarray(v, dtype=float) for v in limits]
    shares = [np.abs(x).max(axis=0) / lim for x, lim in zip((qd, qdd, jerk), allowed)]
    slow = max(1.0, float(shares[0].max()), float(np.sqrt(shares[1].max())),
               float(np.cbrt(shares[2].max())))  # fmt: skip
    count = max(1, int(round(t[-1] * slow / config.waypoint_period_s)))
    t_played = np.linspace(0.0, t[-1] * slow, count + 1)[1:]
    q_w = np.column_stack([np.interp(t_played / slow, t, q[:, j]) for j in range(q.shape[1])])
    qd_w = np.column_stack([np.interp(t_played / slow, t, qd[:, j]) for j in range(q.shape[1])])
    qd_w[-1] = 0.0  # rest to rest
    return Waypoints(t_played, q_w, qd_w / slow, q[0].copy(), slow)


def check_poses_fit(Q: np.ndarray, q_lower: np.ndarray, q_upper: np.ndarray, approach: float):
    """InvalidInputError where a pose's approach (q +- approach) leaves the joint limits."""
    Q = np.atleast_2d(np.asarray(Q, dtype=float))
    bad = np.argwhere((Q - approach < q_lower) | (Q + approach > q_upper))
    if len(bad):
        i, j = bad[0]
        raise InvalidInputError(
            f"pose {i}: joint {j + 1} at {Q[i, j]:.3f} rad is within the approach "
            f"({approach:g} rad) of its limits [{q_lower[j]:.3f}, {q_upper[j]:.3f}]: "
            "plan the poses with a margin (comgrasp plan-poses) or move that pose"
        )


def windows_text(spans: list[list[tuple[float, float]]]) -> str:
    """``--before``/``--after`` text of per-pose spans: ``a:b+c:d,e:f+g:h`` (s)."""
    return ",".join("+".join(f"{t0:.4f}:{t1:.4f}" for t0, t1 in pose) for pose in spans)


def load_to_send(estimate, payload) -> tuple[bool, str]:
    """(send, why): the load goes to the robot only for an ``identified`` verdict.

    ``payload``: the ``Payload`` in the flange frame (``payload_in_flange``), or None where
    none was made. The reasons of any other verdict are the answer.
    """
    if estimate.verdict != IDENTIFIED or payload is None:
        reasons = "; ".join(estimate.reasons) or "no payload file could be made"
        return False, f"verdict {estimate.verdict}: {reasons}. Nothing was sent to the robot"
    return True, "identified"


def load_read_back(sent: dict, m_load: float, F_x_Cload, I_load, tolerance: float) -> list[str]:
    """What the robot reports back differing from what was sent (empty: all agree).

    ``sent``: ``exports.franka_load``'s dict (mass, F_x_Cload, load_inertia column-major);
    ``I_load`` read back as 9 values (column-major) or a 3x3 matrix.
    """
    mass, com, inertia = sent["mass"], sent["F_x_Cload"], sent["load_inertia"]
    out = []
    if abs(m_load - mass) > tolerance:
        out.append(f"m_load {m_load:.6g} kg, sent {mass:.6g}")
    if np.max(np.abs(np.asarray(F_x_Cload) - com)) > tolerance:
        out.append(f"F_x_Cload {np.round(F_x_Cload, 6)} m, sent {np.round(com, 6)}")
    I_read = np.asarray(I_load, dtype=float)
    I_read = I_read.reshape(-1, order="F") if I_read.ndim == 2 else I_read  # 3x3 or 9
    if np.max(np.abs(I_read - inertia)) > tolerance:
        out.append(f"I_load {np.round(I_load, 6)}, sent {np.round(inertia, 6)}")
    return out
