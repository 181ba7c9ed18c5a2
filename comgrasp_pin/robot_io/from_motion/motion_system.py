"""The linear system of a motion's samples: the extra columns, the rows' noise, pi's derived parts.

Rows are sample-major (sample i's n joints, then sample i + 1's). Shared by the payload's
fit (``dynamic``), the arm's identification (``arm_model``) and the gains' calibration
(``gain_calibration``).
"""

from __future__ import annotations

import numpy as np
from numpy.polynomial import legendre

from comgrasp_pin.robot_io.from_motion.motion_signals import MotionSamples

DRIFT_DEGREE = 3
"""The drift of the efforts' offsets over a motion, a polynomial of this degree per joint
(Legendre, with the offset): a random walk's slow part. Measured on the Panda with the
realistic sensor (24 runs): degree 1 leaves the CoM errors 1.7 times the stated std, 3 cuts
them by a third (rms z 1.3), 5 and 8 fit the noise and do worse."""
COULOMB_SPEED = 0.02
"""Coulomb friction modelled as tanh(qd / COULOMB_SPEED) (rad/s): smooth through zero speed."""


def drift_columns(S: MotionSamples) -> list[np.ndarray]:
    """(k, n) columns of the sensor's drift over the motion, one per degree.

    Legendre polynomials of degree 1 to ``DRIFT_DEGREE`` in time scaled to [-1, 1], the same
    for every joint.
    """
    u = (2 * S.t - S.t[0] - S.t[-1]) / (S.t[-1] - S.t[0])
    n = S.q.shape[1]
    return [np.tile(legendre.legval(u, [0] * d + [1])[:, None], (1, n))
            for d in range(1, DRIFT_DEGREE + 1)]  # fmt: skip


def offset_columns(S: MotionSamples) -> list[np.ndarray]:
    """The offset and its drift, per joint: [ones, drift columns]."""
    return [np.ones_like(S.qd), *drift_columns(S)]


def friction_columns(S: MotionSamples) -> list[np.ndarray]:
    """Viscous and Coulomb friction, per joint."""
    return [S.qd, np.tanh(S.qd / COULOMB_SPEED)]


def joint_columns(columns: list[np.ndarray]) -> np.ndarray:
    """(k n, len(columns) n): column c of joint j acts on joint j's rows only."""
    k, n = columns[0].shape
    out = np.zeros((k, n, len(columns) * n))
    for c, values in enumerate(columns):
        for j in range(n):
            out[:, j, c * n + j] = values[:, j]
    return out.reshape(k * n, -1)


def row_noise(A: np.ndarray, b_rows: np.ndarray, k: int, n: int) -> np.ndarray:
    """(n,) per joint noise std of the rows: a first plain fit's residuals."""
    beta, *_ = np.linalg.lstsq(A, b_rows, rcond=None)
    r = (A @ beta - b_rows).reshape(k, n)
    dof = max(k * n - A.shape[1], 1) / (k * n)
    return np.maximum(np.sqrt(np.mean(r**2, axis=0) / dof), 1e-9)


def prior_of(est):
    """((4,) mean, (4, 4) cov) of (m, c), or None (no prior, or a CoM seen as a line only)."""
    if est is None or isinstance(est, tuple):
        return est
    if est.cov is None or est.unobservable_ee is not None:
        return None
    return np.concatenate([[est.mass], est.com_ee]), np.asarray(est.cov, float)


def _derived(p: np.ndarray) -> np.ndarray:
    """(13,) mass, CoM and the inertia about the CoM (flattened) of the ten parameters p."""
    m = p[0] if abs(p[0]) > 1e-9 else 1e-9
    c = p[1:4] / m
    Ixx, Ixy, Iyy, Ixz, Iyz, Izz = p[4:]
    I_o = np.array([[Ixx, Ixy, Ixz], [Ixy, Iyy, Iyz], [Ixz, Iyz, Izz]])
    I_c = I_o - m * (c @ c * np.eye(3) - np.outer(c, c))  # parallel axis theorem
    return np.concatenate([[p[0]], c, I_c.ravel()])


def derived_jacobian(pi: np.ndarray) -> np.ndarray:
    """(13, 10) d (mass, CoM, inertia about the CoM) / d pi, by central differences."""
    steps = np.diag(1e-6 * np.maximum(np.abs(pi), 1e-6))
    return np.column_stack([(_derived(pi + h) - _derived(pi - h)) / (2 * h[i])
                            for i, h in enumerate(steps)])  # fmt: skip


def about_com(pi: np.ndarray, cov: np.ndarray):
    """Mass, CoM, inertia about the CoM and their covariances (the delta method)."""
    value = _derived(pi)
    D = derived_jacobian(pi)
    C = D @ cov @ D.T
    return float(value[0]), value[1:4], value[4:].reshape(3, 3), C[:4, :4], C[4:, 4:]
