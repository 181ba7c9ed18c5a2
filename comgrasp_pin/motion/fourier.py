"""Finite Fourier series joint motions that start and end at rest (Swevers et al. 1997).

Joint i moves as

    q_i(t)   = q0_i + sum_l  a_il / (w l) sin(w l t) - b_il / (w l) (cos(w l t) - 1)
    qd_i(t)  = sum_l  a_il cos(w l t) + b_il sin(w l t)
    qdd_i(t) = sum_l -a_il w l sin(w l t) + b_il w l cos(w l t)

with w = 2 pi / period_s and l = 1..L harmonics, so q(0) = q0 and the motion repeats every
period. It is at rest at t = 0 (and at every whole period) when sum_l a_il = 0 and
sum_l l b_il = 0; ``rest_basis`` spans the coefficients that satisfy both, so a free vector z
gives a rest-to-rest motion. q, qd, qdd are linear in the coefficients: ``basis`` gives the
matrices. Units: rad (or m), s; a and b in rad/s. Pure NumPy.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


def basis(t: np.ndarray, period_s: float, harmonics: int) -> tuple[np.ndarray, ...]:
    """(B_q, B_qd, B_qdd), each (len(t), 2L): q - q0 = B_q @ c, qd = B_qd @ c, ... for the
    coefficients c = (a_1..a_L, b_1..b_L) of one joint (rad/s)."""
    w = 2.0 * np.pi / period_s
    wl = w * np.arange(1, harmonics + 1)
    s, c = np.sin(np.outer(t, wl)), np.cos(np.outer(t, wl))
    B_q = np.hstack([s / wl, (1.0 - c) / wl])
    B_qd = np.hstack([c, s])
    B_qdd = np.hstack([-s * wl, c * wl])
    return B_q, B_qd, B_qdd


def rest_basis(harmonics: int) -> np.ndarray:
    """(2L, 2L - 2) orthonormal basis of the coefficients at rest at t = 0: c = N @ z."""
    L = harmonics
    C = np.zeros((2, 2 * L))
    C[0, :L] = 1.0  # qd(0) = sum a_l
    C[1, L:] = np.arange(1, L + 1)  # qdd(0) = w sum l b_l
    _, _, Vt = np.linalg.svd(C)
    return Vt[2:].T


@dataclass(frozen=True)
class FourierMotion:
    """A rest-to-rest finite Fourier series motion of n joints.

    Attributes:
        q0: (n,) configuration at t = 0 and at every whole period (rad or m).
        a: (n, L) sine coefficients of the velocity (rad/s).
        b: (n, L) cosine coefficients of the velocity (rad/s).
        period_s: fundamental period (s).
    """

    q0: np.ndarray
    a: np.ndarray
    b: np.ndarray
    period_s: float

    @classmethod
    def from_free(cls, q0: np.ndarray, Z: np.ndarray, period_s: float) -> FourierMotion:
        """The motion of free coefficients ``Z`` ((2L - 2, n), see ``rest_basis``)."""
        L = (Z.shape[0] + 2) // 2
        C = rest_basis(L) @ Z
        return cls(np.asarray(q0, float), C[:L].T.copy(), C[L:].T.copy(), float(period_s))

    @property
    def harmonics(self) -> int:
        return self.a.shape[1]

    def evaluate(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """q, qd, qdd at the times ``t`` (k,) (s), each (k, n)."""
        B_q, B_qd, B_qdd = basis(np.asarray(t, float), self.period_s, self.harmonics)
        C = np.vstack([self.a.T, self.b.T])
        return self.q0 + B_q @ C, B_qd @ C, B_qdd @ C
