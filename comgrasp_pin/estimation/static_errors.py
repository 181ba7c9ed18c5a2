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

Poses read from both sides have their own model (``side_friction``). ``residual_rules``
applies them: the covariance, its degrees of freedom and the share explained.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from comgrasp_pin.errors import InvalidInputError
from comgrasp_pin.estimation.block_sandwich import block_sandwich
from comgrasp_pin.estimation.estimate import ComEstimate, mc_jacobian
from comgrasp_pin.estimation.regressor import RANK_TOL, stacked_regressor
from comgrasp_pin.estimation.side_friction import share_dof
from comgrasp_pin.estimation.trust import MIN_EXPLAINED, payload_seen, t95, unexplained_reason
from comgrasp_pin.robot import RobotModel


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


def residual_rules(robot, est: ComEstimate, Q, sigma, cov, dtau, pose_errors: bool, friction):
    """(estimate, dof of its covariance, findings) after the residuals' two rules.

    The covariance is scaled by the chi-square per degree of freedom where that exceeds 1
    (the readings err more than their noise; the wrist sensor's rule), with its dof; and the
    payload must explain ``trust.MIN_EXPLAINED`` of the torque differences (the motion's).
    With ``pose_errors``, the covariance and its (4,) dof are the poses' block sandwich;
    with the sides' ``friction`` (its share above 0), Satterthwaite's (``share_dof``).
    """
    chi2_dof, dof, explained = residual_chi2(est, sigma, cov, dtau)
    if pose_errors:
        if len(Q) < 2:
            raise InvalidInputError("pose errors need 2 poses or more: their spread is the error")
        theta = np.r_[est.mass, est.mass * est.com_ee]
        cov_mc, dof = pose_block_cov(robot, Q, dtau, sigma, theta)
        est = dataclasses.replace(est, cov=cov_mc)
    elif friction is not None and friction.share_left > 0:  # the sides' friction (REML)
        est = dataclasses.replace(est, cov=est.cov * max(chi2_dof, 1.0))
        G = mc_jacobian(np.r_[est.mass, est.mass * est.com_ee])
        dof = np.minimum(dof, share_dof(stacked_regressor(robot, Q)[0], cov, friction, G))
    elif chi2_dof > 1:
        est = dataclasses.replace(est, cov=est.cov * chi2_dof)
    else:
        dof = np.inf
    findings = []
    q = t95(np.atleast_1d(dof)[0])
    seen = est.cov is not None and payload_seen(est.mass, np.sqrt(est.cov[0, 0]), q)
    if seen and explained < MIN_EXPLAINED:
        findings.append(unexplained_reason(explained, "torque differences"))
    return est, dof, findings
