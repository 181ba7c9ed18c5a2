"""Stuck joint friction that a pose's two sides leave: its scale measured, its share found.

A joint that stops under a position controller holds friction: the torque read at rest is
the gravity torque plus up to the friction's limit, with the sign of the approach. A pose
read from both sides (approached from above and below on every joint,
``windows.read_joined``) gives two readings whose mean cancels most of it, and whose half
difference measures it: the sides' spread s_ij at pose i, joint j, in each run (empty and
loaded). What the mean leaves (the sides' friction is not quite equal) is bounded by that
spread at the visit, so its variance is modelled as a share kappa^2 of a scale S_ij:

    var(dtau_ij) = noise_ij^2 + kappa^2 S_ij,   V_ij = s_ij^2 (empty) + s_ij^2 (loaded),
    S_ij = (1 - rho) mean_i V_ij + rho V_ij,

rho in [0, 1] weighing the pose's own spread against the joint's mean over the poses (a
joint may stop with little friction at one pose and much at the next, or the spread at one
visit may be mostly noise). For each rho of a grid, kappa is the value at which the
generalised least squares' residuals, refitted at each trial, have a chi-square per degree
of freedom of 1 (Paule and Mandel 1982, the between-laboratory variance of interlaboratory
studies), or 0 where the noise alone explains them; rho is the one whose restricted
likelihood (REML, Patterson and Thompson 1971) is highest. The weights follow: a joint whose
reading depends on the side it came from counts less, and the interval holds what it leaves.

kappa is itself estimated, and from few readings where the noise hides the friction on most
joints: a CoM component that rests on the one joint whose friction shows has a variance
known far worse than "the readings less the unknowns" says. Its degrees of freedom are
Satterthwaite's (``share_dof``): 2 v^2 / ((dv / dkappa^2)^2 var(kappa^2)), with the moment
estimator's var(kappa^2) = 2 dof / tr(P E)^2 (P the GLS residual projector, E the friction's
scale): the readings less the unknowns where the friction dominates every reading, fewer
where it shows on few.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

SHARE_TOL = 1e-6
"""Paule-Mandel's kappa is bisected to this relative width."""
MAX_SHARE = 64.0
"""The largest kappa tried (the friction left, as a multiple of the sides' spread)."""
MIX_STEPS = 11
"""rho's grid: 0, 0.1, ..., 1."""


@dataclass(frozen=True)
class SideFriction:
    """What the two sides of each pose showed of the joints' stuck friction.

    Attributes:
        spread: (k, n) sqrt(V_ij): the sides' spread of both runs at each pose (N m).
        share_left: kappa, the share of it the sides' mean left (0: the noise explains the
            residuals).
        own_pose: rho, the weight of a pose's own spread against the joint's mean, or None
            where kappa is 0.
    """

    spread: np.ndarray
    share_left: float
    own_pose: float | None


def side_spreads(before, after) -> np.ndarray | None:
    """(k, n) sqrt(V_ij) of the paired readings (``windows.StaticReading``) (N m).

    None where a window was read from one side (no measure of its friction).
    """
    if any(r.side_spread is None for r in (*before, *after)):
        return None
    return np.sqrt([b.side_spread**2 + a.side_spread**2 for b, a in zip(before, after)])


def side_friction_cov(
    Y: np.ndarray, dtau: np.ndarray, cov: np.ndarray, spread: np.ndarray
) -> tuple[SideFriction, np.ndarray]:
    """(what was found, the differences' covariance with the friction the sides left).

    Args:
        Y: (k n, 4) the stacked regressor of (m, m c_ee) (``stacked_regressor``).
        dtau: (k n,) the stacked torque differences, pose-major (N m).
        cov: (k n, k n) their covariance from the readings' noise (and drift).
        spread: (k, n) sqrt(V_ij) (``side_spreads``, N m).
    """
    V = np.square(spread)
    dof = len(dtau) - int(np.linalg.matrix_rank(Y))
    if dof <= 0 or not np.any(V > 0) or _excess(Y, dtau, cov, dof) <= 0:
        return SideFriction(spread, 0.0, None), cov  # the noise explains the residuals
    tried = []
    for rho in np.linspace(0.0, 1.0, MIX_STEPS):
        extra = _scale(V, float(rho))
        kappa = _paule_mandel(Y, dtau, cov, extra, dof)
        L = np.linalg.cholesky(cov + kappa**2 * extra)
        A = np.linalg.solve(L, Y)
        # REML's -log likelihood less constants: its chi-square term is dof at every rho
        nll = np.sum(np.log(np.diag(L))) + 0.5 * np.linalg.slogdet(A.T @ A)[1]
        tried.append((float(nll), float(rho), kappa, extra))
    _, rho, kappa, extra = min(tried, key=lambda t: t[0])
    return SideFriction(spread, kappa, rho), cov + kappa**2 * extra


def share_dof(Y: np.ndarray, cov: np.ndarray, found: SideFriction, G: np.ndarray) -> np.ndarray:
    """(p,) Satterthwaite's degrees of freedom of each estimate's variance, kappa estimated.

    ``G`` (p, 4): d(estimate) / d(m, m c_ee) at the fit; ``cov``: ``side_friction_cov``'s,
    kappa included. At most the readings less the unknowns; infinite where kappa is 0 (the
    noise alone, known from many samples).
    """
    dof = len(cov) - int(np.linalg.matrix_rank(Y))
    if found.share_left <= 0 or dof <= 0:
        return np.full(len(G), np.inf)
    E = _scale(np.square(found.spread), float(found.own_pose))
    W = np.linalg.inv(cov)
    cov_theta = np.linalg.inv(Y.T @ W @ Y)
    K = cov_theta @ Y.T @ W  # the GLS's gain: theta = K dtau
    trace_PE = np.trace(W @ E) - np.trace(K @ E @ W @ Y)
    var_k2 = 2.0 * dof / trace_PE**2
    v = np.einsum("ij,jk,ik->i", G, cov_theta, G)
    dv = np.einsum("ij,jk,ik->i", G, K @ E @ K.T, G)  # d v / d kappa^2
    with np.errstate(divide="ignore"):
        return np.minimum(2.0 * v**2 / (dv**2 * var_k2), float(dof))


def _scale(V: np.ndarray, rho: float) -> np.ndarray:
    """(k n, k n) the friction's scale, diag((1 - rho) mean_i V_ij + rho V_ij), pose-major."""
    return np.diag(((1.0 - rho) * V.mean(axis=0) + rho * V).ravel())


def _excess(Y, dtau, cov, dof: int) -> float:
    """The GLS residuals' chi-square per degree of freedom less 1 under covariance ``cov``."""
    L = np.linalg.cholesky(cov)
    A, b = np.linalg.solve(L, Y), np.linalg.solve(L, dtau)
    r = b - A @ np.linalg.lstsq(A, b, rcond=None)[0]
    return float(r @ r) / dof - 1.0


def _paule_mandel(Y, dtau, cov, extra, dof: int) -> float:
    """The kappa > 0 at which the GLS residuals' chi-square per degree of freedom is 1.

    The chi-square exceeds 1 without the friction (``side_friction_cov`` checks); at most
    MAX_SHARE (errors where the sides agree: the chi-square's rule takes the rest). The
    value returned leaves the chi-square just above 1.
    """
    lo, hi = 0.0, 1.0
    while _excess(Y, dtau, cov + hi**2 * extra, dof) > 0:
        if hi >= MAX_SHARE:
            return hi
        lo, hi = hi, 2.0 * hi
    while hi - lo > SHARE_TOL * hi:
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if _excess(Y, dtau, cov + mid**2 * extra, dof) > 0 else (lo, mid)
    return lo
