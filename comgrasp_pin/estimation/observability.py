"""What the torques observe of theta = (m, m c_ee): the reduced regression theta = B w.

Two ways to the same ``Reduced``:

- ``by_gram`` for well-conditioned pose sets without payload motion: the eigenvalues of the
  Gram matrix Yr^T Yr give the singular values (``closed_form``), with its inverse kept for
  the least squares;
- ``by_svd`` for everything else: rank decisions by SVD (a lost pure-CoM direction for poses
  that share the wrist's orientation relative to gravity, an unobservable mass refused),
  payload motion between poses included.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from comgrasp_pin.errors import InvalidInputError, UnobservableError
from comgrasp_pin.estimation import closed_form, small_linalg
from comgrasp_pin.estimation.regressor import (
    gravity_in_ee,
    one_pose_basis,
    perpendicular_basis,
    stacked_regressor,
)
from comgrasp_pin.robot import RobotModel

MASS_NULL_TOL = 1e-3
"""A lost direction whose mass component exceeds this (unit null vector) makes m unobservable."""


@dataclass(frozen=True)
class Reduced:
    """The torque regression and what of theta it observes: theta = B w.

    Y (rows, 4) for theta, T (k, 4, 4), B (4, p), u the unobservable direction (ee) or None,
    sv the singular values of Y (padded with 0 for one pose), cond the condition number of
    Yr = Y B (rows, p). From ``by_gram`` also (Yr^T Yr)^-1 and Yr^T b (else None).
    """

    Y: np.ndarray
    T: np.ndarray
    B: np.ndarray
    u: np.ndarray | None
    sv: np.ndarray
    cond: float
    Yr: np.ndarray
    gram_inv: np.ndarray | None = None
    Yr_b: np.ndarray | None = None


def by_gram(robot: RobotModel, Q: np.ndarray, b: np.ndarray, rcond: float) -> Reduced | None:
    """The reduction of a well-conditioned pose set through the Gram matrix, or None.

    One pose: w = (m, m c_wx, m c_wy) with B = [[1, 0], [0, R[:2]^T]]; several: w = theta.
    None where ``closed_form`` would leave the pose set to the SVD.
    """
    k = len(Q)
    Xb, T = closed_form.regression(robot, Q, b)
    p = Xb.shape[0] - 1
    P = Xb @ Xb.T
    lam = small_linalg.eigvalsh(P[:p, :p])
    low, high = float(lam[0]), float(lam[-1])
    if not low > max(closed_form.MIN_EIGEN_RATIO, 4.0 * rcond * rcond) * high:
        return None
    Yr = Xb[:p].T
    sv = np.zeros(4)
    np.sqrt(lam[::-1], out=sv[:p])
    if k == 1:
        R = T[0, :3, :3]
        B = np.zeros((4, 3))
        B[0, 0] = 1.0
        B[1:, 1:] = R[:2].T
        u = R[2] * -1.0  # gravity in the ee frame
        Y = Yr @ B.T  # exact: Y (0, u) = 0
    else:
        B, u, Y = np.eye(4), None, Yr
    return Reduced(Y, T, B, u, sv, math.sqrt(high / low), Yr, small_linalg.inv(P[:p, :p]),
                   P[:p, p])  # fmt: skip


def motion_maps(motion: np.ndarray | None, k: int) -> np.ndarray | None:
    """(k, 4, 4) maps A_i: theta at pose i = A_i theta (theta at the first pose).

    From the payload's rigid motions M_i = (R_i, p_i): m c_i = R_i (m c) + m p_i.
    """
    if motion is None:
        return None
    M = np.asarray(motion, dtype=float)
    if M.shape != (k, 4, 4) or not np.all(np.isfinite(M)):
        raise InvalidInputError(
            f"payload_motion_ee must be ({k}, 4, 4) finite transforms (one per pose), got "
            f"shape {M.shape}"
        )
    A = np.zeros((k, 4, 4))
    A[:, 0, 0] = 1.0
    A[:, 1:, 0] = M[:, :3, 3]
    A[:, 1:, 1:] = M[:, :3, :3]
    return A


def by_svd(
    robot: RobotModel, Q: np.ndarray, rcond: float, maps: np.ndarray | None = None
) -> Reduced:
    """The regression and the observable combination of theta, or UnobservableError."""
    k = len(Q)
    Y, T = stacked_regressor(robot, Q)
    if maps is not None:
        n = Q.shape[1]
        Y = np.concatenate([Y[i * n : (i + 1) * n] @ maps[i] for i in range(k)])
    if k == 1:
        u, B = gravity_in_ee(T[0, :3, :3]), one_pose_basis(T[0, :3, :3])
        s_full = None
    else:
        _, s_full, Vt = np.linalg.svd(Y, full_matrices=False)
        rank = int(np.sum(s_full > rcond * s_full[0])) if s_full[0] > 0 else 0
        if rank == 4:
            u, B = None, np.eye(4)
        elif rank == 3 and abs(Vt[3, 0]) <= MASS_NULL_TOL:
            u = Vt[3, 1:] / np.linalg.norm(Vt[3, 1:])
            u = u if u @ gravity_in_ee(T[0, :3, :3]) >= 0 else -u
            B = np.zeros((4, 3))
            B[0, 0] = 1.0
            B[1:, 1:] = perpendicular_basis(u)
        else:
            raise UnobservableError(
                f"the {k} poses leave the mass unobservable: singular values of the "
                f"regression {np.array2string(s_full, precision=3)} (rank {rank} of 4 at "
                f"rcond={rcond}); use poses where the joints bear the payload's weight"
            )
    Yr = Y @ B
    S = np.linalg.svd(Yr, compute_uv=False)
    if not S[-1] > rcond * S[0]:
        raise UnobservableError(
            "the pose set leaves the mass unobservable: singular values of the regression "
            f"for (mass, CoM across gravity) are {np.array2string(S, precision=3)}, below "
            f"rcond={rcond}; no joint torque separates mass from CoM offset at this q"
        )
    sv = np.append(S, 0.0) if s_full is None else s_full
    return Reduced(Y, T, B, u, sv, float(S[0] / S[-1]), Yr)
