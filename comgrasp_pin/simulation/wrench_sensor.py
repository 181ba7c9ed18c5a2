"""The wrist force/torque sensor: MuJoCo's true wrench at the ``ft_sensor`` site, read as a
strain-gauge sensor reports it.

- The truth: MuJoCo's ``force`` and ``torque`` sensors on the site (``world.add_ft_sensor``)
  give the wrench the arm applies to the gripper's subtree (gripper, fingers, what they
  hold, contacts included), in the site's frame, torque about its origin. The sensor's own
  convention (``robot_io.log_files.wrench_log``) is the other side of that interaction: what the
  tool
  applies to the sensor, at rest f = m g and tau = c x m g. ``wrench_from_sensors`` turns
  the first into the second (a sign).
- The errors (``WrenchSensorConfig``): a constant bias, an offset drawn per episode, a
  random-walk drift, a temperature-like drift (a rate drawn per episode) and white noise.
  Samples are indexed from the world's start: sample j is taken at t = j / rate_hz.

RNG discipline: the sensor has its own streams, ``(seed, 29)`` for the noise and the drift's
steps and ``(seed, 31)`` for the per-episode offset and drift rate, so that adding it (or
reading it or not) changes no other random draw of a run. Reading is also independent of the
reading pattern: sample j's noise and drift are the stream's j-th row whether or not the
samples before it were read (the unread ones are drawn and dropped), so a wrench measured
after a torque-only window is the same as after one that read the wrench too.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from comgrasp_pin.config import WrenchSensorConfig
from comgrasp_pin.errors import InvalidInputError

FORCE_TORQUE_STREAMS = (29, 31)
"""The second word of the sensor's two seeds: (noise and drift steps, per-episode errors)."""


def wrench_from_sensors(site_readings: np.ndarray) -> np.ndarray:
    """(..., 6) the wrench of ``robot_io.log_files.wrench_log``'s convention (the tool's on the
    sensor:
    force N, torque N m, site frame) from MuJoCo's force and torque sensors' readings
    (..., 6) at the site (the arm's on the tool's subtree): their negative."""
    return -np.asarray(site_readings, dtype=float)


@dataclass(frozen=True)
class WrenchMeasurement:
    """The wrist sensor's readings averaged over a window at one arm configuration.

    Attributes:
        wrench: (6,) mean reading: force (N) and torque (N m) the tool side applies to the
            sensor, in ``sensor_frame`` (``robot_io.log_files.wrench_log``'s convention).
        std_error: (6,) standard error of the mean, from the samples' spread (N, N m); inf
            with a single sample.
        q: (n,) the arm's configuration during the window (rad), its mean.
        n_samples: number of sensor samples averaged (at the sensor's rate).
        duration: length of the window (s).
        time: the robot's clock when the window began (s).
        sensor_frame: the URDF frame of the wrench ("ft_sensor").
    """

    wrench: np.ndarray
    std_error: np.ndarray
    q: np.ndarray
    n_samples: int
    duration: float
    time: float
    sensor_frame: str = "ft_sensor"


class WrenchSensor:
    """Turns true wrenches (the wrench-log convention) into readings; one per episode.

    Attributes:
        config: the error model.
        offset: (6,) the constant part of every reading in this episode: ``config.bias``
            plus the offset drawn from ``config.bias_std`` (N, N m).
        drift_rate: (6,) this episode's temperature-like drift rate (N/s, N m/s).
        period: time between samples (s), 1 / ``config.rate_hz``.
    """

    _CHUNK = 65_536  # rows drawn at once when skipping unread samples

    def __init__(self, config: WrenchSensorConfig, seed: int | None = None):
        self.config = config
        streams = [None if seed is None else (int(seed), s) for s in FORCE_TORQUE_STREAMS]
        self._rng = np.random.default_rng(streams[0])
        episode = np.random.default_rng(streams[1])
        self._noise_std = _per_axis(config.noise_std)
        self._step_std = _per_axis(config.drift_std) * np.sqrt(1.0 / config.rate_hz)
        self.offset = np.asarray(config.bias, dtype=float) + _per_axis(
            config.bias_std
        ) * episode.standard_normal(6)
        self.drift_rate = _per_axis(config.drift_rate_std) * episode.standard_normal(6)
        self.period = 1.0 / config.rate_hz
        self._next = 0  # the first sample not drawn yet
        self._drift = np.zeros(6)  # the random walk after sample _next - 1

    def read(self, indices: np.ndarray, wrench_true: np.ndarray) -> np.ndarray:
        """(N, 6) readings of samples ``indices`` (N,) (increasing integers, none read
        before) from their true wrenches ``wrench_true`` (N, 6) (N, N m, sensor frame, the
        wrench-log convention). Sample j is taken at ``j * period`` s.

        Raises:
            InvalidInputError: indices not increasing, already read, or shapes that differ.
        """
        idx = np.asarray(indices, dtype=np.int64)
        truth = np.asarray(wrench_true, dtype=float)
        if idx.ndim != 1 or truth.shape != (len(idx), 6) or len(idx) == 0:
            raise InvalidInputError(
                f"indices must be (N,) and wrench_true (N, 6), N >= 1; got {idx.shape} and "
                f"{truth.shape}"
            )
        if idx[0] < self._next or np.any(np.diff(idx) <= 0):
            raise InvalidInputError(
                f"sample indices must increase and start at {self._next} or later (the "
                f"samples before it were read or passed); got {idx[0]}..{idx[-1]}"
            )
        self._skip(int(idx[0]) - self._next)
        rows = self._rng.standard_normal((int(idx[-1] - idx[0]) + 1, 12))
        path = self._walk(rows[:, 6:])
        self._next = int(idx[-1]) + 1
        pick = idx - idx[0]
        t = idx * self.period
        return (truth + self.offset + path[pick] + self.drift_rate * t[:, None]
                + self._noise_std * rows[pick, :6])  # fmt: skip

    def _walk(self, draws: np.ndarray) -> np.ndarray:
        """(N, 6) the random walk after each of N samples (one step each, summed in order,
        so that any split of the samples gives the same bits)."""
        path = np.cumsum(np.vstack([self._drift, self._step_std * draws]), axis=0)[1:]
        self._drift = path[-1].copy()
        return path

    def _skip(self, count: int) -> None:
        """Draw and drop ``count`` unread samples (their noise; their drift steps count)."""
        while count > 0:
            rows = self._rng.standard_normal((min(count, self._CHUNK), 12))
            self._walk(rows[:, 6:])
            self._next += len(rows)
            count -= len(rows)


def _per_axis(pair: tuple[float, float]) -> np.ndarray:
    """(6,) a (force, torque) pair spread over the three axes of each."""
    return np.repeat(np.asarray(pair, dtype=float), 3)


def steps_per_sample(config: WrenchSensorConfig, dt: float) -> int:
    """How many simulation steps of ``dt`` (s) one sensor period spans.

    Raises:
        InvalidInputError: the sensor's rate does not divide the simulation's.
    """
    k = round(1.0 / (config.rate_hz * dt))
    if k < 1 or abs(k * config.rate_hz * dt - 1.0) > 1e-9:
        raise InvalidInputError(
            f"the wrist sensor's rate_hz ({config.rate_hz}) must divide the simulation's "
            f"{1.0 / dt:g} Hz"
        )
    return k


def window_measurement(
    sensor: WrenchSensor,
    wrench_true: np.ndarray,
    first_step: int,
    k: int,
    q: np.ndarray,
    dt: float,
    time: float,
) -> WrenchMeasurement:
    """The sensor's mean over a window of simulation steps.

    Args:
        sensor: the episode's sensor.
        wrench_true: (n, 6) the true wrench (wrench-log convention) at each of the window's
            n steps, the first at step ``first_step`` (the simulation's step count of its
            state: time / dt).
        k: steps per sensor sample (``steps_per_sample``); a step s is sampled when
            s % k == 0 (a window without one takes its last step as a sample).
        q: (n_joints,) the mean configuration over the window (rad).
        dt: the simulation's step (s).
        time: the simulation's clock when the window began (s).
    """
    steps = first_step + np.arange(len(wrench_true))
    rows = np.flatnonzero(steps % k == 0)
    if len(rows) == 0:
        rows = np.array([len(wrench_true) - 1])
    indices = -(-steps[rows] // k)  # a last step between samples counts as the next one
    readings = sensor.read(indices, wrench_true[rows])
    n = len(readings)
    std_error = readings.std(axis=0, ddof=1) / np.sqrt(n) if n > 1 else np.full(6, np.inf)
    return WrenchMeasurement(readings.mean(axis=0), std_error, q, n, len(wrench_true) * dt, time)
