"""The payload's ten inertial parameters, physically consistent, solved by IPOPT.

A rigid body's parameters pi = (m, m c, I at the frame origin) (Pinocchio's order) are
physically consistent when its pseudo-inertia

    J = [[Sigma, m c], [m c^T, m]],   Sigma = 1/2 tr(I) 1 - I   (the second moment of mass)

is positive definite (Wensing, Kim, Slotine 2017: a mass distribution exists with these
moments). The log-Cholesky parametrisation (Rucker & Wensing 2022) writes J = U U^T with

    U = e^alpha [[e^d1, s12, s13, t1], [0, e^d2, s23, t2], [0, 0, e^d3, t3], [0, 0, 0, 1]]

so that every theta = (alpha, d1, d2, d3, s12, s23, s13, t1, t2, t3) in R^10 is a
consistent body and every consistent body has one theta: the fit is unconstrained in theta.
m = e^(2 alpha) and c = t.

The data enter through the normal equations of a weighted linear least squares in
beta = (pi, x), x extra linear unknowns (offsets, friction): f = 1/2 |W (A beta - b)|^2. x is
profiled out exactly (the Schur complement), leaving a quadratic in pi; IPOPT minimises it
over theta, plus a Gaussian prior on (m, c) where a static estimate gives one. The
covariance of pi is the Laplace approximation in pi: the inverse of the objective's Hessian
in pi at the optimum. At an optimum inside the parametrisation it equals the inverse Hessian
in theta mapped by d pi / d theta; at a spread's bound (a payload thin along an axis) the
Hessian in theta is flat along that spread, which pi barely follows, and the theta route
would give the thin axis's second moment zero variance: the data's information says what it
is. A direction the data do not determine is refused (``UnobservableError``), never given
zero variance.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from comgrasp_pin.errors import SolverError, UnobservableError
from comgrasp_pin.estimation.ipopt import IPOPT_OPTIONS

N_PARAMS = 10
EIG_FLOOR = 1e-9
"""Smallest eigenvalue (kg m^2) a start's pseudo-inertia is lifted to."""
FLAT_RCOND = 1e-12
"""A direction of a column-scaled information matrix whose eigenvalue is below this fraction of
the largest is flat: the data do not determine it."""
NAMES = ("m", "m c_x", "m c_y", "m c_z", "I_xx", "I_xy", "I_yy", "I_xz", "I_yz", "I_zz")
"""The ten parameters' names, Pinocchio's order."""
LOG_SPREAD_MIN = -12.0
"""Lower bound of d1, d2, d3: a spread of the mass of e^-12 (6e-6) times a metre along an
axis, whose second moment (about 1e-11 kg m^2) no torque sees. A payload thin along an axis
(a rod about its own axis) has its optimum there; unbounded, IPOPT walks d towards minus
infinity and never converges."""


@dataclass(frozen=True)
class InertialFit:
    """A consistent fit of the ten parameters and the extra unknowns.

    Attributes:
        pi: (10,) m (kg), m c (kg m), I at the frame origin (kg m^2), Pinocchio's order.
        cov: (10, 10) covariance of pi (Laplace approximation in pi).
        x: (e,) the extra linear unknowns at the optimum (given pi).
        x_std: (e,) their standard deviations.
        theta: (10,) the log-Cholesky parameters.
        unconstrained_pi: (10,) the plain weighted least squares' pi (may be inconsistent).
        return_status, iterations: IPOPT's.
    """

    pi: np.ndarray
    cov: np.ndarray
    x: np.ndarray
    x_std: np.ndarray
    theta: np.ndarray
    unconstrained_pi: np.ndarray
    return_status: str
    iterations: int


def pi_of_theta(theta):
    """The parameters (10) of log-Cholesky theta (10); NumPy arrays or CasADi symbols."""
    lib = ca if isinstance(theta, (ca.SX, ca.MX)) else np
    alpha, d1, d2, d3, s12, s23, s13, t1, t2, t3 = (theta[i] for i in range(10))
    e = lib.exp
    rows = [[e(d1), s12, s13, t1], [0, e(d2), s23, t2], [0, 0, e(d3), t3], [0, 0, 0, 1]]
    U = ca.blockcat(rows) if lib is ca else np.array(rows, dtype=float)
    J = e(2 * alpha) * (U @ U.T)
    m, h, S = J[3, 3], J[0:3, 3], J[0:3, 0:3]
    tr = S[0, 0] + S[1, 1] + S[2, 2]
    inertia = [tr - S[0, 0], -S[0, 1], tr - S[1, 1], -S[0, 2], -S[1, 2], tr - S[2, 2]]
    out = [m, h[0], h[1], h[2], *inertia]
    return ca.vertcat(*out) if lib is ca else np.array(out, dtype=float)


def pseudo_inertia(pi: np.ndarray) -> np.ndarray:
    """(4, 4) J of pi (10)."""
    m, h = pi[0], pi[1:4]
    Ixx, Ixy, Iyy, Ixz, Iyz, Izz = pi[4:]
    inertia = np.array([[Ixx, Ixy, Ixz], [Ixy, Iyy, Iyz], [Ixz, Iyz, Izz]])
    S = 0.5 * np.trace(inertia) * np.eye(3) - inertia
    return np.block([[S, h[:, None]], [h[None, :], np.array([[m]])]])


def theta_of_pi(pi: np.ndarray) -> np.ndarray:
    """Log-Cholesky theta of pi.

    An inconsistent pi is first lifted to the nearest consistent one (J's eigenvalues raised
    to ``EIG_FLOOR``).
    """
    J = pseudo_inertia(np.asarray(pi, float))
    w, V = np.linalg.eigh(J)
    J = (V * np.maximum(w, EIG_FLOOR)) @ V.T
    P = np.eye(4)[::-1]
    U = P @ np.linalg.cholesky(P @ J @ P) @ P  # upper triangular, J = U U^T
    a = U[3, 3]
    U = U / a
    return np.array(
        [np.log(a), *np.log(np.diag(U)[:3]), U[0, 1], U[1, 2], U[0, 2], U[0, 3], U[1, 3], U[2, 3]]
    )


def fit_inertial(
    A_pi: np.ndarray,
    A_x: np.ndarray,
    b: np.ndarray,
    w: np.ndarray,
    prior: tuple[np.ndarray, np.ndarray] | None = None,
) -> InertialFit:
    """Minimise 1/2 |w (A_pi pi + A_x x - b)|^2 (+ prior) over consistent pi and free x.

    Args:
        A_pi: (r, 10) the payload's regressor rows.
        A_x: (r, e) the extra unknowns' columns (e may be 0).
        b: (r,) the torques the payload and the extras explain.
        w: (r,) each row's weight, 1 / its noise std.
        prior: ((4,) mean of (m, c_x, c_y, c_z), (4, 4) its covariance), or None.

    Raises:
        UnobservableError: the rows cannot determine the ten parameters and the extras.
        SolverError: IPOPT did not converge.
    """
    Aw = np.column_stack([A_pi, A_x]) * w[:, None]
    bw = b * w
    G, g = Aw.T @ Aw, Aw.T @ bw
    scale = np.sqrt(np.maximum(np.diag(G), 1e-300))
    s = np.linalg.svd(G / np.outer(scale, scale), compute_uv=False)
    if s[-1] < FLAT_RCOND * s[0]:
        raise UnobservableError(
            f"the motion does not determine the payload's ten parameters and the "
            f"{A_x.shape[1]} offset/friction unknowns (scaled condition number "
            f"{np.sqrt(s[0] / max(s[-1], 1e-300)):.1e}): move every wrist joint, faster"
        )
    n = N_PARAMS
    Gxx_inv = np.linalg.inv(G[n:, n:]) if A_x.shape[1] else np.zeros((0, 0))
    G_eff = G[:n, :n] - G[:n, n:] @ Gxx_inv @ G[n:, :n]
    g_eff = g[:n] - G[:n, n:] @ Gxx_inv @ g[n:]
    pi_ls = np.linalg.solve(G_eff, g_eff)
    theta, status, iters = _solve(G_eff, g_eff, theta_of_pi(pi_ls), prior)
    pi = pi_of_theta(theta)
    cov = covariance(_hessian_pi(G_eff, pi, prior))
    x = Gxx_inv @ (g[n:] - G[n:, :n] @ pi)
    x_std = np.sqrt(np.clip(np.diag(Gxx_inv), 0, None)) if A_x.shape[1] else np.zeros(0)
    return InertialFit(pi, 0.5 * (cov + cov.T), x, x_std, theta, pi_ls, status, iters)


def covariance(H: np.ndarray) -> np.ndarray:
    """(10, 10) the inverse of pi's Hessian H, refusing a flat direction.

    Raises:
        UnobservableError: a direction of H (columns scaled to unit diagonal) has an
            eigenvalue below ``FLAT_RCOND`` times the largest; the message names the
            parameters it mixes.
    """
    scale = np.sqrt(np.maximum(np.diag(H), 1e-300))
    e, V = np.linalg.eigh(H / np.outer(scale, scale))
    flat = e < FLAT_RCOND * e[-1]
    if np.any(flat):
        v = V[:, np.argmin(e)]
        names = [NAMES[i] for i in np.flatnonzero(np.abs(v) > 0.2 * np.abs(v).max())]
        raise UnobservableError(
            f"the data do not determine the payload's {' + '.join(names)} ({flat.sum()} flat "
            f"direction(s) of the information, scaled eigenvalue ratio {e[0] / e[-1]:.1e}): "
            "move every wrist joint, faster"
        )
    inv = (V / e) @ V.T / np.outer(scale, scale)
    return 0.5 * (inv + inv.T)


def _hessian_pi(G: np.ndarray, pi: np.ndarray, prior) -> np.ndarray:
    """(10, 10) the Hessian in pi of 1/2 pi^T G pi - g^T pi (+ the prior on (m, c = h / m))."""
    if prior is None:
        return G
    mean, cov = prior
    p = ca.SX.sym("pi", N_PARAMS)
    dev = ca.vertcat(p[0], p[1:4] / p[0]) - ca.DM(np.asarray(mean, float))
    f = 0.5 * ca.mtimes([dev.T, ca.DM(np.linalg.inv(cov)), dev])
    return G + np.asarray(ca.Function("H", [p], [ca.hessian(f, p)[0]])(pi))


def _solve(G, g, theta0, prior):
    """IPOPT on f(theta) = 1/2 pi^T G pi - g^T pi (+ prior); (theta, status, iters)."""
    th = ca.SX.sym("theta", N_PARAMS)
    pi = pi_of_theta(th)
    f = 0.5 * ca.mtimes([pi.T, ca.DM(G), pi]) - ca.dot(ca.DM(g), pi)
    if prior is not None:
        mean, cov = prior
        s_th = ca.vertcat(pi[0], th[7], th[8], th[9])  # (m, c) = (e^(2 alpha), t)
        dev = s_th - ca.DM(np.asarray(mean, float))
        f += 0.5 * ca.mtimes([dev.T, ca.DM(np.linalg.inv(cov)), dev])
    lbx = np.full(N_PARAMS, -np.inf)
    lbx[1:4] = LOG_SPREAD_MIN
    theta0 = np.maximum(theta0, lbx + 0.5)  # a start strictly inside the bound
    f0 = float(ca.Function("f0", [th], [f])(theta0))
    f_scaled = f / max(abs(f0), 1.0)  # IPOPT's tolerances on an O(1) objective
    opts = dict(IPOPT_OPTIONS)
    # the objective, scaled to O(1), is flat along a thin payload's spread: IPOPT reaches its
    # optimum to 1e-5..1e-7 and creeps on (its dual infeasibility wandering around 1e-6);
    # accept that (Solved_To_Acceptable_Level)
    opts.update({"ipopt.max_iter": 500, "ipopt.acceptable_tol": 1e-5, "ipopt.acceptable_iter": 5})
    # a line search's trial step may overflow exp(): IPOPT backtracks; not worth a warning
    opts["show_eval_warnings"] = False
    solver = ca.nlpsol("inertial_fit", "ipopt", {"x": th, "f": f_scaled}, opts)
    sol = solver(x0=theta0, lbx=lbx)
    stats = solver.stats()
    status = str(stats["return_status"])
    if status not in ("Solve_Succeeded", "Solved_To_Acceptable_Level"):
        raise SolverError("IPOPT did not fit the payload's inertial parameters", status,
                          stats.get("iter_count"))  # fmt: skip
    theta = np.asarray(sol["x"]).ravel()
    return theta, status, int(stats.get("iter_count", 0))
