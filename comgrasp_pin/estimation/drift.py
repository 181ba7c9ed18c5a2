"""The covariance of torque differences when the sensor drifts: a random walk in time.

A joint-torque sensor's offset wanders (temperature, the electronics): modelled as a random
walk W of ``drift_std`` N m / sqrt(s) per joint, independent between joints, on top of each
window's white noise. A static reading is W and the noise averaged over a time window; a
difference tau_after - tau_before is a weighted sum of window averages (+1 the held window,
-1 the empty one). Two averages over windows A and B share drift
drift_std^2 E[min(s, t)] (s, t uniform over A and B: Cov(W_s, W_t) = drift_std^2 min(s, t)),
so two poses' differences share as much as their intervals interleave in time, and a
difference grows with the time between its windows. ``difference_covariance`` gives the
(k n, k n) covariance that ``estimate_com(..., dtau_cov=...)`` takes.
"""

from __future__ import annotations

import numpy as np

from comgrasp_pin import validate
from comgrasp_pin.errors import InvalidInputError

_GRID = 48
"""Points per window in ``mean_min`` (its error is about a window's length / (6 _GRID))."""


def mean_min(a: tuple[float, float], b: tuple[float, float]) -> float:
    """E[min(s, t)] (s) for s, t uniform over the windows ``a``, ``b`` = (start, length) s."""
    grid = (np.arange(_GRID) + 0.5) / _GRID
    s, t = a[0] + a[1] * grid, b[0] + b[1] * grid
    return float(np.minimum(s[:, None], t[None, :]).mean())


def difference_weights(empty_of: list[int | None], n_empty: int) -> np.ndarray:
    """(k, k + n_empty) weights of k differences over the windows held_0..k-1, empty_0..n-1.

    Difference i is its held window minus the empty window ``empty_of[i]``, or, where that is
    None (the empty reading modelled), minus the mean of the empty windows (the offset they
    show).
    """
    k = len(empty_of)
    weights = np.zeros((k, k + n_empty))
    for i, j in enumerate(empty_of):
        weights[i, i] = 1.0
        if j is None:
            weights[i, k:] = -1.0 / n_empty
        else:
            weights[i, k + j] = -1.0
    return weights


def difference_covariance(
    windows: list[tuple[float, float]],
    white_std: np.ndarray,
    weights: np.ndarray,
    drift_std: float | np.ndarray,
) -> np.ndarray:
    """(k n, k n) covariance of k torque differences, pose-major (pose 0's n joints first).

    Args:
        windows: (start, length) of each averaging window (s, on one clock).
        white_std: (w, n) each window's standard error from white noise (N m).
        weights: (k, w) each difference as a weighted sum of the windows' averages (e.g.
            +1 on its held window and -1 on its empty one).
        drift_std: the random walk's std after one second (N m / sqrt(s)), one for every
            channel or (n,) one each (a wrist sensor's force and torque); 0: white noise
            only.
    """
    white = validate.real_array(white_std, "white_std")
    W = validate.real_array(weights, "weights")
    spans = [(float(start), float(length)) for start, length in windows]
    if white.ndim != 2 or W.ndim != 2 or white.shape[0] != len(spans) or W.shape[1] != len(spans):
        raise InvalidInputError(
            f"white_std must be (windows, joints) and weights (differences, windows) for "
            f"{len(spans)} windows, got {white.shape} and {W.shape}"
        )
    k, n = W.shape[0], white.shape[1]
    drift = np.broadcast_to(np.asarray(drift_std, dtype=float), (n,))
    if not (np.all(drift >= 0) and np.all(np.isfinite(white)) and np.all(np.isfinite(spans))):
        raise InvalidInputError("drift_std must be >= 0 and the windows and stds finite")
    M = np.array([[mean_min(u, v) for v in spans] for u in spans])
    blocks = np.zeros((k, n, k, n))
    for j in range(n):
        blocks[:, j, :, j] = W @ (drift[j] ** 2 * M + np.diag(white[:, j] ** 2)) @ W.T
    cov = blocks.reshape(k * n, k * n)
    return 0.5 * (cov + cov.T)
