"""The payload least squares posed symbolically in CasADi and solved by IPOPT.

    minimise_w  0.5 * || Y w - b ||^2      Y (rows, p), b (rows,) are parameters

One ``nlpsol`` is built per (rows, p) = (k poses * n joints, number of observable unknowns)
and cached: building costs tens of ms, a solve about 0.4 ms. The problem is a convex
quadratic, so IPOPT with the exact (constant) Hessian takes one Newton step; the options tell
IPOPT that the Hessian is constant and skip its NLP scaling. Every solve starts from w = 0
(no warm start from a previous answer), so timings are fair.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache

import casadi as ca
import numpy as np

from comgrasp_pin.errors import SolverError

IPOPT_OPTIONS: dict = {
    "expand": True,  # MX -> SX: cheaper function evaluations
    "print_time": False,
    "record_time": False,
    "ipopt.print_level": 0,
    "ipopt.sb": "yes",
    "ipopt.hessian_constant": "yes",
    "ipopt.jac_c_constant": "yes",
    "ipopt.jac_d_constant": "yes",
    "ipopt.nlp_scaling_method": "none",
    "ipopt.tol": 1e-10,
    "ipopt.max_iter": 50,
}
"""Options of every IPOPT solver built here (quiet, tuned for a linear least squares)."""

_ACCEPTED = ("Solve_Succeeded", "Solved_To_Acceptable_Level")


@dataclass(frozen=True)
class IpoptResult:
    """Solution w (p,), IPOPT's return_status and iteration count."""

    w: np.ndarray
    return_status: str
    iterations: int


@cache
def lsq_solver(rows: int, p: int) -> ca.Function:
    """The cached IPOPT solver for a (rows, p) problem; parameter = (vec(Y) column-major, b)."""
    Y = ca.SX.sym("Y", rows, p)
    b = ca.SX.sym("b", rows)
    w = ca.SX.sym("w", p)
    r = Y @ w - b
    nlp = {"x": w, "p": ca.vertcat(ca.vec(Y), b), "f": 0.5 * ca.dot(r, r)}
    return ca.nlpsol(f"com_lsq_{rows}x{p}", "ipopt", nlp, IPOPT_OPTIONS)


def solve_lsq(Y: np.ndarray, b: np.ndarray) -> IpoptResult:
    """Solve min ||Y w - b|| with IPOPT; SolverError (with IPOPT's status) if it fails."""
    rows, p = Y.shape
    solver = lsq_solver(rows, p)
    params = np.concatenate([Y.ravel(order="F"), b])
    sol = solver(x0=np.zeros(p), p=params)
    stats = solver.stats()
    status = str(stats.get("return_status", "unknown"))
    iterations = int(stats.get("iter_count", -1))
    w = np.asarray(sol["x"], dtype=float).ravel()
    if status not in _ACCEPTED or not np.all(np.isfinite(w)):
        raise SolverError("IPOPT failed on the CoM least squares", status, iterations)
    return IpoptResult(w, status, iterations)
