"""A payload and a wrist sensor's bias from the wrench at rest in several orientations.

At rest, a force/torque sensor holding a body of mass m with its CoM at c (sensor frame)
reads, in orientation k (gravity g_k in the sensor frame, m/s^2),

    f_k   = m g_k              + b_f
    tau_k = (m c) x g_k        + b_tau   = -[g_k]x (m c) + b_tau

with b = (b_f, b_tau) the sensor's six offsets (its bias). The reading is linear in
theta = (m, m c, b_f, b_tau) (10 unknowns, 6 rows per orientation): a weighted linear least
squares, closed form. What it needs:

- m and b_f: gravity in at least two directions (the force's change is m times gravity's);
- m c and b_tau: the torque changes by -[g_j - g_k]x m c, which leaves m c's component along
  g_j - g_k unseen; two non-parallel changes see all of it. Three distinct orientations give
  them (three points of a sphere are never on one line), rotations about one horizontal axis
  too; nearly equal ones give them badly. ``check_orientations`` measures gravity's spread
  and, where it is too small, names the rotation of the sensor that would add it.

The covariance is the least squares' (A^T W A)^-1 with W from each window's own noise (or
the inverse of the readings' full covariance, ``wrench_cov``: a sensor's drift shared across
windows), scaled by the residuals' chi-square per degree of freedom where that exceeds 1
(errors the noise model leaves out then show in the residuals). (m, c) and their covariance
follow by the delta method.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from comgrasp_pin.errors import InvalidInputError, UnobservableError
from comgrasp_pin.estimation.estimate import MASS_SIGMAS

N_UNKNOWNS = 10
MIN_ORIENTATIONS = 3
MIN_SPREAD_DEG = 10.0
"""Gravity's direction in the sensor frame must spread by at least this much (deg, RMS about
its mean) along two directions. Below it a CoM coordinate is known only from torque changes
smaller than about sin(10 deg) = 17 % of the payload's moment, and the CoM's error grows as
the inverse of the spread."""


@dataclass(frozen=True)
class StaticWrenchFit:
    """A payload (sensor frame) and the sensor's bias from k orientations at rest (SI units).

    Attributes:
        mass: kg.
        com_sensor: (3,) CoM in the sensor frame (m).
        cov: (4, 4) covariance of (mass, com_sensor) (kg, m).
        bias: (6,) the sensor's offsets: force (N), torque (N m), sensor frame.
        bias_std: (6,) their standard deviations.
        theta: (10,) m, m c, b_f, b_tau as fitted; theta_cov: (10, 10) their covariance.
        residuals: (k, 6) measured minus fitted wrench per orientation (N, N m).
        chi2_dof: the weighted residuals' chi-square per degree of freedom (nan with none).
        scale: the factor the covariance was multiplied by, max(1, chi2_dof) (1 with no
            degree of freedom).
        n_orientations: k.
        spread_deg: (2,) gravity's RMS change of direction along the two tangent directions
            (deg), largest first.
        held: whether a payload is seen: its mass above ``MASS_SIGMAS`` standard deviations.
            Where it is not, the CoM is not defined: ``com_sensor`` and its rows of ``cov``
            are NaN, and the mass's interval holds zero.
    """

    mass: float
    com_sensor: np.ndarray
    cov: np.ndarray
    bias: np.ndarray
    bias_std: np.ndarray
    theta: np.ndarray
    theta_cov: np.ndarray
    residuals: np.ndarray
    chi2_dof: float
    scale: float
    n_orientations: int
    spread_deg: np.ndarray
    held: bool

    @property
    def cov_dof(self) -> float:
        """The degrees of freedom of ``cov``: 6 k - 10 where the residuals scaled it, else inf."""
        return float(6 * self.n_orientations - N_UNKNOWNS) if self.scale > 1 else np.inf


def skew(v: np.ndarray) -> np.ndarray:
    """[v]x, the matrix of v x ."""
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def regressor(g_sensor: np.ndarray) -> np.ndarray:
    """(6k, 10) rows of the reading in theta = (m, m c, b_f, b_tau), per orientation."""
    rows = []
    for g in g_sensor:
        A = np.zeros((6, N_UNKNOWNS))
        A[:3, 0] = g
        A[3:, 1:4] = -skew(g)
        A[:, 4:] = np.eye(6)
        rows.append(A)
    return np.vstack(rows)


def _spread(g_sensor: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """How gravity's direction (unit vectors u_k) changes over the orientations.

    Returns the RMS spread of u_k about their mean along the scatter's principal directions
    (3,) (largest first; a unit vector's change, about its angle in rad for small ones),
    those directions (3, 3) as rows, and the mean direction (3,).
    """
    u = g_sensor / np.linalg.norm(g_sensor, axis=1, keepdims=True)
    mean = u.mean(axis=0)
    d = u - mean
    w, V = np.linalg.eigh(d.T @ d / len(u))
    order = np.argsort(w)[::-1]
    return np.sqrt(np.clip(w[order], 0, None)), V[:, order].T, mean


def _missing_rotation(g_sensor: np.ndarray, spread: np.ndarray, dirs: np.ndarray, mean) -> str:
    """The rotation of the sensor that would change gravity's direction where it did not."""
    up = mean / max(np.linalg.norm(mean), 1e-12)
    if np.degrees(spread[0]) < MIN_SPREAD_DEG:  # gravity never moved: tilt about two axes
        tilt = np.abs(np.eye(3) @ up)
        a, b = (int(i) for i in np.argsort(tilt)[:2])
        return (
            f"tilts of the sensor about two axes across gravity (its {'xyz'[a]} and "
            f"{'xyz'[b]} axes here); turning about gravity's own axis does not count"
        )
    axis = dirs[0] - (dirs[0] @ up) * up  # rotating about the direction gravity moved
    axis /= np.linalg.norm(axis)  # along tilts it across that direction
    name = "xyz"[int(np.argmax(np.abs(axis)))]
    return (
        f"a rotation of the sensor about its axis [{axis[0]:+.2f}, {axis[1]:+.2f}, "
        f"{axis[2]:+.2f}] (mostly {name}) by 30 deg or more in some of the poses"
    )


def check_orientations(g_sensor: np.ndarray, sensor_frame: str = "sensor") -> np.ndarray:
    """The spread of gravity's direction (2,) (deg); raise if it does not determine theta.

    Three distinct orientations determine the ten unknowns (the changes of gravity between
    them span a plane); the check asks for a spread of ``MIN_SPREAD_DEG`` along the two
    largest principal directions of gravity's scatter.

    Raises:
        UnobservableError: fewer than ``MIN_ORIENTATIONS`` orientations, or too little
            spread; the message names the rotation of the sensor that would add it.
    """
    k = len(g_sensor)
    if k < MIN_ORIENTATIONS:
        raise UnobservableError(
            f"{k} orientation(s) of the sensor at rest; the mass, the CoM and the sensor's "
            f"six offsets need at least {MIN_ORIENTATIONS}, with gravity in different "
            "directions in the sensor frame (comgrasp plan-poses plans them)"
        )
    spread, dirs, mean = _spread(g_sensor)
    spread_deg = np.degrees(spread[:2])
    if spread_deg[1] < MIN_SPREAD_DEG:
        raise UnobservableError(
            f"gravity's direction in the {sensor_frame} frame spreads by only "
            f"{spread_deg[0]:.1f} and {spread_deg[1]:.1f} deg (RMS, along its two main "
            f"directions) over the {k} orientations; at least {MIN_SPREAD_DEG:g} deg along "
            f"both is needed. Missing: {_missing_rotation(g_sensor, spread, dirs, mean)}"
        )
    return spread_deg


def fit_static_wrench(
    g_sensor: np.ndarray,
    wrench: np.ndarray,
    wrench_std: np.ndarray | None,
    sensor_frame: str = "sensor",
    known_cov: np.ndarray | None = None,
    wrench_cov: np.ndarray | None = None,
) -> StaticWrenchFit:
    """Mass, CoM (sensor frame) and the sensor's bias from k orientations at rest.

    Args:
        g_sensor: (k, 3) gravity in the sensor frame at each orientation (m/s^2).
        wrench: (k, 6) the mean reading there: force (N), torque (N m), sensor frame.
        wrench_std: (k, 6) or (6,) standard deviation of each mean reading (N, N m), > 0.
        sensor_frame: the frame's name, for messages.
        known_cov: (4, 4) covariance (kg, kg m) of a body's (m, m c) already taken out of
            ``wrench`` (a tool identified before), added to the fit's; None for none.
        wrench_cov: (6 k, 6 k) the readings' full covariance, orientation-major (N, N m),
            used instead of ``wrench_std`` (which may then be None): a drift shared by the
            windows (``estimation.drift``); None for ``wrench_std``'s independent noise.

    Raises:
        InvalidInputError: shapes, NaN or a std that is not > 0.
        UnobservableError: the orientations do not determine the unknowns
            (``check_orientations``).
    """
    g_sensor = np.asarray(g_sensor, dtype=float)
    wrench = np.asarray(wrench, dtype=float)
    k = len(g_sensor)
    if g_sensor.shape != (k, 3) or wrench.shape != (k, 6):
        raise InvalidInputError(
            f"g_sensor must be (k, 3) and wrench (k, 6); got {g_sensor.shape}, {wrench.shape}"
        )
    if not (np.all(np.isfinite(g_sensor)) and np.all(np.isfinite(wrench))):
        raise InvalidInputError("g_sensor and wrench must be finite (no NaN or inf)")
    spread = check_orientations(g_sensor, sensor_frame)
    whiten = _whitening(wrench_std, wrench_cov, k)
    A, b = regressor(g_sensor), wrench.ravel()
    Aw = whiten(A)
    info = Aw.T @ Aw
    theta = np.linalg.lstsq(Aw, whiten(b), rcond=None)[0]
    residuals = (b - A @ theta).reshape(k, 6)
    dof = 6 * k - N_UNKNOWNS
    chi2_dof = float(np.sum(whiten(residuals.ravel()) ** 2) / dof) if dof > 0 else float("nan")
    scale = max(1.0, chi2_dof) if dof > 0 else 1.0
    theta_cov = scale * np.linalg.inv(info)
    if known_cov is not None:
        theta_cov[:4, :4] += known_cov
    m = float(theta[0])
    held = m > MASS_SIGMAS * np.sqrt(theta_cov[0, 0])
    J = np.zeros((4, N_UNKNOWNS))  # d(m, c) / d theta, c = (m c) / m
    J[0, 0] = 1.0
    J[1:, 0] = -theta[1:4] / m**2 if held else np.nan
    J[1:, 1:4] = np.eye(3) / m if held else np.nan
    cov = J @ theta_cov @ J.T
    return StaticWrenchFit(
        mass=m,
        com_sensor=theta[1:4] / m if held else np.full(3, np.nan),
        cov=0.5 * (cov + cov.T),
        bias=theta[4:].copy(),
        bias_std=np.sqrt(np.diag(theta_cov)[4:]),
        theta=theta,
        theta_cov=theta_cov,
        residuals=residuals,
        chi2_dof=chi2_dof,
        scale=scale,
        n_orientations=k,
        spread_deg=spread,
        held=bool(held),
    )


def _whitening(wrench_std, wrench_cov, k: int) -> Callable[[np.ndarray], np.ndarray]:
    """The map from rows (6 k, ...) to the same rows divided by their noise.

    By ``wrench_std`` ((6,) or (k, 6)) row by row, or by the Cholesky factor of
    ``wrench_cov`` (6 k, 6 k) where given.

    Raises:
        InvalidInputError: a std of the wrong shape or not finite and > 0; a covariance of
            the wrong shape or not positive definite.
    """
    if wrench_cov is None:
        try:
            std = np.broadcast_to(np.asarray(wrench_std, dtype=float), (k, 6))
        except (ValueError, TypeError):
            raise InvalidInputError(
                f"wrench_std must be (6,) or ({k}, 6) (N, N m), got shape {np.shape(wrench_std)}"
            ) from None
        if not (np.all(np.isfinite(std)) and np.all(std > 0)):
            raise InvalidInputError("wrench_std must be finite and > 0 (N, N m)")
        w = 1.0 / std.ravel()
        return lambda x: x * (w[:, None] if x.ndim == 2 else w)
    cov = np.asarray(wrench_cov, dtype=float)
    try:
        if cov.shape != (6 * k, 6 * k) or not np.all(np.isfinite(cov)):
            raise np.linalg.LinAlgError
        L = np.linalg.cholesky(0.5 * (cov + cov.T))
    except np.linalg.LinAlgError:
        raise InvalidInputError(
            f"wrench_cov must be a finite, positive definite ({6 * k}, {6 * k}) matrix "
            f"(N, N m) for {k} orientations; got shape {cov.shape}"
        ) from None
    return lambda x: np.linalg.solve(L, x)


def information(g_sensor: np.ndarray, wrench_std: tuple[float, float]) -> np.ndarray:
    """(k, 10, 10) the information of theta = (m, m c, b_f, b_tau) each orientation gives.

    For white noise of ``wrench_std`` (force N, torque N m) on each window's mean; summed
    over orientations it is the inverse of the fit's covariance (before any scaling).
    """
    w = 1.0 / np.repeat(np.asarray(wrench_std, dtype=float), 3)
    rows = regressor(np.atleast_2d(g_sensor)).reshape(-1, 6, N_UNKNOWNS) * w[None, :, None]
    return np.einsum("kri,krj->kij", rows, rows)


def predicted_cov(info: np.ndarray, mass: float, com_sensor: np.ndarray) -> np.ndarray:
    """(4, 4) covariance of (mass, com_sensor) (kg, m) that the information ``info`` promises.

    ``info``: (10, 10) summed over the orientations; for a payload of ``mass`` at
    ``com_sensor`` (the delta method); infinite where ``info`` is singular.
    """
    s = np.linalg.svd(info, compute_uv=False)
    if not s[-1] > 1e-12 * s[0]:
        return np.full((4, 4), np.inf)
    J = np.zeros((4, 4))
    J[0, 0] = 1.0
    J[1:, 0] = -np.asarray(com_sensor, dtype=float) / mass
    J[1:, 1:] = np.eye(3) / mass
    return J @ np.linalg.inv(info)[:4, :4] @ J.T
