"""The estimate: a frozen result with its uncertainty, and how it is assembled.

theta = (m, m c_ee) (kg, kg m) is what the linear least squares delivers; the result holds
(m, c_ee) and their covariance (by the delta method from theta's, or the posterior's).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from comgrasp_pin.errors import EmptyGripperError, InvalidInputError, UnobservableError

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
        weight: payload weight m |g| (N), g the robot model's gravity.
        unobservable_ee: (3,) unit gravity direction in the ee frame along which the CoM is
            not observed (one pose), or None when the full 3-D CoM is estimated.
        cov: (4, 4) covariance of (mass, com_ee) (kg, m): from torque_std (or dtau_cov), or
            from the noise the residuals show where readings outnumber the unknowns, else
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
        torque_std: std of one torque reading (N m) as the residuals show it (the residuals'
            std over sqrt(2), a difference being of two readings), where no torque_std or
            dtau_cov was given and readings outnumber the unknowns; else None.
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
    torque_std: float | None = None

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


def mc_jacobian(theta: np.ndarray) -> np.ndarray:
    """(4, 4) G = d(m, c)/d theta = [[1, 0], [-c / m, I / m]] at theta = (m, m c).

    A mass within 1e-12 kg of zero, always refused by ``refuse_empty_gripper`` (its
    threshold is at least 3 standard deviations of readings no better than 1e-9 N m), gets
    1 / m = 0: the mass's own variance stays right and nothing overflows.
    """
    m = float(theta[0])
    inv_m = 1.0 / m if abs(m) > 1e-12 else 0.0
    G = np.zeros((4, 4))
    G[0, 0] = 1.0
    G[1:, 0] = theta[1:] * (-inv_m * inv_m)
    G[1, 1] = G[2, 2] = G[3, 3] = inv_m
    return G


def delta_method(theta: np.ndarray, cov_theta: np.ndarray) -> np.ndarray:
    """(4, 4) covariance of (m, c) = (theta_0, theta_1:4 / theta_0) from that of theta."""
    G = mc_jacobian(theta)
    return G @ cov_theta @ G.T


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
