"""Static torque measurements as a real arm needs them: the approach, the window, the noise.

- ``arrive``: reach a measurement pose the same way every time (from the same side in every
  joint). A current-based reading (UR CB3) holds the friction of the last motion: reached
  from one side before the grasp and from the other after, the difference of the two
  readings carries up to twice the drives' Coulomb friction (1-3 N m here), which no
  average removes. Reached from the same side, it cancels.
- ``measure``: average the torques over a window long enough for the noise measured in it
  (``TrialConfig.window_sem``); the samples' spread, not the sensor's data sheet, says how
  long that is.
- ``pair_std``: the std of each averaged reading as the estimator needs it (a difference of
  two has twice its variance): the windows' measured spread and the sensor's drift over the
  time between the empty and the held window.

Policy as pure functions where it can be; ``Cell`` does the moving. SI units.
"""

from __future__ import annotations

import numpy as np

from comgrasp_pin.config import EpisodeConfig, TrialConfig
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
