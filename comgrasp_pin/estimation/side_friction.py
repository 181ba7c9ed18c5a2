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
visit may be mostly noise). kappa and rho are the pair of highest restricted likelihood
(REML, Patterson and Thompson 1971: the likelihood of the residuals, which the fitted
payload does not bias): for each rho of a grid, kappa maximises it (0 where the noise alone
explains the residuals best). The weights follow: a joint whose reading depends on the side
it came from counts less, and the interval holds what it leaves.

kappa is itself estimated, and from few readings where the noise hides the friction on most
joints: a CoM component that rests on the one joint whose friction shows has a variance
known far worse than "the readings less the unknowns" says. Its degrees of freedom are
Satterthwaite's (``share_dof``): 2 v^2 / ((dv / dkappa^2)^2 var(kappa^2)), with REML's
var(kappa^2) = 2 / tr(P E P E) (P the GLS residual projector, E the friction's scale): the
readings less the unknowns where the friction dominates every reading, about as many as the
readings it dominates where it shows on few. (A moment estimator, Paule and Mandel's, which
sets the residuals' chi-square per degree of freedom to 1, would leave kappa to the noise of
the many readings the friction does not show in, with Satterthwaite's dof below 1 at times
on franky-sim's sessions.)
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import minimize_scalar

from comgrasp_pin.estimation.regressor import RANK_TOL

SHARE_TOL = 1e-6
"""log(kappa) is found to this width (a relative width of kappa)."""
MIN_SHARE = 1e-6
"""The smallest kappa tried above 0."""
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
    if dof <= 0 or not np.any(V > 0):
        return SideFriction(spread, 0.0, None), cov
    tried = []
    for rho in np.linspace(0.0, 1.0, MIX_STEPS):
        extra = _scale(V, float(rho))
        tried.append((*_reml_share(Y, dtau, cov, extra), float(rho), extra))
    nll, kappa, rho, extra = min(tried, key=lambda t: t[0])
    if _reml_nll(Y, dtau, cov) <= nll:
        return SideFriction(spread, 0.0, None), cov  # the noise explains the residuals
    return SideFriction(spread, kappa, rho), cov + kappa**2 * extra


def share_dof(Y: np.ndarray, cov: np.ndarray, found: SideFriction, G: np.ndarray) -> np.ndarray:
    """(p,) Satterthwaite's degrees of freedom of each estimate's variance, kappa estimated.

    ``G`` (p, 4): d(estimate) / d(m, m c_ee) at the fit; ``cov``: ``side_friction_cov``'s,
    kappa included. At most the readings less the unknowns; infinite where kappa is 0 (the
    noise alone, known from many samples).
    """
    dof = len(cov) - int(np.linalg.matrix_rank(Y))
    if found.share_left <= 0 or found.own_pose is None or dof <= 0:
        return np.full(len(G), np.inf)
    E = _scale(np.square(found.spread), found.own_pose)
    W = np.linalg.inv(cov)
    cov_theta = np.linalg.pinv(Y.T @ W @ Y, rcond=RANK_TOL)
    K = cov_theta @ Y.T @ W  # the GLS's gain: theta = K dtau
    PE = E @ W - E @ W @ Y @ K  # (P E) transposed: P = W - W Y K is symmetric
    var_k2 = 2.0 / np.sum(PE * PE.T)  # REML: 2 / tr(P E P E)
    v = np.einsum("ij,jk,ik->i", G, cov_theta, G)
    dv = np.einsum("ij,jk,ik->i", G, K @ E @ K.T, G)  # d v / d kappa^2
    with np.errstate(divide="ignore"):
        return np.minimum(2.0 * v**2 / (dv**2 * var_k2), float(dof))


def _scale(V: np.ndarray, rho: float) -> np.ndarray:
    """(k n, k n) the friction's scale, diag((1 - rho) mean_i V_ij + rho V_ij), pose-major."""
    return np.diag(((1.0 - rho) * V.mean(axis=0) + rho * V).ravel())


def _reml_share(Y, dtau, cov, extra) -> tuple[float, float]:
    """(REML's -log likelihood, kappa) at the kappa in [MIN_SHARE, MAX_SHARE] that minimises it."""
    found = minimize_scalar(
        lambda log_kappa: _reml_nll(Y, dtau, cov + np.exp(2.0 * log_kappa) * extra),
        bounds=(np.log(MIN_SHARE), np.log(MAX_SHARE)), method="bounded",
        options={"xatol": SHARE_TOL},
    )  # fmt: skip
    return float(found.fun), float(np.exp(found.x))


def _reml_nll(Y: np.ndarray, dtau: np.ndarray, V: np.ndarray) -> float:
    """REML's -log likelihood of ``dtau`` = Y theta + e, e ~ N(0, V), less constants."""
    L = np.linalg.cholesky(V)
    A, b = np.linalg.solve(L, Y), np.linalg.solve(L, dtau)
    r = b - A @ np.linalg.lstsq(A, b, rcond=None)[0]
    sv = np.linalg.svd(A, compute_uv=False)
    log_det = 2.0 * np.sum(np.log(sv[sv > RANK_TOL * sv[0]]))  # over what the poses see
    return float(np.sum(np.log(np.diag(L))) + 0.5 * log_det + 0.5 * r @ r)
