"""Static time windows of a JointLog: averaged readings, the static check, automatic windows.

A window is static when the joint speed stays below ``max_speed`` (rad/s, or m/s for a
prismatic joint) over it. The speed is the change of position over ``SPEED_SPAN`` seconds
(not sample to sample: encoder noise divided by a 2 ms step would swamp a slow drift).
Each static window gives the mean configuration and torques, and the per-sample spread of
the torques, from which the noise of the mean follows (std / sqrt(n), white noise assumed).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from comgrasp_pin.errors import InvalidInputError, LogError, NotStaticError
from comgrasp_pin.robot_io.log_files.joint_readers import JointLog
from comgrasp_pin.robot_io.log_files.log_types import WrenchLog

MAX_SPEED = 0.01  # default static threshold on every joint's speed (rad/s): 0.6 deg/s
SPEED_SPAN = 0.1  # seconds over which the joint speed is measured
MIN_STATIC_S = 0.5
"""Automatic windows: the arm must stay static this long (s)."""
MIN_SAMPLES = 3


@dataclass(frozen=True)
class StaticReading:
    """One static window's averaged readings.

    Attributes:
        t0, t1: the window (s from the log's first message).
        q: (n,) mean configuration (rad / m).
        tau: (n,) mean joint torques (N m / N).
        tau_std: (n,) standard deviation of one torque sample over the window (N m / N).
        n_samples: number of samples averaged.
        max_speed: the largest joint speed seen in the window (rad/s).
        side_spread: (n,) the std of the sides' means (``read_joined``), or None.
    """

    t0: float
    t1: float
    q: np.ndarray
    tau: np.ndarray
    tau_std: np.ndarray
    n_samples: int
    max_speed: float
    side_spread: np.ndarray | None = None

    @property
    def tau_mean_std(self) -> np.ndarray:
        """(n,) std of the mean torque: tau_std / sqrt(n_samples), white noise assumed."""
        return self.tau_std / np.sqrt(self.n_samples)


def parse_windows(
    text: str, option: str = "--before", joined: bool = False
) -> list[tuple[float, ...]]:
    """``"T0:T1,T0:T1"`` (s) as a list of windows (t0, t1); InvalidInputError if malformed.

    With ``joined``, a window may be spans joined by ``+`` (``T0:T1+T2:T3``): one reading,
    the mean of its spans' means (``read_joined``), given as the flat tuple (t0, t1, t2, t3).
    """
    out = []
    for part in (p.strip() for p in str(text).split(",")):
        pieces = part.split("+") if joined else [part]
        bounds = _bounds([piece.split(":") for piece in pieces])
        if bounds is None:
            joins = " or spans joined by + (1.0:2.0+3.0:4.0)" if joined else ""
            raise InvalidInputError(
                f"{option} {text!r}: each window is T0:T1 in seconds from the log's start"
                f"{joins}, windows separated by commas (e.g. 1.0:2.0,5.5:6.5)"
            )
        for t0, t1 in zip(bounds[::2], bounds[1::2]):
            if not (np.isfinite(t0) and np.isfinite(t1) and t1 > t0):
                raise InvalidInputError(f"{option} window {part!r}: need finite T0 < T1")
        out.append(tuple(bounds))
    return out


def _bounds(numbers: list[list[str]]) -> list[float] | None:
    """The floats of spans' ``[T0, T1]`` texts, or None where one is not two numbers."""
    if any(len(n) != 2 for n in numbers):
        return None
    try:
        return [float(x) for n in numbers for x in n]
    except ValueError:
        return None


def spans(window: tuple[float, ...]) -> list[tuple[float, float]]:
    """The (t0, t1) spans of a window (one, or several joined by ``parse_windows``)."""
    return list(zip(window[::2], window[1::2]))


def joint_speed(time: np.ndarray, position: np.ndarray, span: float = SPEED_SPAN) -> np.ndarray:
    """(N,) largest joint speed at each sample: |q(t + span) - q(t)| / span, by joint.

    Within ``span`` of the end, the span looks backwards; a single sample has speed 0.
    """
    n = len(time)
    idx = np.arange(n)
    fwd = np.searchsorted(time, time + span)  # first sample a full span ahead
    ok = fwd < n
    bwd = np.searchsorted(time, time - span)  # where the span ahead runs out, look back
    lo = np.where(ok, idx, bwd)
    hi = np.where(ok, np.minimum(fwd, n - 1), idx)
    dt = time[hi] - time[lo]
    with np.errstate(divide="ignore", invalid="ignore"):
        v = np.abs(position[hi] - position[lo]).max(axis=1) / dt
    return np.where(dt > 0, v, 0.0)


def read_window(
    log: JointLog | WrenchLog,
    t0: float,
    t1: float,
    max_speed: float = MAX_SPEED,
    label: str = "window",
    readings: np.ndarray | None = None,
) -> StaticReading:
    """The averaged readings of ``log`` over [t0, t1] (s), checked to be static.

    ``readings``: (N, m) the samples to average, one row per log sample (a wrench log's
    ``wrench``); default the joint log's efforts.

    Raises:
        LogError: the window is not inside the log, or holds fewer than MIN_SAMPLES samples.
        NotStaticError: a joint moved faster than ``max_speed`` in it.
    """
    end = float(log.time[-1])
    if t0 < 0 or t1 > end + 1e-9 or t1 <= t0:
        raise LogError(
            f"{label} {t0:g}:{t1:g} s is outside the log ({log.source} runs 0:{end:.3f} s)"
        )
    sel = (log.time >= t0) & (log.time <= t1)
    n = int(sel.sum())
    if n < MIN_SAMPLES:
        raise LogError(
            f"{label} {t0:g}:{t1:g} s holds {n} sample(s); at least {MIN_SAMPLES} are needed"
        )
    speed = float(joint_speed(log.time[sel], log.position[sel]).max())
    if speed > max_speed:
        raise NotStaticError(
            f"{label} {t0:g}:{t1:g} s is not static: a joint moves at {speed:.3g} rad/s, above "
            f"the threshold {max_speed:g} rad/s; choose a window where the arm stands still"
        )
    samples = log.effort if readings is None else readings
    if samples is None:
        raise LogError(f"{log.source} has no efforts to average in {label} {t0:g}:{t1:g} s")
    tau = samples[sel]
    return StaticReading(
        t0=float(t0),
        t1=float(t1),
        q=log.position[sel].mean(axis=0),
        tau=tau.mean(axis=0),
        tau_std=tau.std(axis=0, ddof=1),
        n_samples=n,
        max_speed=speed,
    )


def read_joined(
    log: JointLog | WrenchLog,
    window: tuple[float, ...],
    max_speed: float = MAX_SPEED,
    label: str = "window",
    readings: np.ndarray | None = None,
) -> StaticReading:
    """One reading of a window of one or several spans (``parse_windows``'s ``joined``).

    Several spans (a pose approached from both sides, whose stuck friction has opposite
    signs) give the mean of their means, each span weighted alike: q, tau, a ``tau_std``
    whose ``tau_mean_std`` is that mean's std, sqrt(sum s_i^2 / n_i) / k, and the std of the
    spans' means (two sides: half their difference, the stuck friction). One span is
    ``read_window``'s reading.
    """
    parts = [read_window(log, t0, t1, max_speed, label, readings) for t0, t1 in spans(window)]
    if len(parts) == 1:
        return parts[0]
    n = sum(r.n_samples for r in parts)
    mean_std = np.sqrt(sum(r.tau_mean_std**2 for r in parts)) / len(parts)
    return StaticReading(
        t0=parts[0].t0,
        t1=parts[-1].t1,
        q=np.mean([r.q for r in parts], axis=0),
        tau=np.mean([r.tau for r in parts], axis=0),
        tau_std=mean_std * np.sqrt(n),
        n_samples=n,
        max_speed=max(r.max_speed for r in parts),
        side_spread=np.std([r.tau for r in parts], axis=0),
    )


def read_pairs(
    log: JointLog | WrenchLog,
    before: Sequence[tuple[float, ...]],
    after: Sequence[tuple[float, ...]],
    max_speed: float = MAX_SPEED,
    readings: np.ndarray | None = None,
) -> tuple[tuple[StaticReading, ...], tuple[StaticReading, ...]]:
    """(before readings, after readings) of paired windows (``read_joined``), or a LogError.

    ``before[i]`` is the empty arm at the pose of ``after[i]``; ``readings`` as
    ``read_window``'s.
    """
    if len(before) != len(after):
        raise LogError(
            f"{len(before)} --before window(s) but {len(after)} --after window(s): each "
            "before window pairs with the after window of the same pose (same count needed)"
        )
    if not before:
        raise LogError("no windows given: at least one before/after pair is needed")
    rb = tuple(read_joined(log, w, max_speed, f"before window {i}", readings)
               for i, w in enumerate(before))  # fmt: skip
    ra = tuple(read_joined(log, w, max_speed, f"after window {i}", readings)
               for i, w in enumerate(after))  # fmt: skip
    return rb, ra


def find_static_windows(
    log: JointLog | WrenchLog,
    max_speed: float = MAX_SPEED,
    min_duration: float = MIN_STATIC_S,
    split_at: float | None = None,
    guard: float = 0.25,
) -> list[tuple[float, float]]:
    """Windows (t0, t1) where every joint stays slower than ``max_speed`` for ``min_duration``.

    Args:
        log: the readings.
        max_speed: the static threshold (rad/s).
        min_duration: shortest window kept (s).
        split_at: a time (s, the grasp) that no window may span; windows are cut ``guard``
            seconds either side of it.
        guard: see ``split_at`` (s).
    """
    still = joint_speed(log.time, log.position) <= max_speed
    if split_at is not None:
        still &= np.abs(log.time - split_at) > guard
    edges = np.flatnonzero(np.diff(np.r_[0, still.astype(np.int8), 0]))
    out = []
    for a, b in zip(edges[::2], edges[1::2]):
        # the speed at sample i looks SPEED_SPAN ahead: trim the span at both ends
        t0, t1 = log.time[a] + SPEED_SPAN, log.time[b - 1] - SPEED_SPAN
        if t1 - t0 >= min_duration:
            out.append((float(t0), float(t1)))
    return out


def pair_by_configuration(
    log: JointLog,
    grasp_time: float,
    max_speed: float = MAX_SPEED,
    min_duration: float = MIN_STATIC_S,
    max_distance: float = 0.05,
) -> tuple[list[tuple[float, float]], list[tuple[float, float]]]:
    """Automatic windows: static windows before ``grasp_time`` paired with those after it.

    Each window after the grasp is paired with the unused window before it whose mean
    configuration is nearest (largest joint difference, rad), if within ``max_distance``.

    Returns:
        (before, after): lists of windows, before[i] pairs with after[i].

    Raises:
        LogError: no window before or after the grasp, or none pairs up.
    """
    if not 0.0 < grasp_time < log.duration:
        raise InvalidInputError(
            f"--grasp-time {grasp_time:g} s is outside the log (0:{log.duration:.3f} s)"
        )
    windows = find_static_windows(log, max_speed, min_duration, split_at=grasp_time)
    before = [w for w in windows if w[1] < grasp_time]
    after = [w for w in windows if w[0] > grasp_time]
    if not before or not after:
        raise LogError(
            f"found {len(before)} static window(s) before and {len(after)} after the grasp "
            f"at {grasp_time:g} s (static: joint speed below {max_speed:g} rad/s for "
            f"{min_duration:g} s); both are needed"
        )
    q_mean = [read_window(log, *w, max_speed=np.inf).q for w in before]
    used: set[int] = set()
    pairs = []
    for w in after:
        qa = read_window(log, *w, max_speed=np.inf).q
        dist = [
            np.inf if i in used else float(np.abs(qa - qb).max()) for i, qb in enumerate(q_mean)
        ]
        best = int(np.argmin(dist))
        if dist[best] <= max_distance:
            used.add(best)
            pairs.append((before[best], w))
    if not pairs:
        raise LogError(
            f"no static window after the grasp has a partner before it within {max_distance:g} "
            "rad of its configuration: measure before and after at the same poses"
        )
    return [p[0] for p in pairs], [p[1] for p in pairs]
