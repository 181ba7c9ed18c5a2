"""What readings at rest err by beyond their noise: the residuals' rules, the poses' sandwich.

``residual_chi2``: the fit's residuals against the readings' noise (their chi-square per
degree of freedom, which scales the covariance where it exceeds 1) and the share of the
torque differences the payload explains. ``pose_block_cov``: at rest, some errors are
constant over a pose's window and differ between poses: a joint's stuck friction (the torque
read at rest is the gravity torque plus whatever friction the stop left, up to its limit), a
servo's sag, a cable's pull at that pose. Averaging more samples does not shrink them, and
they may be correlated across the joints of a pose. The CR2 block sandwich
(``block_sandwich``, Bell and McCaffrey 2002) with one block per pose estimates the variance
from the poses' own residuals whatever their correlation within a pose, with Satterthwaite
degrees of freedom (at most k - 1): the motion's model, whose blocks are spans of time, at
rest.

``side_friction_cov``: where each pose was read from two sides (approached from above and
below on every joint, ``windows.read_joined``), the sides' half difference measures each
joint's stuck friction there, and their mean cancels most of it. What is left is modelled
per joint as a share kappa of that friction's scale F_j (the RMS of the half differences over
the poses and both runs): var(dtau_ij) = noise_ij^2 + kappa^2 F_j^2. kappa is found from the
fit's residuals, the generalised least squares refitted at each trial, so that their
chi-square per degree of freedom is 1 (Paule and Mandel 1982, the between-laboratory
variance of interlaboratory studies), or 0 where the noise alone explains them. The weights
follow: a joint whose reading depends on the side it was approached from counts less.
"""

from __future__ import annotations

import numpy as np

from comgrasp_pin.estimation.block_sandwich import block_sandwich
from comgrasp_pin.estimation.estimate import ComEstimate, mc_jacobian
from comgrasp_pin.estimation.regressor import stacked_regressor
from comgrasp_pin.robot import RobotModel

RANK_TOL = 1e-9
"""Singular values below this fraction of the largest are directions the fit left open."""
SHARE_TOL = 1e-6
"""Paule-Mandel's kappa is bisected to this relative width."""
MAX_SHARE = 64.0
"""The largest kappa tried (the friction left, as a multiple of the sides' spread)."""


def residual_chi2(est: ComEstimate, sigma: np.ndarray, cov: np.ndarray | None, dtau):
    """(chi-square per degree of freedom, degrees of freedom, share explained) of the fit.

    The residuals are whitened by the differences' covariance (``cov``, pose-major) or,
    without it, by the std of a difference of two readings, sqrt(2) ``sigma``. The degrees
    of freedom are the readings (k n) less the directions the fit determined (the rank of
    its regressor); NaN chi-square with none left. The share explained is 1 - |r|^2 /
    |dtau|^2 of the whitened residuals r and torque differences ``dtau`` (k, n): the
    motion's rule (``trust.MIN_EXPLAINED``) at rest.
    """
    r = np.asarray(est.residuals, dtype=float).ravel()
    d = np.asarray(dtau, dtype=float).ravel()
    if cov is None:
        w = np.tile(np.sqrt(2.0) * sigma, len(r) // len(sigma))
        r, d = r / w, d / w
    else:
        L = np.linalg.cholesky(cov)
        r, d = np.linalg.solve(L, r), np.linalg.solve(L, d)
    explained = 1.0 - float(r @ r) / max(float(d @ d), 1e-300)
    sv = np.asarray(est.singular_values, dtype=float)
    dof = r.size - int(np.sum(sv > RANK_TOL * sv.max()))
    if dof <= 0 or est.cov is None:
        return float("nan"), np.inf, explained
    return float(r @ r / dof), float(dof), explained


def pose_block_cov(
    robot: RobotModel, Q: np.ndarray, dtau: np.ndarray, sigma: np.ndarray, theta: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """((4, 4) covariance of (mass, com_ee), (4,) its dof) from the poses' residuals.

    Args:
        robot: the arm.
        Q: (k, n) the poses (k >= 2).
        dtau: (k, n) the torque differences (N m).
        sigma: (n,) std of one averaged reading (the fit's weights: 1 / (sqrt(2) sigma)).
        theta: (4,) the fit's (m, m c_ee).
    """
    Q = np.atleast_2d(np.asarray(Q, dtype=float))
    k, n = Q.shape
    Y, _ = stacked_regressor(robot, Q)
    w = np.tile(1.0 / (np.sqrt(2.0) * np.asarray(sigma, dtype=float)), k)
    sandwich = block_sandwich(Y, np.asarray(dtau, float).ravel(), w, k, n,
                              [np.array([i]) for i in range(k)], p=4)  # fmt: skip
    G = mc_jacobian(np.asarray(theta, dtype=float))
    return G @ sandwich.cov @ G.T, np.array([sandwich.dof(G[r]) for r in range(4)])


def side_friction(before, after) -> np.ndarray | None:
    """(n,) F_j: per joint, the RMS over the poses and both runs of the sides' spread (N m).

    ``before``, ``after``: the paired readings (``windows.StaticReading``); None where a
    window was read from one side (no measure of its friction).
    """
    spreads = [r.side_spread for r in (*before, *after)]
    if any(s is None for s in spreads):
        return None
    return np.sqrt(np.mean(np.square(spreads), axis=0))


def side_friction_cov(
    Y: np.ndarray, dtau: np.ndarray, cov: np.ndarray, friction: np.ndarray
) -> tuple[float, np.ndarray]:
    """(kappa, the differences' covariance with the friction left): Paule-Mandel's kappa.

    Args:
        Y: (k n, 4) the stacked regressor of (m, m c_ee) (``stacked_regressor``).
        dtau: (k n,) the stacked torque differences (N m).
        cov: (k n, k n) their covariance from the readings' noise (and drift).
        friction: (n,) F_j (``side_friction``, N m).
    """
    extra = np.diag(np.tile(np.square(friction), len(dtau) // len(friction)))
    dof = len(dtau) - int(np.linalg.matrix_rank(Y))

    def excess(kappa: float) -> float:
        """The GLS residuals' chi-square per degree of freedom less 1 at ``kappa``."""
        L = np.linalg.cholesky(cov + kappa**2 * extra)
        A, b = np.linalg.solve(L, Y), np.linalg.solve(L, dtau)
        r = b - A @ np.linalg.lstsq(A, b, rcond=None)[0]
        return float(r @ r) / dof - 1.0

    if dof <= 0 or not np.any(friction > 0) or excess(0.0) <= 0:
        return 0.0, cov
    lo, hi = 0.0, 1.0
    while excess(hi) > 0:
        if hi >= MAX_SHARE:  # errors where the sides agree: the chi-square's rule takes them
            return hi, cov + hi**2 * extra
        lo, hi = hi, 2.0 * hi
    while hi - lo > SHARE_TOL * hi:
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if excess(mid) > 0 else (lo, mid)
    return lo, cov + lo**2 * extra
