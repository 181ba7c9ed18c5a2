"""Small statistics for the reports: bins of the tilt, means with t intervals, binomial
intervals, calibration of a stated standard deviation (z scores, coverage) and paired
differences. NumPy and the standard library only (no SciPy)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from comgrasp_pin.errors import InvalidInputError

THETA_BINS_DEG = (0.0, 2.5, 5.0, 7.5, 10.0, 12.5, 15.0, 20.0, 25.0, 30.0, 45.0, 60.0, 90.0)
"""|θ| bins of the accuracy table and figure (deg): fine in the paper's range (0-30)."""
CALIBRATION_BINS_DEG = (0.0, 5.0, 10.0, 15.0, 20.0, 25.0, 30.0, 60.0, 90.0)
"""|θ| bins of the calibration table and figure (deg)."""
COMPARISON_RANGES_DEG = (0.0, 10.0, 20.0, 30.0, 60.0, 90.0)
"""|θ| ranges of the method comparison (deg)."""

Z_68 = 1.0
"""Half width of the "68 %" interval in standard deviations: ±1σ holds 68.27 % of N(0, 1)."""
Z_95 = 1.959963984540054
"""Half width of the 95 % interval in standard deviations (the 97.5 % normal quantile)."""


def bin_masks(x: np.ndarray, edges: Sequence[float]) -> list[tuple[float, float, np.ndarray]]:
    """(lo, hi, mask of x in the bin) for each bin; bins are [lo, hi) except the last,
    which is [lo, hi] so that a value on the top edge (a tilt of exactly 90 deg) counts."""
    x = np.asarray(x, float)
    out = []
    last = len(edges) - 2
    for k, (lo, hi) in enumerate(zip(edges[:-1], edges[1:])):
        inside = (x >= lo) & ((x < hi) | ((x == hi) if k == last else False))
        out.append((float(lo), float(hi), inside))
    return out


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
    x: np.ndarray, y: np.ndarray, edges: Sequence[float] = THETA_BINS_DEG
) -> list[tuple[float, float, float, int]]:
    """(lo, hi, mean of y, count) for each bin of x (see ``bin_masks``); mean is nan for
    empty bins."""
    y = np.asarray(y, float)
    out = []
    for lo, hi, inside in bin_masks(x, edges):
        count = int(inside.sum())
        out.append((lo, hi, float(y[inside].mean()) if count else float("nan"), count))
    return out


# --- Student's t quantile (no SciPy): regularised incomplete beta, then bisection ---------


def _beta_cf(a: float, b: float, x: float) -> float:
    """Continued fraction of the incomplete beta function (modified Lentz)."""
    tiny, eps = 1e-300, 1e-15
    qab, qap, qam = a + b, a + 1.0, a - 1.0
    c, d = 1.0, 1.0 - qab * x / qap
    d = 1.0 / (d if abs(d) > tiny else tiny)
    h = d
    for m in range(1, 500):
        m2 = 2 * m
        for aa in (
            m * (b - m) * x / ((qam + m2) * (a + m2)),
            -(a + m) * (qab + m) * x / ((a + m2) * (qap + m2)),
        ):
            d = 1.0 + aa * d
            d = 1.0 / (d if abs(d) > tiny else tiny)
            c = 1.0 + aa / c
            c = c if abs(c) > tiny else tiny
            h *= d * c
        if abs(d * c - 1.0) < eps:
            break
    return h


def _betainc(a: float, b: float, x: float) -> float:
    """Regularised incomplete beta function I_x(a, b)."""
    if x <= 0.0:
        return 0.0
    if x >= 1.0:
        return 1.0
    front = math.exp(
        math.lgamma(a + b) - math.lgamma(a) - math.lgamma(b) + a * math.log(x) + b * math.log1p(-x)
    )
    if x < (a + 1.0) / (a + b + 2.0):
        return front * _beta_cf(a, b, x) / a
    return 1.0 - front * _beta_cf(b, a, 1.0 - x) / b


def t_cdf(t: float, df: float) -> float:
    """P(T <= t) for Student's t with ``df`` degrees of freedom."""
    tail = 0.5 * _betainc(0.5 * df, 0.5, df / (df + t * t))
    return 1.0 - tail if t >= 0 else tail


def t_quantile(p: float, df: float) -> float:
    """The ``p`` quantile of Student's t with ``df`` > 0 degrees of freedom (bisection on
    ``t_cdf``, to 1e-10)."""
    if not 0.0 < p < 1.0 or df <= 0:
        raise InvalidInputError(f"t_quantile needs 0 < p < 1 and df > 0, got p={p}, df={df}")
    if p < 0.5:
        return -t_quantile(1.0 - p, df)
    lo, hi = 0.0, 1.0
    while t_cdf(hi, df) < p:
        hi *= 2.0
    while hi - lo > 1e-10 * max(1.0, hi):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if t_cdf(mid, df) < p else (lo, mid)
    return 0.5 * (lo + hi)


# --- means with confidence intervals ------------------------------------------------------


@dataclass(frozen=True)
class MeanCI:
    """The mean of ``n`` values and its two-sided t confidence interval (nan when n < 2)."""

    mean: float
    lo: float
    hi: float
    n: int


def mean_ci(values: Sequence[float] | np.ndarray, level: float = 0.95) -> MeanCI:
    """Mean and its t interval: mean ± t_{(1+level)/2, n-1} · s / sqrt(n), s the sample
    standard deviation (ddof 1). Non-finite values are ignored."""
    v = np.asarray(values, float)
    v = v[np.isfinite(v)]
    n = len(v)
    if n == 0:
        return MeanCI(float("nan"), float("nan"), float("nan"), 0)
    mean = float(v.mean())
    if n < 2:
        return MeanCI(mean, float("nan"), float("nan"), 1)
    half = t_quantile(0.5 * (1.0 + level), n - 1) * float(v.std(ddof=1)) / math.sqrt(n)
    return MeanCI(mean, mean - half, mean + half, n)


@dataclass(frozen=True)
class BinSeries:
    """Per-bin means of y over bins of x, ready to plot: nan where a bin is empty, so that
    a line drawn through them breaks there instead of bridging the gap."""

    lo: np.ndarray
    hi: np.ndarray
    centre: np.ndarray
    mean: np.ndarray
    ci_lo: np.ndarray
    ci_hi: np.ndarray
    n: np.ndarray


def bin_series(
    x: np.ndarray, y: np.ndarray, edges: Sequence[float] = THETA_BINS_DEG, level: float = 0.95
) -> BinSeries:
    """Mean of y and its t interval (``mean_ci``) in each bin of x (``bin_masks``)."""
    y = np.asarray(y, float)
    lo, hi, cis = [], [], []
    for b_lo, b_hi, inside in bin_masks(x, edges):
        lo.append(b_lo)
        hi.append(b_hi)
        cis.append(mean_ci(y[inside], level))
    lo_a, hi_a = np.array(lo), np.array(hi)
    return BinSeries(
        lo=lo_a,
        hi=hi_a,
        centre=0.5 * (lo_a + hi_a),
        mean=np.array([c.mean for c in cis]),
        ci_lo=np.array([c.lo for c in cis]),
        ci_hi=np.array([c.hi for c in cis]),
        n=np.array([c.n for c in cis], int),
    )


# --- calibration of a stated standard deviation --------------------------------------------


def z_scores(estimate: np.ndarray, truth: np.ndarray, std: np.ndarray) -> np.ndarray:
    """(estimate − truth) / std; nan where std is missing, not finite or not positive."""
    estimate, truth, std = (np.asarray(a, float) for a in (estimate, truth, std))
    good = np.isfinite(std) & (std > 0) & np.isfinite(estimate) & np.isfinite(truth)
    out = np.full(np.broadcast(estimate, truth, std).shape, np.nan)
    np.divide(estimate - truth, std, out=out, where=good)
    return out


def coverage(z: np.ndarray, half_width: float) -> float:
    """Fraction of the finite z with |z| <= half_width (nan when there are none)."""
    z = np.asarray(z, float)
    z = z[np.isfinite(z)]
    return float(np.mean(np.abs(z) <= half_width)) if len(z) else float("nan")


@dataclass(frozen=True)
class Calibration:
    """How well a stated standard deviation describes the errors: n finite z scores,
    the fractions inside ±1σ (``cov68``) and ±1.96σ (``cov95``), rms and mean of z."""

    n: int
    inside68: int
    inside95: int
    rms: float
    mean: float

    @property
    def cov68(self) -> float:
        return self.inside68 / self.n if self.n else float("nan")

    @property
    def cov95(self) -> float:
        return self.inside95 / self.n if self.n else float("nan")


def calibration(z: np.ndarray) -> Calibration:
    """``Calibration`` of the finite values of z (well calibrated: cov68 ≈ 0.683,
    cov95 ≈ 0.95, rms ≈ 1, mean ≈ 0)."""
    z = np.asarray(z, float)
    z = z[np.isfinite(z)]
    if not len(z):
        return Calibration(0, 0, 0, float("nan"), float("nan"))
    a = np.abs(z)
    return Calibration(
        n=len(z),
        inside68=int(np.sum(a <= Z_68)),
        inside95=int(np.sum(a <= Z_95)),
        rms=float(np.sqrt(np.mean(z * z))),
        mean=float(np.mean(z)),
    )


def binned_calibration(
    x: np.ndarray, z: np.ndarray, edges: Sequence[float] = CALIBRATION_BINS_DEG
) -> list[tuple[float, float, Calibration]]:
    """(lo, hi, ``calibration`` of the z whose x falls in the bin) for each bin."""
    z = np.asarray(z, float)
    return [(lo, hi, calibration(z[inside])) for lo, hi, inside in bin_masks(x, edges)]


# --- paired differences and a slope ----------------------------------------------------------


@dataclass(frozen=True)
class PairedDifference:
    """a − b over pairs: mean difference with its t interval, and how many pairs each wins
    (``ties``: |a − b| <= the tie tolerance)."""

    diff: MeanCI
    a_better: int
    b_better: int
    ties: int


def paired_difference(
    a: np.ndarray, b: np.ndarray, tie: float = 0.0, level: float = 0.95
) -> PairedDifference:
    """Compare a and b pair by pair (larger is better); pairs with a non-finite value are
    left out."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    good = np.isfinite(a) & np.isfinite(b)
    d = a[good] - b[good]
    return PairedDifference(
        diff=mean_ci(d, level),
        a_better=int(np.sum(d > tie)),
        b_better=int(np.sum(d < -tie)),
        ties=int(np.sum(np.abs(d) <= tie)),
    )


def slope_through_origin(x: np.ndarray, y: np.ndarray) -> float:
    """Least-squares k of y ≈ k·x (no intercept) over the finite pairs; nan without data."""
    x, y = np.asarray(x, float), np.asarray(y, float)
    good = np.isfinite(x) & np.isfinite(y)
    x, y = x[good], y[good]
    denom = float(x @ x)
    return float(x @ y) / denom if denom > 0 else float("nan")
