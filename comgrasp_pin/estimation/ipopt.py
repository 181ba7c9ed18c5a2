"""The torque balance posed in CasADi and solved by IPOPT: what least squares cannot pose.

Residuals, one per joint and pose, in standard deviations of a torque difference:
``e = w * (Y theta(x) - b)``. The objective is the negative log posterior

    f(x) = sum_i rho(e_i) + 1/2 |(I - d d^T)(c - p)|^2 / s^2    (the second term with a prior)

- ``rho`` is 1/2 e^2 (``loss="l2"``) or the pseudo-Huber delta^2 (sqrt(1 + (e/delta)^2) - 1)
  (``loss="huber"``): quadratic near zero, linear beyond ``delta`` standard deviations, so a
  bump or a spike on one reading barely moves the estimate;
- without a prior the unknowns are the observable combination ``x = w`` of theta = B w
  (linear residuals: a convex problem);
- with an ``AxisPrior`` (point p, unit direction d, std s, ee frame) the unknowns are
  ``x = (m, c_ee)`` and theta = (m, m c_ee): the prior settles what the torques cannot see.

One ``nlpsol`` is built per (rows, unknowns, loss, prior) and cached, folded with the
objective's derivatives into one CasADi Function: a call gives the optimum, the Hessian,
gradient and value there in one array (building costs milliseconds, a solve a fraction of
one, and each extra call from Python or conversion of its outputs some 20 us after IPOPT
has run). ``cov`` is the inverse of the objective's Hessian at the optimum (the Laplace
approximation of the posterior).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cache

import casadi as ca
import numpy as np

from comgrasp_pin.errors import SolverError, UnobservableError

IPOPT_OPTIONS: dict = {
    "expand": True,  # MX -> SX: cheaper function evaluations
    "print_time": False,
    "record_time": False,
    "ipopt.print_level": 0,
    "ipopt.sb": "yes",
    "ipopt.tol": 1e-10,
    "ipopt.max_iter": 100,
}
"""Options of every IPOPT solver built here (quiet; a tight tolerance on a small problem)."""

_LINEAR_OPTIONS = {
    "ipopt.hessian_constant": "yes",
    "ipopt.jac_c_constant": "yes",
    "ipopt.jac_d_constant": "yes",
    "ipopt.nlp_scaling_method": "none",
}
"""Extra options where the problem is a linear least squares (l2, no prior)."""

_ACCEPTED = ("Solve_Succeeded", "Solved_To_Acceptable_Level")
_STALLED = "Search_Direction_Becomes_Too_Small"
"""IPOPT's status when it starts at (or reaches) the optimum of a well-scaled problem and
cannot step further; accepted when the gradient there is zero to GRADIENT_TOL."""
GRADIENT_TOL = 1e-8
"""A stalled solve is accepted when |grad f| <= GRADIENT_TOL (1 + |f|)."""


@dataclass(frozen=True)
class IpoptResult:
    """Solution x, its Hessian (the posterior's inverse covariance), IPOPT's status."""

    x: np.ndarray
    hessian: np.ndarray
    return_status: str
    iterations: int


@dataclass(frozen=True)
class IpoptProblem:
    """The cached problem: ``solve(x0, params)`` -> (x; vec(H); grad; f) at IPOPT's optimum.

    ``nlpsol`` is the bare IPOPT solver inside it (x0=..., p=...), for benchmarks.
    """

    nlpsol: ca.Function
    solve: ca.Function


@cache
def build(rows: int, p: int, loss: str, prior: bool) -> IpoptProblem:
    """The cached problem for ``rows`` residuals and ``p`` unknowns.

    The parameter vector is (vec(Y) column-major, b, w, delta, point, direction, 1/std):
    Y is (rows, p) without a prior (theta = x) and (rows, 4) with one (theta = (m, m c)).
    """
    x = ca.SX.sym("x", p)
    Y = ca.SX.sym("Y", rows, 4 if prior else p)
    b, w = ca.SX.sym("b", rows), ca.SX.sym("w", rows)
    delta, point, direction = ca.SX.sym("delta"), ca.SX.sym("point", 3), ca.SX.sym("d", 3)
    inv_std = ca.SX.sym("inv_std")
    theta = ca.vertcat(x[0], x[0] * x[1:4]) if prior else x
    e = w * (Y @ theta - b)
    if loss == "l2":
        f = 0.5 * ca.sumsqr(e)
    else:
        f = delta**2 * ca.sum1(ca.sqrt(1.0 + (e / delta) ** 2) - 1.0)
    if prior:
        dev = x[1:4] - point
        across = dev - direction * ca.dot(direction, dev)
        f += 0.5 * inv_std**2 * ca.sumsqr(across)
    params = ca.vertcat(ca.vec(Y), b, w, delta, point, direction, inv_std)
    options = dict(IPOPT_OPTIONS)
    if loss == "l2" and not prior:
        options.update(_LINEAR_OPTIONS)
    name = f"com_{loss}_{'prior' if prior else 'free'}_{rows}x{p}"
    solver = ca.nlpsol(name, "ipopt", {"x": x, "p": params, "f": f}, options)
    H, g = ca.hessian(f, x)
    derivatives = ca.Function(f"{name}_derivatives", [x, params], [H, g, f])
    x0_in, p_in = ca.MX.sym("x0", p), ca.MX.sym("p", params.shape[0])
    x_opt = solver(x0=x0_in, p=p_in)["x"]
    H_opt, g_opt, f_opt = derivatives(x_opt, p_in)
    out = ca.vertcat(x_opt, ca.vec(H_opt), g_opt, f_opt)
    return IpoptProblem(solver, ca.Function(f"{name}_solve", [x0_in, p_in], [out]))


def parameters(
    Y: np.ndarray, b: np.ndarray, w: np.ndarray, loss: str, delta: float, prior
) -> tuple[np.ndarray, float]:
    """(The parameter vector of ``build``, the objective's scale 1 / max(w)^2).

    IPOPT sees the objective scaled by 1 / max(w)^2 (the same minimiser, well scaled even
    for weights of 1e6); the caller scales the Hessian back.
    """
    root = 1.0 / float(w.max())
    if loss == "huber":  # e = w r: scaling w scales e; keep the threshold in the same units
        delta = delta * root
    if prior is None:
        tail = [delta, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]
    else:
        point, direction = prior.point_ee.tolist(), prior.direction_ee.tolist()
        tail = [delta, *point, *direction, root / prior.std]
    return np.concatenate([Y.ravel(order="F"), b, w * root, tail]), root * root


def solve(
    Y: np.ndarray,
    b: np.ndarray,
    w: np.ndarray,
    x0: np.ndarray,
    loss: str,
    delta: float,
    prior=None,
) -> IpoptResult:
    """Minimise the objective of the module docstring from ``x0``.

    Args:
        Y: (rows, p) regression of the unknowns (no prior) or (rows, 4) of theta (prior).
        b: (rows,) torque differences (N m).
        w: (rows,) 1 / their standard deviations (1 / N m).
        x0: (p,) start (the closed form's answer).
        loss: "l2" or "huber".
        delta: pseudo-Huber threshold (standard deviations).
        prior: an ``AxisPrior`` or None.

    Raises:
        SolverError: IPOPT did not converge (its status is kept).
    """
    params, scale = parameters(Y, b, w, loss, delta, prior)
    return run(build(len(b), len(x0), loss, prior is not None), x0, params, scale)


def run(problem: IpoptProblem, x0, params: np.ndarray, scale: float) -> IpoptResult:
    """``solve`` on a built problem and its parameter vector (``parameters``).

    Raises:
        SolverError: IPOPT did not converge (its status is kept).
    """
    p = len(x0)
    out = problem.solve(x0, params).full().ravel()
    stats = problem.solve.stats()
    status = str(stats.get("return_status", "unknown"))
    iterations = int(stats.get("iter_count", -1))
    x, H = out[:p], out[p : p + p * p].reshape(p, p)
    if status not in _ACCEPTED or not math.isfinite(sum(x.tolist())):
        # IPOPT's step may stall at an optimum it started at: accepted where |grad f| is 0
        grad, f = out[p + p * p : -1], float(out[-1])
        stalled_at_optimum = status == _STALLED and float(np.linalg.norm(grad)) <= (
            GRADIENT_TOL * (1 + abs(f))
        )
        if not (status in _ACCEPTED or stalled_at_optimum) or not np.all(np.isfinite(x)):
            raise SolverError("IPOPT failed on the CoM estimate", status, iterations)
    return IpoptResult(x, H / scale, status, iterations)


FLAT_RCOND = 1e-6
"""The posterior is flat where the Hessian's eigenvalues span more than 1 / FLAT_RCOND^2
(as the estimator's RCOND on singular values)."""


def laplace_covariance(H: np.ndarray) -> np.ndarray:
    """The covariance from the posterior's Hessian; UnobservableError where it is singular."""
    eig = np.linalg.eigvalsh(0.5 * (H + H.T))
    if not eig[0] > FLAT_RCOND * FLAT_RCOND * eig[-1]:
        raise UnobservableError(
            f"the posterior is flat in some direction (Hessian eigenvalues "
            f"{np.array2string(eig, precision=3)}): the data and the prior do not determine "
            "the estimate"
        )
    return np.linalg.inv(H)
