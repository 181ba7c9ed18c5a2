"""The estimate: a frozen result with its uncertainty, and how it is assembled.

theta = (m, m c_ee) (kg, kg m) is what the linear least squares delivers; the result holds
(m, c_ee) and their covariance (by the delta method from theta's, or the posterior's).
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass

import numpy as np

from comgrasp_pin.errors import EmptyGripperError, InvalidInputError, UnobservableError
from comgrasp_pin.estimation.regressor import G0

MIN_MASS_KG = 1e-3
"""Without torque_std, a payload below this mass (kg) is taken as an empty gripper."""
MASS_SIGMAS = 3.0
"""With torque_std, a payload below MASS_SIGMAS standard deviations is an empty gripper."""


@dataclass(frozen=True)
class ComEstimate:
    """A payload estimate. Frames: ``ee`` (the eelink) and ``world``; SI units.

    Attributes:
        com_ee: (3,) CoM in the ee frame (m); its component along ``unobservable_ee`` is 0.
        mass: payload mass (kg).
        weight: payload weight m * G0 (N).
        unobservable_ee: (3,) unit gravity direction in the ee frame along which the CoM is
            not observed (one pose), or None when the full 3-D CoM is estimated.
        cov: (4, 4) covariance of (mass, com_ee) (kg, m): from torque_std, or from the noise
            the residuals show where readings outnumber the unknowns (``noise_std``), else
            None; zero variance along ``unobservable_ee`` (that component is fixed at 0).
            With a prior (IPOPT), the posterior's (Laplace at the optimum).
        residual_rms: RMS of the torque residuals (N m).
        residuals: (k, n) residuals dtau - Y theta per pose and joint (N m).
        condition_number: largest / smallest singular value over the estimated directions.
        singular_values: (4,) singular values of the stacked Y for theta = (m, m c_ee) in SI
            units, descending; for one pose the last is 0 (the direction along gravity).
        method: "lstsq" or "ipopt".
        solver_status: IPOPT's return_status, or "closed_form" for lstsq.
        iterations: IPOPT iterations (0 for lstsq).
        n_poses: number of static poses k.
        T_world_ee: (k, 4, 4) ee poses at the measurement configurations.
        noise_std: std of a torque difference estimated from the residuals (N m) when no
            torque_std was given, else None.
    """

    com_ee: np.ndarray
    mass: float
    weight: float
    unobservable_ee: np.ndarray | None
    cov: np.ndarray | None
    residual_rms: float
    residuals: np.ndarray
    condition_number: float
    singular_values: np.ndarray
    method: str
    solver_status: str
    iterations: int
    n_poses: int
    T_world_ee: np.ndarray
    noise_std: float | None = None

    @property
    def std(self) -> np.ndarray | None:
        """(4,) standard deviations of (mass, com_ee) (kg, m), or None without cov."""
        return None if self.cov is None else np.sqrt(np.clip(np.diag(self.cov), 0.0, None))

    def com_world(self, pose: int = 0) -> np.ndarray:
        """(3,) CoM in the world frame (m) at measurement pose ``pose``."""
        T = self.T_world_ee[pose]
        return T[:3, :3] @ self.com_ee + T[:3, 3]

    def com_line_ee(self) -> tuple[np.ndarray, np.ndarray | None]:
        """The CoM locus in the ee frame.

        Returns:
            (point (3,), direction (3,)) of the vertical line through the CoM for one pose,
            or (com_ee, None) when fully observed.
        """
        return self.com_ee, self.unobservable_ee


NEAR_SINGULAR = 100.0
"""A refused estimate whose torque regression has a condition number above this (good poses:
5-30) is reported as unobservable (a near-singular pose set), not as an empty gripper."""


def delta_method(theta: np.ndarray, cov_theta: np.ndarray) -> np.ndarray:
    """(4, 4) covariance of (m, c) = (theta_0, theta_1:4 / theta_0) from that of theta."""
    m = theta[0]
    G = np.zeros((4, 4))
    G[0, 0] = 1.0
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):  # m ~ 0: refused later
        com = theta[1:] / m
        G[1:, 0] = -com / m
        G[1:, 1:] = np.eye(3) / m
        return G @ cov_theta @ G.T


@contextmanager
def singular_is_unobservable() -> Iterator[None]:
    """Turn NumPy's LinAlgError (a singular matrix) into UnobservableError; a decorator too."""
    try:
        yield
    except np.linalg.LinAlgError as exc:
        raise UnobservableError(
            f"the regression is numerically singular ({exc}): the poses do not determine the "
            "estimate (a larger rcond refuses such pose sets up front)"
        ) from None


def check_finite_result(**values: float | np.ndarray | None) -> None:
    """InvalidInputError naming the results that are NaN or inf (None is fine).

    An estimate never carries a NaN or an infinity: the readings behind one are out of any
    arm's range, or the problem is degenerate beyond what the solver can report.
    """
    bad = [k for k, v in values.items() if v is not None and not np.all(np.isfinite(v))]
    if bad:
        raise InvalidInputError(
            f"the estimate's {', '.join(bad)} would not be finite: the torque readings are "
            "out of range for this arm, or the poses are degenerate"
        )


def refuse_empty_gripper(mass: float, mass_var: float | None, cond: float) -> None:
    """EmptyGripperError (or UnobservableError) when ``mass`` (kg) is not measurably positive.

    Args:
        mass: the estimated mass (kg).
        mass_var: its variance (kg^2), or None without a covariance.
        cond: the condition number of the torque regression.
    """
    threshold = MIN_MASS_KG if mass_var is None else MASS_SIGMAS * math.sqrt(max(mass_var, 0.0))
    if mass > threshold:
        return
    if mass_var is not None and cond > NEAR_SINGULAR:
        raise UnobservableError(
            f"the pose set is near singular (condition number {cond:.3g} > "
            f"{NEAR_SINGULAR:g}): the estimate {mass:.3g} kg +- {threshold / MASS_SIGMAS:.3g} "
            "kg is swamped by its error bar; measure away from singular configurations"
        )
    what = f"{MASS_SIGMAS:g} standard deviations" if mass_var is not None else "MIN_MASS_KG"
    raise EmptyGripperError(
        f"estimated payload mass {mass:.3g} kg is not measurably above zero (threshold "
        f"{threshold:.3g} kg = {what}): is the gripper empty, or are tau_before and "
        "tau_after swapped?"
    )


def assemble_estimate(
    mass: float,
    com_ee: np.ndarray,
    cov: np.ndarray | None,
    u: np.ndarray | None,
    residuals: np.ndarray,
    sv: np.ndarray,
    cond: float,
    method: str,
    status: str,
    iters: int,
    T: np.ndarray,
    noise_std: float | None = None,
) -> ComEstimate:
    """The frozen estimate, or an error when its mass is not measurably positive.

    Args:
        mass: kg.
        com_ee: (3,) m.
        cov: (4, 4) covariance of (mass, com_ee), or None.
        u: (3,) unobservable direction (ee) or None.
        residuals: (k, n) N m.
        sv: singular values of the torque regression.
        cond: its condition number.
        method: the solver's name.
        status: its status.
        iters: its iterations.
        T: (k, 4, 4) T_world_ee at the poses.
        noise_std: std of a torque difference estimated from the residuals (N m), when
            torque_std was not given; None otherwise.

    Raises:
        UnobservableError: the mass is within MASS_SIGMAS standard deviations of zero and the
            regression is near singular (condition number above NEAR_SINGULAR).
        EmptyGripperError: the mass is not measurably above zero (MASS_SIGMAS standard
            deviations, or MIN_MASS_KG without a covariance).
    """
    m = float(mass)
    refuse_empty_gripper(m, None if cov is None else float(cov[0, 0]), float(cond))
    residuals = np.array(residuals, dtype=float)
    return new_estimate(
        np.array(com_ee, dtype=float),
        m,
        None if cov is None else np.array(cov, dtype=float),
        None if u is None else np.array(u, dtype=float),
        residuals,
        math.sqrt(float(residuals.ravel() @ residuals.ravel()) / residuals.size),
        np.array(sv, dtype=float),
        float(cond),
        method,
        status,
        iters,
        np.array(T, dtype=float),
        noise_std,
    )


def new_estimate(
    com_ee: np.ndarray,
    mass: float,
    cov: np.ndarray | None,
    u: np.ndarray | None,
    residuals: np.ndarray,
    rms: float,
    sv: np.ndarray,
    cond: float,
    method: str,
    status: str,
    iters: int,
    T: np.ndarray,
    noise_std: float | None,
) -> ComEstimate:
    """The ``ComEstimate`` of arrays this package owns (made read-only here, not copied).

    ``rms`` is that of ``residuals`` (k, n). Refuses non-finite results (InvalidInputError).
    """
    # Python float sums never warn: NaN or inf anywhere (or an overflowing sum) shows here,
    # and check_finite_result then names what is not finite
    screen = mass + rms + sum(com_ee.tolist())
    if cov is not None:
        screen += sum(cov.ravel().tolist())
    if not math.isfinite(screen):
        check_finite_result(mass=mass, com_ee=com_ee, cov=cov, residual_rms=rms)
    for a in (com_ee, u, cov, residuals, sv, T):
        if a is not None:
            a.setflags(write=False)
    return construct(com_ee, mass, cov, u, residuals, rms, sv, cond, method, status, iters, T,
                     noise_std)  # fmt: skip


def construct(com_ee, mass, cov, u, residuals, rms, sv, cond, method, status, iters, T,
              noise_std) -> ComEstimate:  # fmt: skip
    """The ``ComEstimate`` of checked, read-only fields (``new_estimate``'s last step).

    The dataclass's own ``__init__`` sets each of its 15 fields through
    ``object.__setattr__`` (it is frozen), 2 us of a 10 us estimate; the instance
    dictionary is filled in one step instead, with the same fields.
    """
    est = object.__new__(ComEstimate)
    object.__setattr__(est, "__dict__", {
        "com_ee": com_ee,
        "mass": mass,
        "weight": mass * G0,
        "unobservable_ee": u,
        "cov": cov,
        "residual_rms": rms,
        "residuals": residuals,
        "condition_number": cond,
        "singular_values": sv,
        "method": method,
        "solver_status": status,
        "iterations": iters,
        "n_poses": residuals.shape[0],
        "T_world_ee": T,
        "noise_std": noise_std,
    })  # fmt: skip
    return est
