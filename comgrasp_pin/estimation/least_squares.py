"""What the torques observe of theta = (m, m c_ee), and its whitened least squares.

One SVD of the stacked regression Y (k n, 4) decides observability (threshold ``rcond``
relative to the largest singular value):

- rank 4: the full 3-D CoM is estimated;
- rank 3 with a lost direction that is a pure CoM direction u (one pose, or poses that never
  turn the wrist relative to gravity): the CoM along u is not observed; the least squares
  gives the solution with no component along u (the pseudo-inverse's), and zero variance
  there;
- anything else leaves the mass unobservable: ``UnobservableError``.

The fit is generalised least squares: with W the inverse square root of the torque
differences' covariance (a diagonal of 1 / std, or L^-1 for a full covariance L L^T),
A = W Y and A's truncated SVD give theta and its covariance (A^T A)^+ in one step, the
Cramer-Rao bound for Gaussian noise. Where no noise is given, it is estimated from the
residuals (readings must outnumber the observed unknowns), else there is no covariance.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import NamedTuple

import numpy as np

from comgrasp_pin.errors import UnobservableError

MASS_NULL_TOL = 1e-3
"""A lost direction whose mass component exceeds this (unit null vector) makes m unobservable."""
NOISE_FLOOR = 1e-6
"""No torque difference is taken as known better than this (N m): the noise estimated from
the residuals of noise-free data is floored here, so its weights stay finite."""


class Observed(NamedTuple):
    """The SVD of Y (rows, 4) and what it observes.

    Attributes:
        rank: 4, or 3 where the CoM along ``u`` is lost.
        u: (3,) unit CoM direction (ee) the torques cannot see, oriented along gravity at the
            first pose, or None.
        singular_values: (4,) of Y, descending; the lost one is 0.
        condition_number: largest over smallest singular value of the observed directions.
        U, s, Vt: Y's thin SVD (U (rows, rank), s (rank,), Vt (rank, 4)).
    """

    rank: int
    u: np.ndarray | None
    singular_values: np.ndarray
    condition_number: float
    U: np.ndarray
    s: np.ndarray
    Vt: np.ndarray


def observe(Y: np.ndarray, rcond: float, down_ee: Callable[[], np.ndarray]) -> Observed:
    """Y's observability by its SVD; ``down_ee()`` (3,) orients a lost CoM direction.

    Raises:
        UnobservableError: the mass (or more than one CoM direction) is not observed.
    """
    U, s, Vt = np.linalg.svd(Y, full_matrices=len(Y) < 4)
    sv = (s.tolist() + [0.0, 0.0, 0.0])[:4]  # fewer than 4 readings: 0s
    rank = sum(x > rcond * sv[0] for x in sv) if sv[0] > 0 else 0
    u = None
    if rank == 3 and abs(Vt[3, 0]) <= MASS_NULL_TOL:
        u = Vt[3, 1:] * (1.0 / math.hypot(*Vt[3, 1:].tolist()))
        u = u if u @ down_ee() >= 0 else -u
    elif rank != 4:
        raise UnobservableError(
            f"the poses leave the mass unobservable: singular values of the torque regression "
            f"{np.array2string(np.array(sv), precision=3)} (rank {rank} of 4 at "
            f"rcond={rcond:g}); use poses where the joints bear the payload's weight, and turn "
            "the wrist against gravity between poses"
        )
    cond = sv[0] / sv[rank - 1]
    sv[rank:] = [0.0] * (4 - rank)
    return Observed(rank, u, np.array(sv), cond, U[:, :rank], s[:rank], Vt[:rank])


class Fit(NamedTuple):
    """The least squares of b on Y, whitened.

    Attributes:
        theta: (4,) the solution (kg, kg m), no component along the lost direction.
        cov_root: (4, rank) R with cov(theta) = R R^T (V S^-1 of the whitened regression),
            or None where the noise is unknown and cannot be estimated (no more readings
            than observed unknowns).
        Vt: (rank, 4) the observed directions of theta (the whitened regression's).
        row_std: (rows,) std of each torque difference (N m) where it is not the same for
            all (per joint; None with a full covariance), else a float, or None (unknown).
        chol: the full covariance's Cholesky factor, or None.
        torque_std: std of one reading estimated from the residuals (N m), or None.
    """

    theta: np.ndarray
    cov_root: np.ndarray | None
    Vt: np.ndarray
    row_std: np.ndarray | float | None
    chol: np.ndarray | None
    torque_std: float | None


def fit(
    Y: np.ndarray,
    b: np.ndarray,
    seen: Observed,
    row_std: np.ndarray | float | None,
    chol: np.ndarray | None,
) -> Fit:
    """Generalised least squares of ``b`` (rows,) on ``Y`` (rows, 4) at ``seen.rank``.

    Args:
        Y: (rows, 4) the regression of theta.
        b: (rows,) the torque differences (N m).
        seen: Y's observability (``observe``).
        row_std: std of each torque difference (N m): a float (all the same), (rows,), or
            None (unknown: estimated from the residuals).
        chol: the lower Cholesky factor of the differences' covariance, in place of
            ``row_std``, or None.
    """
    if chol is None and not isinstance(row_std, np.ndarray):  # one std: Y's own SVD
        root = seen.Vt.T * (1.0 / seen.s)  # V S^-1
        theta = root @ (seen.U.T @ b)
        torque_std = None
        if row_std is None:
            if len(b) <= seen.rank:
                return Fit(theta, None, seen.Vt, None, None, None)
            r = b - Y @ theta
            row_std = max(math.sqrt(float(r @ r) / (len(b) - seen.rank)), NOISE_FLOOR)
            torque_std = row_std / math.sqrt(2.0)  # a difference is of two readings
        return Fit(theta, root * row_std, seen.Vt, row_std, None, torque_std)
    A, b_w = whitened(Y, b, row_std, chol)
    U, s, Vt = np.linalg.svd(A, full_matrices=False)
    root = Vt[: seen.rank].T * (1.0 / s[: seen.rank])
    theta = root @ (U[:, : seen.rank].T @ b_w)
    return Fit(theta, root, Vt[: seen.rank], row_std, chol, None)


def whitened(
    Y: np.ndarray, b: np.ndarray, row_std: np.ndarray | float | None, chol: np.ndarray | None
) -> tuple[np.ndarray, np.ndarray]:
    """(W Y, W b): W = L^-1 for a full covariance L L^T, else 1 / each row's std."""
    if chol is not None:
        return np.linalg.solve(chol, Y), np.linalg.solve(chol, b)
    if row_std is None:
        return Y, b
    if isinstance(row_std, np.ndarray):
        return Y / row_std[:, None], b / row_std
    return Y / row_std, b / row_std
