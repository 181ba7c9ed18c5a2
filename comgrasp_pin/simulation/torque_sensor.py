"""Joint-torque readings as real arms report them, from the drives' true torques.

Two classes (``TorqueSensorConfig.kind``; ``make_torque_sensor`` picks one):

- ``JointTorqueSensor`` ("link"): a torque sensor on the link side of the gear (Franka,
  KUKA iiwa): white noise, a constant bias, an offset per joint drawn once per episode, and
  slow drift (a random walk). The drives' friction does not reach it.
- ``CurrentTorqueSensor`` ("current"): the torque a UR CB3 infers from its motor currents:
  all of the above plus the drives' friction, Coulomb and viscous. At rest, the friction
  holds what it held when the joint stopped: the reading keeps the sign of the last motion.

Sampled at every control step. The default (0.05 N m white noise per sample) is that of a
joint-torque-sensor class arm; the experiments never use a noise-free sensor.
"""

from __future__ import annotations

import numpy as np

from comgrasp_pin.config import TorqueSensorConfig
from comgrasp_pin.errors import InvalidInputError


def _offset_rng(seed: int | None) -> np.random.Generator:
    """The generator of the per-episode errors: apart from the noise's, so that the noise
    of a given seed is the same with and without them."""
    return np.random.default_rng(None if seed is None else (int(seed), 13))


class JointTorqueSensor:
    """Turns the drives' true torques into readings; one instance per simulated arm.

    Noise is drawn in blocks of about ``_BLOCK_VALUES`` numbers (one draw per control step
    would cost more than the physics step itself). Samples nobody reads need not be formed:
    ``skip`` advances the noise stream and the drift over them, and ``read_many`` forms a
    window of samples at once; both give, to the bit, what a ``read`` per step would.

    Attributes:
        offsets: (n,) each joint's offset in this episode (N m), from ``config.offset_std``.
        needs_velocity: whether a reading depends on the joint velocities (then every control
            step must be read, as the friction remembers the last motion).
    """

    _BLOCK_VALUES = 24_576
    needs_velocity = False

    def __init__(self, n: int, config: TorqueSensorConfig, seed: int | None = None):
        self.config = config
        self._rng = np.random.default_rng(seed)
        self._drift = np.zeros(n)
        self._n = n
        self._noise = np.empty((0, 2 * n))
        self._next = 0
        self._episode_rng = _offset_rng(seed)
        self.offsets = np.zeros(n)
        if config.offset_std > 0:
            self.offsets = config.offset_std * self._episode_rng.standard_normal(n)

    def read(self, tau_true: np.ndarray, dt: float, qd: np.ndarray | None = None) -> np.ndarray:
        """One sample (N m) of the (n,) true torques, ``dt`` seconds after the last one;
        ``qd`` (n,) the joint velocities (rad/s), which only a current-based reading uses."""
        c = self.config
        if self._next >= len(self._noise):
            self._refill()
        draw = self._noise[self._next]
        self._next += 1
        reading = tau_true + c.bias
        if c.offset_std > 0:
            reading = reading + self.offsets
        if c.drift_std > 0:
            self._drift += c.drift_std * np.sqrt(dt) * draw[self._n :]
            reading += self._drift
        if c.noise_std > 0:
            reading += c.noise_std * draw[: self._n]
        return reading

    def read_many(
        self, tau_true: np.ndarray, dt: float, qd: np.ndarray | None = None
    ) -> np.ndarray:
        """(N, n) samples of N consecutive control steps' true torques ``tau_true`` (N, n),
        ``dt`` seconds apart: the values N calls of ``read`` return."""
        c = self.config
        draws = self._take(len(tau_true))
        reading = tau_true + c.bias
        if c.offset_std > 0:
            reading = reading + self.offsets
        if c.drift_std > 0:
            reading += self._walk(draws, dt)
        if c.noise_std > 0:
            reading += c.noise_std * draws[:, : self._n]
        return reading

    def skip(self, steps: int, dt: float) -> None:
        """Advance over ``steps`` control steps whose samples nobody reads (noise stream and
        drift as ``steps`` calls of ``read`` would leave them)."""
        if self.needs_velocity:
            raise InvalidInputError(
                "a current-based reading depends on every step's joint velocities: read each "
                "step (skip is for link-side sensors only)"
            )
        if steps > 0:
            draws = self._take(steps)
            if self.config.drift_std > 0:
                self._walk(draws, dt)

    def _walk(self, draws: np.ndarray, dt: float) -> np.ndarray:
        """(N, n) the drift after each of N steps (summed one step at a time, as ``read``)."""
        steps = self.config.drift_std * np.sqrt(dt) * draws[:, self._n :]
        path = np.cumsum(np.vstack([self._drift, steps]), axis=0)[1:]
        self._drift = path[-1].copy()
        return path

    def _take(self, count: int) -> np.ndarray:
        """(count, 2n) the next rows of the noise stream, in the blocks ``read`` draws."""
        parts, need = [], count
        while need > 0:
            if self._next >= len(self._noise):
                self._refill()
            part = self._noise[self._next : self._next + need]
            self._next += len(part)
            need -= len(part)
            parts.append(part)
        return parts[0] if len(parts) == 1 else np.concatenate(parts)

    def _refill(self) -> None:
        rows = max(1, self._BLOCK_VALUES // (2 * self._n))
        self._noise = self._rng.standard_normal((rows, 2 * self._n))
        self._next = 0


class CurrentTorqueSensor(JointTorqueSensor):
    """A current-based reading (UR CB3 style): the link-side errors plus the drives' friction.

    Attributes:
        friction_sign: (n,) +-1, the direction each joint last moved in (at first, drawn
            per episode: how it came to rest is not known).
    """

    needs_velocity = True

    def __init__(self, n: int, config: TorqueSensorConfig, seed: int | None = None):
        super().__init__(n, config, seed)
        self._coulomb = _per_joint(config.coulomb, n, "coulomb")
        self._viscous = _per_joint(config.viscous, n, "viscous")
        self.friction_sign = self._episode_rng.choice([-1.0, 1.0], size=n)

    def read(self, tau_true: np.ndarray, dt: float, qd: np.ndarray | None = None) -> np.ndarray:
        reading = super().read(tau_true, dt)
        if qd is None:
            qd = np.zeros(self._n)
        moving = np.abs(qd) > self.config.moving_speed
        self.friction_sign = np.where(moving, np.sign(qd), self.friction_sign)
        return reading + self._coulomb * self.friction_sign + self._viscous * qd

    def read_many(
        self, tau_true: np.ndarray, dt: float, qd: np.ndarray | None = None
    ) -> np.ndarray:
        reading = super().read_many(tau_true, dt)
        if qd is None:
            qd = np.zeros_like(reading)
        # Each step's sign is that of the last step up to it where the joint moved.
        moving = np.abs(qd) > self.config.moving_speed
        last = np.where(moving, np.arange(len(qd))[:, None], -1)
        np.maximum.accumulate(last, axis=0, out=last)
        moved_sign = np.sign(np.take_along_axis(qd, np.maximum(last, 0), axis=0))
        signs = np.where(last >= 0, moved_sign, self.friction_sign)
        self.friction_sign = signs[-1].copy()
        return reading + self._coulomb * signs + self._viscous * qd


def _per_joint(values: tuple[float, ...], n: int, name: str) -> np.ndarray:
    """(n,) from a per-joint tuple (empty: zeros)."""
    if not values:
        return np.zeros(n)
    if len(values) != n:
        raise InvalidInputError(f"{name} has {len(values)} values; the arm has {n} joints")
    return np.asarray(values, dtype=float)


def make_torque_sensor(n: int, config: TorqueSensorConfig, seed: int | None = None):
    """The sensor of ``config.kind`` ("link" or "current") for an arm of ``n`` joints."""
    cls = CurrentTorqueSensor if config.kind == "current" else JointTorqueSensor
    return cls(n, config, seed)
