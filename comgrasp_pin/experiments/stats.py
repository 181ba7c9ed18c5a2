"""Small statistics for the reports: binned means and binomial confidence intervals."""

from __future__ import annotations

import numpy as np

THETA_BINS_DEG = (0.0, 2.5, 5.0, 7.5, 10.0, 12.5, 15.0, 20.0, 25.0, 30.0, 45.0, 60.0, 90.0)


def wilson_interval(successes: int, n: int, z: float = 1.96) -> tuple[float, float]:
    """95 % Wilson score interval (fractions) for ``successes`` out of ``n`` trials."""
    if n <= 0:
        return (0.0, 1.0)
    p = successes / n
    denom = 1.0 + z * z / n
    centre = (p + z * z / (2 * n)) / denom
    half = z * np.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / denom
    return (max(0.0, centre - half), min(1.0, centre + half))


def binned_mean(
    x: np.ndarray, y: np.ndarray, edges: tuple[float, ...] = THETA_BINS_DEG
) -> list[tuple[float, float, float, int]]:
    """(lo, hi, mean of y, count) for each bin [lo, hi) of x; mean is nan for empty bins."""
    x, y = np.asarray(x, float), np.asarray(y, float)
    out = []
    for lo, hi in zip(edges[:-1], edges[1:]):
        inside = (x >= lo) & (x < hi)
        count = int(inside.sum())
        out.append((lo, hi, float(y[inside].mean()) if count else float("nan"), count))
    return out
