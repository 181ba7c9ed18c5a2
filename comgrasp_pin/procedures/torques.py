"""Static torque measurements as a real arm needs them: the approach, the window, the noise.

- ``arrive``: reach a measurement pose the same way every time (from the same side in every
  joint). A current-based reading (UR CB3) holds the friction of the last motion: reached
  from one side before the grasp and from the other after, the difference of the two
  readings carries up to twice the drives' Coulomb friction (1-3 N m here), which no
  average removes. Reached from the same side, it cancels.
- ``measure``: average the torques over a window long enough for the noise measured in it
  (``TrialConfig.window_sem``); the samples' spread, not the sensor's data sheet, says how
  long that is.
- ``pair_noise``: the noise of the torque differences as the estimator needs it: the
  sensor's white noise (the ideal preset's), or the windows' measured spread and the
  sensor's drift as a full covariance: a random walk shared by every window, so that two
  poses' differences whose empty-to-held intervals overlap in time share that much drift
  (generalised least squares then takes most of it out where the poses differ).

Policy as pure functions where it can be; ``Cell`` does the moving. SI units.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from comgrasp_pin.config import EpisodeConfig, TrialConfig
from comgrasp_pin.estimation.drift import difference_covariance
from comgrasp_pin.procedures.cell import Cell, TorqueMeasurement


def arrive(cell: Cell, q: np.ndarray, trial: TrialConfig, duration: float | None = None,
           settle: float = 0.0) -> None:  # fmt: skip
    """Move to the measurement configuration ``q`` (rad) in ``duration`` s (None: the
    shortest), then hold ``settle`` s. With ``trial.approach_deg`` > 0, by way of ``q`` plus
    that much in every joint, the last ``approach_time`` s: every joint then comes to rest
    moving the same way, before the grasp and after it."""
    if trial.approach_deg > 0:
        cell.move_to(q + np.radians(trial.approach_deg), duration=duration)
        duration = trial.approach_time
    cell.move_to(q, duration=duration, settle=settle)


def combine(a: TorqueMeasurement, b: TorqueMeasurement) -> TorqueMeasurement:
    """One measurement of the samples of two windows at the same configuration, back to
    back: means and variances weighted by their sample counts."""
    n = a.n_samples + b.n_samples
    wa, wb = a.n_samples / n, b.n_samples / n
    var = (a.n_samples**2 * a.std_error**2 + b.n_samples**2 * b.std_error**2) / n**2
    return TorqueMeasurement(wa * a.tau + wb * b.tau, np.sqrt(var), wa * a.q + wb * b.q, n,
                             a.duration + b.duration, a.time)  # fmt: skip


def extra_window(measured: TorqueMeasurement, sem: float, window_max: float) -> float:
    """How much longer (s) to average after ``measured`` for a standard error of ``sem``
    (N m) in every joint, the whole window at most ``window_max`` s; 0: long enough (or no
    target, ``sem`` 0). The noise is white: the standard error falls as 1 / sqrt(time)."""
    worst = float(np.max(measured.std_error))
    if sem <= 0 or worst <= sem or not np.isfinite(worst):
        return 0.0
    needed = measured.duration * (worst / sem) ** 2
    return max(0.0, min(needed, window_max) - measured.duration)


def measure(cell: Cell, settle: float, trial: TrialConfig) -> TorqueMeasurement:
    """Settle ``settle`` s, average ``trial.window`` s, and on as long as the measured
    noise needs (``extra_window``)."""
    first = cell.measure_torques(settle, trial.window)
    more = extra_window(first, trial.window_sem, trial.window_max)
    return first if more <= 0 else combine(first, cell.measure_torques(0.0, more))


@dataclass(frozen=True)
class PairNoise:
    """The noise of the stacked torque differences tau_after - tau_before, for
    ``estimate_com``: one of ``std`` (each reading's std, N m, the differences independent)
    or ``cov`` ((k n, k n) covariance of the differences, pose-major, N m^2).
    """

    std: float | None
    cov: np.ndarray | None

    def first(self, k: int, n: int) -> PairNoise:
        """The noise of the first ``k`` poses' differences (``n`` joints)."""
        return self if self.cov is None else PairNoise(None, self.cov[: k * n, : k * n])

    def subset(self, poses: list[int], n: int) -> PairNoise:
        """The noise of the differences of ``poses`` only."""
        if self.cov is None:
            return self
        rows = np.concatenate([np.arange(i * n, (i + 1) * n) for i in poses])
        return PairNoise(None, self.cov[np.ix_(rows, rows)])


def drift_cov(before: list, after: list, drift_std: float) -> np.ndarray:
    """(k n, k n) covariance of the k differences' (after - before) white noise and drift
    (``estimation.drift``). Each difference is its held window minus its empty window;
    where ``before`` is None (tau_before from the model, carried by the measured poses'
    mean offset), minus the mean of the measured poses' empty windows."""
    measured = [b for b in before if b is not None]
    windows = [*after, *measured]
    k = len(after)
    weights = np.zeros((k, len(windows)))
    column = k  # the next measured empty window's
    for i, b in enumerate(before):
        weights[i, i] = 1.0
        if b is not None:
            weights[i, column] = -1.0
            column += 1
        else:
            weights[i, k:] = -1.0 / len(measured)
    spans = [(float(m.time), float(m.duration)) for m in windows]
    white = np.array([np.asarray(m.std_error, dtype=float) for m in windows])
    return difference_covariance(spans, white, weights, drift_std)


def pair_noise(before: list, after: list, config: EpisodeConfig) -> PairNoise:
    """The noise of the torque differences for the estimator.

    ``before``, ``after``: the TorqueMeasurements at each pose (``before`` None where the
    model gave tau_before). ``trial.torque_std_from``: "spec", the sensor's white noise over
    the samples averaged (the ideal preset's; ``pair_std``); "measured", the windows'
    spread and the sensor's drift (``drift_std``, from its data sheet) with its
    correlation across poses and windows (``drift_cov``), where every time is known and
    some empty window was measured; else per joint as ``pair_std``.
    """
    trial, torque = config.trial, config.sensors.torque
    timed = all(np.isfinite(m.time) for m in [*before, *after] if m is not None)
    if trial.torque_std_from == "measured" and timed and any(b is not None for b in before):
        return PairNoise(None, drift_cov(before, after, torque.drift_std))
    std = pair_std(before, after, config)
    if isinstance(std, float):
        return PairNoise(std, None)
    return PairNoise(None, np.diag(np.tile(2.0 * std**2, len(after))))


def pair_std(before: list, after: list, config: EpisodeConfig) -> float | np.ndarray:
    """The std of each averaged reading (N m; scalar, or (6,) per joint) for the estimator.

    ``before``, ``after``: the TorqueMeasurements at each pose (``before`` None where the
    model gave tau_before). ``trial.torque_std_from``: "spec", the sensor's white noise over
    the samples averaged (the ideal preset's); "measured", per joint, the windows' spread
    and the sensor's drift (``drift_std``, from its data sheet) over the time between the
    empty and the held window: a random walk adds drift^2 * elapsed to a difference.
    """
    trial, torque = config.trial, config.sensors.torque
    modelled = trial.tau_before != "measured"
    if trial.torque_std_from == "spec":
        n_std = torque.noise_std / np.sqrt(after[0].n_samples)
        return max(n_std * (np.sqrt(0.5) if modelled else 1.0), 1e-6)
    variances = []
    for b, a in zip(before, after, strict=True):
        if b is None:  # one reading: its variance is the difference's
            variances.append(0.5 * a.std_error**2)
            continue
        elapsed = abs(a.time - b.time)
        diff = b.std_error**2 + a.std_error**2 + torque.drift_std**2 * elapsed
        variances.append(0.5 * diff)
    return np.maximum(np.sqrt(np.mean(variances, axis=0)), 1e-6)
