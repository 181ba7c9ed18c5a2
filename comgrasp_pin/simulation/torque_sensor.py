"""A joint-torque sensor as a real one behaves: white noise, a constant bias and slow drift.

Sampled at every control step. The default noise (0.05 N m per sample) is that of a
joint-torque-sensor class arm; the experiments never use a noise-free sensor.
"""

from __future__ import annotations

import numpy as np

from comgrasp_pin.config import TorqueSensorConfig


class JointTorqueSensor:
    """Turns the drives' true torques into readings; one instance per simulated arm.

    Noise is drawn in blocks of about ``_BLOCK_VALUES`` numbers (one draw per control step
    would cost more than the physics step itself).
    """

    _BLOCK_VALUES = 24_576

    def __init__(self, n: int, config: TorqueSensorConfig, seed: int | None = None):
        self.config = config
        self._rng = np.random.default_rng(seed)
        self._drift = np.zeros(n)
        self._n = n
        self._noise = np.empty((0, 2 * n))
        self._next = 0

    def read(self, tau_true: np.ndarray, dt: float) -> np.ndarray:
        """One sample (N m) of the (n,) true torques, ``dt`` seconds after the last one."""
        c = self.config
        if self._next >= len(self._noise):
            rows = max(1, self._BLOCK_VALUES // (2 * self._n))
            self._noise = self._rng.standard_normal((rows, 2 * self._n))
            self._next = 0
        draw = self._noise[self._next]
        self._next += 1
        reading = tau_true + c.bias
        if c.drift_std > 0:
            self._drift += c.drift_std * np.sqrt(dt) * draw[self._n :]
            reading += self._drift
        if c.noise_std > 0:
            reading += c.noise_std * draw[: self._n]
        return reading
