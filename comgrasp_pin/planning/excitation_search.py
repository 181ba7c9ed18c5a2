"""The search behind ``excitation.plan_excitation``: random motions, then CasADi + IPOPT.

A motion is the free Fourier coefficients Z ((2L - 2, n), ``motion.fourier.rest_basis``);
q, qd, qdd on a grid are linear in Z, so the joint limits are linear constraints. The
objective, log tr(M) + log tr(M^-1) with M = A^T A of the column-scaled stacked payload
regressor A, is smooth and bounds the condition number (cond(M) <= tr(M) tr(M^-1)); IPOPT
gets its gradient by CasADi's finite differences of the Pinocchio regressor (a
``casadi.Callback``) and a limited-memory Hessian.

The numbers that tune an excitation motion and its search, and their ranges.

``ExcitationSettings`` holds them (units in the names; what each does: ``excitation``);
``checked_settings`` refuses one out of its range, naming it.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np

from comgrasp_pin import validate
from comgrasp_pin.errors import CollisionError, SolverError
from comgrasp_pin.estimation.payload_regressor import condition_number, regressor_rows
from comgrasp_pin.motion.fourier import FourierMotion, basis, rest_basis
from comgrasp_pin.robot import RobotModel


@dataclass(frozen=True)
class ExcitationSettings:
    """Every number that tunes the motion and its search (units in the names; see module).

    ``periods`` repetitions of the fundamental period fill the duration; ``harmonics`` per
    period. Limits: ``velocity_scale`` of the URDF's, ``acceleration_limit`` (rad/s^2 or
    m/s^2, every joint), ``position_margin_rad`` inside the URDF's. The joints before the
    wrist keep ``arm_range_rad`` and ``arm_rate_scale`` of the velocity and acceleration
    limits. Search: ``samples_per_period`` grid points, ``n_random`` random motions,
    ``n_starts`` IPOPT refinements of ``max_iter`` iterations each, checked for collisions every
    ``check_every_iter`` iterations.

    The defaults are measured (``benchmarks/inertia_from_motion.py``): a payload's inertia
    shows in its torques in proportion to the accelerations, which a velocity limit caps at
    v * omega, so four 5 s periods at 0.8 of the URDF's velocity reach them where two 10 s
    periods at 0.5 do not (UR5: condition number 270 -> 72, moments off by up to 44 % ->
    within 10 %). 7.5 rad/s^2 is the Franka Panda's smallest joint acceleration limit
    (joint 2, Franka's data sheet); a UR arm's wrists allow more (``--acceleration 12``).
    """

    periods: int = 4
    harmonics: int = 5
    velocity_scale: float = 0.8
    acceleration_limit: float = 7.5
    position_margin_rad: float = 0.1
    wrist_joints: int = 3
    wrist_range_rad: float = 1.5
    arm_range_rad: float = 0.3
    arm_rate_scale: float = 1.0
    min_height_m: float = 0.05
    typical_length_m: float = 0.1
    sample_period_s: float = 0.01
    samples_per_period: int = 100
    n_random: int = 1000
    n_starts: int = 3
    max_iter: int = 60
    check_every_iter: int = 10


def checked_settings(s: ExcitationSettings) -> ExcitationSettings:
    """``s`` if every number is in its range, else InvalidInputError naming the field."""
    for name in ("velocity_scale", "acceleration_limit", "wrist_range_rad", "typical_length_m",
                 "sample_period_s", "arm_rate_scale"):  # fmt: skip
        validate.number(getattr(s, name), name, low=0, low_open=True)
    for name in ("position_margin_rad", "arm_range_rad", "min_height_m"):
        validate.number(getattr(s, name), name, low=0)
    validate.number(s.velocity_scale, "velocity_scale", high=1)
    validate.number(s.arm_rate_scale, "arm_rate_scale", high=1)
    for name, low in (("periods", 1), ("harmonics", 2), ("wrist_joints", 1),
                      ("samples_per_period", 10), ("n_random", 1), ("n_starts", 1),
                      ("max_iter", 0), ("check_every_iter", 1)):  # fmt: skip
        validate.integer(getattr(s, name), name, low=low)
    return s


ACCEPTED = ("Solve_Succeeded", "Solved_To_Acceptable_Level", "Maximum_Iterations_Exceeded")
"""IPOPT statuses whose point is used (every iterate keeps the linear limits)."""
BACKTRACK_STEPS = 6  # halvings towards the seed when a refined motion collides
FD_STEP = 1e-6  # finite-difference step of the objective's gradient (rad/s)


@dataclass(frozen=True)
class Limits:
    """Per-joint limits (n,): position bounds (rad), velocity (rad/s), acceleration (rad/s^2)."""

    lower: np.ndarray
    upper: np.ndarray
    velocity: np.ndarray
    acceleration: np.ndarray


class Grid:
    """The optimiser's grid over one period: Z -> (q, qd, qdd), and the objective."""

    def __init__(self, robot, start, period_s, harmonics, samples, scale):
        t = np.linspace(0.0, period_s, samples, endpoint=False)
        N = rest_basis(harmonics)
        self.B = [B @ N for B in basis(t, period_s, harmonics)]  # each (samples, 2L - 2)
        self.robot, self.start, self.period_s, self.scale = robot, start, period_s, scale
        self.shape = (2 * harmonics - 2, robot.nq)

    def motion(self, Z: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """q, qd, qdd (samples, n) of the free coefficients Z."""
        B_q, B_qd, B_qdd = self.B
        return self.start + B_q @ Z, B_qd @ Z, B_qdd @ Z

    def scaled_regressor(self, Z: np.ndarray) -> np.ndarray:
        """(samples * n, 10) stacked payload regressor of Z, columns scaled."""
        return regressor_rows(self.robot, *self.motion(Z)).reshape(-1, 10) * self.scale

    def objective(self, x: np.ndarray) -> float:
        """The value log tr(M) + log tr(M^-1) of the motion ``x`` (Z, column-major)."""
        A = self.scaled_regressor(x.reshape(self.shape))
        eig = np.linalg.eigvalsh(A.T @ A)
        if eig[0] <= 1e-12 * eig[-1]:
            return 50.0  # rank deficient: worse than any motion that sees all ten
        return float(np.log(eig.sum()) + np.log(np.sum(1.0 / eig)))

    def fit_to_limits(self, Z: np.ndarray, lim: Limits) -> np.ndarray:
        """Z with each joint's column scaled so that its tightest limit is just met."""
        dq, qd, qdd = self.motion(Z)
        dq = dq - self.start
        with np.errstate(divide="ignore"):
            up = np.where(dq.max(0) > 0, (lim.upper - self.start) / dq.max(0), np.inf)
            down = np.where(dq.min(0) < 0, (lim.lower - self.start) / dq.min(0), np.inf)
            s = np.minimum.reduce(
                [up, down, lim.velocity / np.abs(qd).max(0), lim.acceleration / np.abs(qdd).max(0)]
            )
        return Z * s


class _Objective(ca.Callback):
    """The grid's objective as a CasADi function of x, differentiated by finite differences."""

    def __init__(self, grid: Grid):
        ca.Callback.__init__(self)
        self.grid, self.nx = grid, int(np.prod(grid.shape))
        opts: dict[str, Any] = {"enable_fd": True, "fd_method": "forward",
                                "fd_options": {"h": FD_STEP}}  # fmt: skip
        self.construct("excitation_objective", opts)

    def get_n_in(self):
        return 1

    def get_n_out(self):
        return 1

    def get_sparsity_in(self, i):
        return ca.Sparsity.dense(self.nx, 1)

    def get_sparsity_out(self, i):
        return ca.Sparsity.dense(1, 1)

    def eval(self, arg):
        return [self.grid.objective(np.asarray(arg[0]).ravel())]


def _solver(grid: Grid, lim: Limits, max_iter: int):
    """IPOPT over x = vec(Z) (column-major: joint by joint) with the linear limits.

    Returns the solver, the bounds of its constraints and the Callback (which must outlive
    the solver).
    """
    B_q, B_qd, B_qdd = grid.B
    n = grid.shape[1]
    G = np.vstack([np.kron(np.eye(n), B) for B in (B_q, B_qd, B_qdd)])
    k = len(B_q)
    lbg = np.concatenate([np.repeat(lim.lower - grid.start, k), np.repeat(-lim.velocity, k),
                          np.repeat(-lim.acceleration, k)])  # fmt: skip
    ubg = np.concatenate([np.repeat(lim.upper - grid.start, k), np.repeat(lim.velocity, k),
                          np.repeat(lim.acceleration, k)])  # fmt: skip
    f = _Objective(grid)
    x = ca.MX.sym("x", f.nx)
    nlp: dict[str, Any] = {"x": x, "f": f(x), "g": ca.mtimes(ca.DM(G), x)}
    opts: dict[str, Any] = {"ipopt.max_iter": max_iter, "ipopt.print_level": 0, "print_time": False,
            "ipopt.sb": "yes", "ipopt.hessian_approximation": "limited-memory",
            "ipopt.tol": 1e-6}  # fmt: skip
    return ca.nlpsol("excitation", "ipopt", nlp, opts), lbg, ubg, f


def random_motions(
    grid: Grid, lim: Limits, count: int, rng: np.random.Generator
) -> list[np.ndarray]:
    """``count`` random motions Z, each joint scaled to its tightest limit on the grid.

    The free coefficients are standard normal: the baseline a planner should beat.
    """
    return [grid.fit_to_limits(rng.standard_normal(grid.shape), lim) for _ in range(count)]


def search(
    robot: RobotModel,
    start: np.ndarray,
    period_s: float,
    lim: Limits,
    scale: np.ndarray,
    s,
    seed: int,
    is_free: Callable[[FourierMotion, np.ndarray], bool],
    say: Callable[[str], None],
) -> tuple[FourierMotion, list[str]]:
    """The best motion found (``s``: ExcitationSettings) and IPOPT's statuses."""
    grid = Grid(robot, start, period_s, s.harmonics, s.samples_per_period, scale)
    t_grid = np.linspace(0.0, period_s, s.samples_per_period, endpoint=False)
    rng = np.random.default_rng(seed)
    say(f"random search: {s.n_random} Fourier motions")
    candidates = random_motions(grid, lim, s.n_random, rng)
    order = np.argsort([condition_number(grid.scaled_regressor(Z)) for Z in candidates])
    seeds = []
    for i in order:
        if is_free(FourierMotion.from_free(start, candidates[i], period_s), t_grid):
            seeds.append(candidates[i])
        if len(seeds) == s.n_starts:
            break
    if not seeds:
        raise CollisionError(
            f"none of {s.n_random} random motions is free of collision and the floor: give "
            "another start, or smaller ranges"
        )
    solver, lbg, ubg, _keep = _solver(grid, lim, s.check_every_iter)
    best, best_cond, statuses = seeds[0], condition_number(grid.scaled_regressor(seeds[0])), []
    for j, Z0 in enumerate(seeds):
        say(f"IPOPT refinement {j + 1}/{len(seeds)} (at most {s.max_iter} iterations)")
        Z, status = _refine(solver, lbg, ubg, Z0, s, lambda Z: is_free(
            FourierMotion.from_free(start, Z, period_s), t_grid))  # fmt: skip
        statuses.append(status)
        cond = condition_number(grid.scaled_regressor(Z))
        if cond < best_cond:
            best, best_cond = Z, cond
    if statuses and all(st not in ACCEPTED for st in statuses):
        raise SolverError("every IPOPT refinement of the excitation motion failed", statuses[0])
    return FourierMotion.from_free(start, best, period_s), statuses


def _refine(solver, lbg, ubg, Z0: np.ndarray, s, free: Callable) -> tuple[np.ndarray, str]:
    """IPOPT from the free motion ``Z0``, checked for collisions on the way.

    Chunks of ``s.check_every_iter`` iterations (up to ``s.max_iter``); returns the last
    free point, or the first colliding one pulled back towards it, and IPOPT's last status.
    """
    Z_free, status = Z0, "not run"
    for _ in range(-(-s.max_iter // s.check_every_iter)):
        sol = solver(x0=Z_free.ravel(order="F"), lbg=lbg, ubg=ubg)
        status = solver.stats()["return_status"]
        if status not in ACCEPTED:
            break
        Z = np.asarray(sol["x"]).ravel().reshape(Z0.shape, order="F")
        if not free(Z):
            return _free_towards(Z, Z_free, free), status
        Z_free = Z
        if status != "Maximum_Iterations_Exceeded":
            break  # converged
    return Z_free, status


def _free_towards(Z: np.ndarray, Z_free: np.ndarray, free: Callable) -> np.ndarray:
    """``Z`` if free, else the first of Z_free + (Z - Z_free) / 2^i that is (or Z_free)."""
    for i in range(BACKTRACK_STEPS + 1):
        candidate = Z_free + (Z - Z_free) / 2**i
        if free(candidate):
            return candidate
    return Z_free
