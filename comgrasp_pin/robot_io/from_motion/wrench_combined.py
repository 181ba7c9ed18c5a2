"""The wrench's rows and the joint torques' rows in one system, and what each source gave.

Per kept sample the six wrench rows (``wrench_system``) come first, then the n joint-torque
rows of the same sample (``payload_system``), so that the stacked system keeps the sample-major
layout the fit, the block sandwich and the validation expect (k samples of r = 6 + n rows). The
payload's ten parameters (ee frame) are shared; each source keeps its own extra unknowns (the
sensor's bias, drift and delay; the joints' offsets, drift, friction and delay) and its own
row weights: 1 / its noise per row (from a first plain fit of that source alone) times its
own block sandwich's widening (``reweighted``).

What each source contributed (``contributions``): with F_s the information about the ten
parameters that source s's rows carry once its own extras are fitted (the Schur complement of
its weighted normal matrix) and C = (sum_s F_s + F_prior)^-1, a quantity q(pi) with gradient
g has variance g^T C g = sum_s g^T C F_s C g: source s's share is g^T C F_s C g / g^T C g
(each in [0, 1], summing to 1 over the sources). Given for the mass, each CoM coordinate and
each principal moment (about the estimate's principal axes).

Whether the sources agree (``agreement``): each source alone fitted (unconstrained least
squares, its covariance widened by its own block sandwich), and the mass and first moments
(m, m c) compared, chi-square with 4 degrees of freedom.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from comgrasp_pin.errors import UnobservableError
from comgrasp_pin.estimation import trust
from comgrasp_pin.estimation.block_sandwich import pooled_dof
from comgrasp_pin.robot_io.from_motion.arm_model import ArmModel
from comgrasp_pin.robot_io.from_motion.dynamic_fit import error_sources, satterthwaite
from comgrasp_pin.robot_io.from_motion.motion_system import about_com, row_noise
from comgrasp_pin.robot_io.from_motion.payload_system import PayloadSystem
from comgrasp_pin.robot_io.from_motion.wrench_system import WrenchSystem
from comgrasp_pin.robot_io.results.estimate_result import JOINT_TORQUES, PRIOR, WRENCH

DISAGREE_P = 0.0027
"""The false-alarm rate of the sources' agreement test, the halves' 3 std rule's: the two
sources' mass or a first moment (m c) is said to differ where its difference exceeds Student's
t quantile of its variance's degrees of freedom at DISAGREE_P / 4 two-sided (Bonferroni over the
four; 3.2 std where the degrees of freedom are many, 6.1 at 6, 12 at 3)."""


@dataclass(frozen=True)
class Stacked:
    """The stacked system: ``b = A_pi pi + A_x x`` per sample, r rows each.

    Attributes:
        A_pi: (k, r, 10); A_x: (k, r, e); b: (k, r) (N, N m); w: (k r,) row weights.
        noise: (r,) each row's noise std (white, from its source's plain fit).
        groups: source name -> (its row indices within a sample, its columns of A_x).
        arm_jac: (k r, p) the arm model's columns on the joint rows (zeros on the wrench's),
            or None.
    """

    A_pi: np.ndarray
    A_x: np.ndarray
    b: np.ndarray
    w: np.ndarray
    noise: np.ndarray
    groups: dict
    arm_jac: np.ndarray | None

    def rows(self, name: str) -> np.ndarray:
        """The flat row indices (into k r) of source ``name``."""
        k, r = self.b.shape
        return (np.arange(k)[:, None] * r + self.groups[name][0]).ravel()


def _noise(A_pi: np.ndarray, A_x: np.ndarray, b: np.ndarray) -> np.ndarray:
    k, n = b.shape
    return row_noise(np.column_stack([A_pi.reshape(k * n, -1), A_x]), b.reshape(-1), k, n)


def stack(W: WrenchSystem, b_wrench: np.ndarray, J: PayloadSystem | None) -> Stacked:
    """The wrench's rows (its measured payload wrench ``b_wrench`` (k, 6)) and ``J``'s, if any.

    Raises:
        AssertionError: the two systems' samples differ (they are taken alike).
    """
    k, e_w = len(W.S.t), W.A_x.shape[1]
    sigma_w = _noise(W.A_pi, W.A_x, b_wrench)
    if J is None:
        groups = {WRENCH: (np.arange(6), np.arange(e_w))}
        return Stacked(W.A_pi, W.A_x.reshape(k, 6, e_w), b_wrench, np.tile(1 / sigma_w, k),
                       sigma_w, groups, None)  # fmt: skip
    assert np.array_equal(J.S.t, W.S.t), "the wrench's and the joints' samples differ"
    n, e_j = J.b.shape[1], J.A_x.shape[1]
    r = 6 + n
    A_x = np.zeros((k, r, e_w + e_j))
    A_x[:, :6, :e_w] = W.A_x.reshape(k, 6, e_w)
    A_x[:, 6:, e_w:] = J.A_x.reshape(k, n, e_j)
    noise = np.concatenate([sigma_w, _noise(J.Y, J.A_x, J.b)])
    arm_jac = None
    if J.arm_jac is not None:
        arm_jac = np.zeros((k, r, J.arm_jac.shape[1]))
        arm_jac[:, 6:] = J.arm_jac.reshape(k, n, -1)
        arm_jac = arm_jac.reshape(k * r, -1)
    groups = {WRENCH: (np.arange(6), np.arange(e_w)),
              JOINT_TORQUES: (np.arange(6, r), np.arange(e_w, e_w + e_j))}  # fmt: skip
    return Stacked(np.concatenate([W.A_pi, J.Y], axis=1), A_x,
                   np.concatenate([b_wrench, J.b], axis=1), np.tile(1 / noise, k), noise,
                   groups, arm_jac)  # fmt: skip


def _information(st: Stacked, name: str) -> np.ndarray:
    """(10, 10) the information about pi in source ``name``'s rows, its own extras fitted."""
    cols, x_cols = st.groups[name]
    A = np.concatenate([st.A_pi[:, cols], st.A_x[:, cols][:, :, x_cols]], axis=2)
    Aw = A.reshape(-1, A.shape[2]) * st.w[st.rows(name), None]
    G = Aw.T @ Aw
    return G[:10, :10] - G[:10, 10:] @ np.linalg.pinv(G[10:, 10:]) @ G[10:, :10]


def _prior_information(pi: np.ndarray, prior) -> np.ndarray:
    """(10, 10) the prior's information about pi: J^T cov^-1 J, J = d(m, c) / d pi."""
    mean, cov = prior
    m, h = pi[0], pi[1:4]
    J = np.zeros((4, 10))
    J[0, 0] = 1.0
    J[1:, 0] = -h / m**2
    J[1:, 1:4] = np.eye(3) / m
    return J.T @ np.linalg.solve(np.asarray(cov, float), J)


def _gradients(pi: np.ndarray) -> dict:
    """Gradients (10,) of the mass, the CoM's coordinates and the principal moments."""
    m, h = pi[0], pi[1:4]
    grads = {"mass_kg": [np.eye(10)[0]], "com_m": []}
    for i in range(3):
        g = np.zeros(10)
        g[0], g[1 + i] = -h[i] / m**2, 1 / m
        grads["com_m"].append(g)
    zero = np.zeros((10, 10))
    _, axes = np.linalg.eigh(about_com(pi, zero)[2])

    def moments(p):
        inertia = about_com(p, zero)[2]
        return np.array([u @ inertia @ u for u in axes.T])

    steps = 1e-6 * np.maximum(np.abs(pi), 1e-6)
    D = np.column_stack([(moments(pi + s * e) - moments(pi - s * e)) / (2 * s)
                         for s, e in zip(steps, np.eye(10))])  # fmt: skip
    grads["principal_moments_kgm2"] = list(D)
    return grads


def contributions(st: Stacked, pi: np.ndarray, prior=None) -> dict:
    """Each source's share of the information about the payload's mass, CoM and moments.

    Returns {source: {"mass_kg": share, "com_m": [3], "principal_moments_kgm2": [3]}}, the
    prior a source of its own where one is given.
    """
    F = {name: _information(st, name) for name in st.groups}
    if prior is not None:
        F[PRIOR] = _prior_information(pi, prior)
    C = np.linalg.pinv(sum(F.values()))
    out: dict = {name: {} for name in F}
    for quantity, grads in _gradients(pi).items():
        for name, F_s in F.items():
            shares = [float(g @ C @ F_s @ C @ g / max(g @ C @ g, 1e-300)) for g in grads]
            out[name][quantity] = shares[0] if quantity == "mass_kg" else shares
    return out


def alone(st: Stacked, name: str, duration_s: float, arm_model: ArmModel | None = None):
    """Source ``name``'s rows alone: (pi, its covariance, its widening, m and m c's dof).

    pi (10,), its covariance (10, 10), the degrees of freedom (4,) of m and m c's variances.
    The widening is the rms over the ten parameters of its block sandwich's widening of
    their white-noise std (``dynamic_fit.ErrorSources.factor``). Where the rows do not
    determine pi, the reason (a string) instead.
    """
    cols, x_cols = st.groups[name]
    k = st.b.shape[0]
    A = np.concatenate([st.A_pi[:, cols], st.A_x[:, cols][:, :, x_cols]], axis=2)
    A = A.reshape(k * len(cols), -1)
    rows = st.rows(name)
    arm_jac = None if st.arm_jac is None or name != JOINT_TORQUES else st.arm_jac[rows]
    b, w = st.b[:, cols].reshape(-1), st.w[rows]
    try:
        err = error_sources(A, b, w, (k, len(cols)), duration_s, np.zeros((k, len(cols))),
                            None, arm_model, arm_jac)  # fmt: skip
    except UnobservableError as exc:
        return f"{name} alone: {exc}"
    data_cov = err.data_cov
    dof = np.array([satterthwaite(c, data_cov, err) for c in np.eye(10)[:4]])
    return err.sensitivity @ b, data_cov + err.arm, float(np.sqrt(np.mean(err.factor**2))), dof


def reweighted(st: Stacked, fits: dict) -> Stacked:
    """``st`` with each source's rows weighted by 1 / (noise x its own sandwich widening).

    A source whose errors are correlated over seconds (a friction the model lacks, an arm
    model's error) carries less information than its white noise says; weighted by its white
    noise alone it would pull the joint fit by more than it knows. The weights are then
    scaled together so that the weighted residuals of a plain fit have unit variance, as the
    fit's covariance (``fit_payload``: the inverse Hessian, widened by the sandwich over the
    white-noise covariance) expects. One source alone: unchanged.
    """
    usable = {n: f for n, f in fits.items() if not isinstance(f, str)}
    if len(st.groups) < 2 or len(usable) < 2:
        return st
    k, r = st.b.shape
    scale = np.ones(r)
    for name, fit in usable.items():
        scale[st.groups[name][0]] = fit[2]
    w = np.tile(1 / (st.noise * scale), k)
    A = np.column_stack([st.A_pi.reshape(k * r, -1), st.A_x.reshape(k * r, -1)])
    beta = np.linalg.lstsq(A * w[:, None], st.b.reshape(-1) * w, rcond=None)[0]
    res = (A @ beta - st.b.reshape(-1)) * w
    s2 = float(res @ res) / max(len(res) - A.shape[1], 1)
    return replace(st, w=w / np.sqrt(s2))


def agreement_limit(nu: np.ndarray) -> np.ndarray:
    """(4,) the largest |difference| / std of each of m, m c before the sources disagree."""
    return np.atleast_1d(trust.t_quantile(nu, 1 - DISAGREE_P / 4))


def agreement(fits: dict, tool_cov: np.ndarray) -> dict | None:
    """The two sources' (m, m c) difference against its std, or None with fewer than two fits.

    ``z``: each difference over its std; ``max_z``: ``agreement_limit`` of their degrees of
    freedom (pooled, ``pooled_dof``); ``chi2``: the four together, for a reader.

    ``fits``: source -> ``alone``'s result; ``tool_cov`` (10, 10) is added to the wrench's
    (the tool subtracted from its rows only).
    """
    usable = {k: v for k, v in fits.items() if not isinstance(v, str)}
    if len(usable) < 2:
        return None
    (pw, cw, _, nw), (pj, cj, _, nj) = usable[WRENCH], usable[JOINT_TORQUES]
    d = pw[:4] - pj[:4]
    chi2 = float(d @ np.linalg.solve((cw + tool_cov + cj)[:4, :4], d))
    var = np.diag(cw + tool_cov + cj)[:4]
    nu = np.array([pooled_dof([(cw[i, i], nw[i]), (tool_cov[i, i], np.inf), (cj[i, i], nj[i])])
                   for i in range(4)])  # fmt: skip
    z, limit = d / np.sqrt(var), agreement_limit(nu)
    return {"chi2": chi2, "z": z.tolist(), "max_z": limit.tolist(),
            "cov_dof": nu.tolist(), "disagree": bool(np.any(np.abs(z) > limit)),
            "mass_kg": {WRENCH: float(pw[0]), JOINT_TORQUES: float(pj[0])},
            "mass_std_kg": {WRENCH: float(np.sqrt(cw[0, 0] + tool_cov[0, 0])),
                            JOINT_TORQUES: float(np.sqrt(cj[0, 0]))}}  # fmt: skip
