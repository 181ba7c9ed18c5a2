"""Smooth joint-space trajectories (pure numpy).

A ``Quintic`` goes from q0 to q1 at rest at both ends with the minimum-jerk profile
s(u) = 10u^3 - 15u^4 + 6u^5, u = t / T. Its peak speed is 15/8 |dq| / T and its peak
acceleration 10 / sqrt(3) |dq| / T^2, so ``min_duration`` gives the shortest T that keeps
every joint within its velocity and acceleration limits. Units: rad (or m), s.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from comgrasp_pin.errors import InvalidInputError

PEAK_VELOCITY = 15.0 / 8.0  # max ds/du of the quintic
PEAK_ACCELERATION = 10.0 / np.sqrt(3.0)  # max d2s/du2 of the quintic


def min_duration(
    q0: np.ndarray,
    q1: np.ndarray,
    v_max: float | np.ndarray,
    a_max: float | np.ndarray,
    t_min: float = 0.1,
) -> float:
    """Shortest duration (s) of a quintic from q0 to q1 (n,) within v_max and a_max
    (scalars or (n,), per joint, rad/s and rad/s^2); at least ``t_min``."""
    dq = np.abs(np.asarray(q1, float) - np.asarray(q0, float))
    t_v = PEAK_VELOCITY * dq / np.asarray(v_max, float)
    t_a = np.sqrt(PEAK_ACCELERATION * dq / np.asarray(a_max, float))
    return float(max(t_min, np.max(t_v), np.max(t_a)))


def _profile(u: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Minimum-jerk s(u), ds/du, d2s/du2 for u in [0, 1]."""
    u = np.clip(u, 0.0, 1.0)
    s = u**3 * (10.0 - 15.0 * u + 6.0 * u**2)
    ds = 30.0 * u**2 * (1.0 - u) ** 2
    dds = 60.0 * u * (1.0 - u) * (1.0 - 2.0 * u)
    return s, ds, dds


@dataclass(frozen=True)
class Quintic:
    """Rest-to-rest minimum-jerk motion from q0 to q1 (n,) in ``duration`` seconds."""

    q0: np.ndarray
    q1: np.ndarray
    duration: float

    def __post_init__(self) -> None:
        q0, q1 = np.asarray(self.q0, float), np.asarray(self.q1, float)
        if q0.shape != q1.shape or q0.ndim != 1:
            raise InvalidInputError(
                f"q0 and q1 must be (n,) of the same n, got {q0.shape}, {q1.shape}"
            )
        if not (np.all(np.isfinite(q0)) and np.all(np.isfinite(q1))):
            raise InvalidInputError("q0 and q1 must be finite")
        if not self.duration > 0.0:
            raise InvalidInputError(f"duration must be > 0 s, got {self.duration}")
        object.__setattr__(self, "q0", q0)
        object.__setattr__(self, "q1", q1)

    @classmethod
    def fastest(
        cls,
        q0: np.ndarray,
        q1: np.ndarray,
        v_max: float | np.ndarray,
        a_max: float | np.ndarray,
    ) -> Quintic:
        """The quintic of ``min_duration``."""
        return cls(q0, q1, min_duration(q0, q1, v_max, a_max))

    def sample(self, t: float | np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Position, velocity, acceleration at time(s) ``t`` (s): each (n,) for a scalar t,
        (k, n) for (k,) times. Clamped to the end points outside [0, duration]."""
        t = np.asarray(t, float)
        T = self.duration
        s, ds, dds = _profile(t / T)
        dq = self.q1 - self.q0
        s, ds, dds = (np.expand_dims(a, -1) for a in (s, ds, dds))
        return self.q0 + s * dq, ds * dq / T, dds * dq / T**2

    def times(self, dt: float) -> np.ndarray:
        """(k,) sample times from 0 to duration inclusive, step ``dt`` (s)."""
        k = max(1, int(np.ceil(self.duration / dt)))
        return np.linspace(0.0, self.duration, k + 1)
