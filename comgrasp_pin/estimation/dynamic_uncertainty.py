"""What a motion's payload estimate does not know: every error source, propagated.

The payload's parameters pi come from a weighted linear system over the motion's samples
(``dynamic``): ``b = A_pi pi + A_x x + e`` with k samples of n joints, rows sample-major.
Three sources of error enter pi's covariance, each measured or given, never a factor:

1. **The data and what the model leaves out** (noise, friction not modelled, the filter,
   the arm model's structural error): the block sandwich (``block_sandwich.py``, CR2 of Bell
   and McCaffrey 2002). The motion is cut into contiguous blocks of ``BLOCK_S`` seconds; each
   block's residuals, freed of the fit's pull on them (its leverage), enter the sandwich
   M (sum_b A_b^T r_b r_b^T A_b) M. Blocks a few seconds long hold errors that are
   correlated over seconds (friction over a stroke, a mismodelled link over a swing), which
   a white-noise Laplace or a few-lag Newey-West estimate miss; for white rows it is
   unbiased, where a delete-a-block jackknife (Kuensch 1989) overstates the variance 1.4
   to 2 times. Its ratio to the white-noise variance scales each
   parameter's Laplace std. Its variance is estimated from B blocks: Satterthwaite's degrees
   of freedom (``BlockSandwich.dof``) set the t quantile of the 95 % interval.
2. **The drive gains** (a log of motor currents): the efforts are K_j I_j. A relative error
   delta_j of gain j scales joint j's efforts, and moves b's rows of joint j by delta_j
   times the part of b that scales with it (``b_gain``). d pi / d delta from the linear
   map (``gains_jacobian``), then J cov(delta) J^T (``relative_gain_cov``).
3. **The arm's own model** (``--arm-model``): its parameters' covariance, mapped through
   d pi / d beta = -P Phi.

All three are linearised through the unconstrained weighted least squares (``sensitivity``),
the consistent fit's own map where no constraint binds. A direction of the payload's
parameters that the motion does not determine is refused (``UnobservableError``): a
pseudo-inverse would give it zero variance.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from comgrasp_pin.errors import InvalidInputError, UnobservableError

BLOCK_S = 2.5
"""Length (s) of the sandwich's blocks: ten times the filter's correlation time at its
4 Hz cutoff, long enough to hold a slow model error within one block."""
MIN_BLOCKS, MAX_BLOCKS = 12, 20
"""The sandwich's block count. Its variance has at most B - 1 degrees of freedom, and a z-score
over a variance with nu of them has E[z^2] = nu / (nu - 2): 1.4 with 8 blocks (rms z 1.18),
1.22 with 12. On 24 paired MuJoCo runs of a 20 s motion (benchmarks/inertia_from_motion.py,
UR5 and Panda, three payloads) 12 blocks of 1.7 s held the mass in 92-96 % of the runs
(rms z 0.91-1.10) where 8 held it in 88-96 % (rms z 0.94-1.15); 16 did no better. Blocks
stay far longer than the 4 Hz filter's correlation (0.25 s). At most 20."""
FOLDS = 5
"""Contiguous folds of the held-out validation: each fifth predicted from the other four."""
FLAT_RCOND = 1e-6
"""A singular value of the column-scaled weighted system below this fraction of the largest is
a direction the data do not determine (its normal matrix's eigenvalue below 1e-12 of the
largest, ``inertial_fit.FLAT_RCOND``)."""
PAYLOAD_NAMES = ("m", "m c_x", "m c_y", "m c_z", "I_xx", "I_xy", "I_yy", "I_xz", "I_yz", "I_zz")


@dataclass(frozen=True)
class Validation:
    """The payload model's prediction on parts of the motion it was not fitted on.

    Attributes:
        rms_Nm: (n,) per joint, the held-out residual's RMS (N m).
        explained: (n,) per joint, 1 - sum(residual^2) / sum(measured^2) on held-out
            samples, the measured payload torque taken without its offsets: the fraction
            of the torque difference the payload explains.
        explained_total: the same over all joints, each weighed by 1 / its noise std (so
            that newtons and newton metres, big and small joints, are not pooled raw).
        t: (k,) the samples' times (s).
        measured: (k, n) the payload's torque as measured, offsets removed (N m).
        predicted: (k, n) its held-out prediction (N m).
        folds: number of contiguous folds.
    """

    rms_Nm: np.ndarray
    explained: np.ndarray
    explained_total: float
    t: np.ndarray
    measured: np.ndarray
    predicted: np.ndarray
    folds: int

    def as_dict(self) -> dict:
        """RESULT.json's ``validation``."""
        return {
            "method": f"{self.folds} contiguous folds, each predicted from the others",
            "rms_Nm": self.rms_Nm.tolist(),
            "explained": self.explained.tolist(),
            "explained_total": self.explained_total,
        }


def contiguous_blocks(k: int, count: int) -> list[np.ndarray]:
    """``count`` contiguous index blocks of 0..k-1, of nearly equal size."""
    return [b for b in np.array_split(np.arange(k), count) if b.size]


def block_count(duration_s: float) -> int:
    """The sandwich's number of blocks for a motion of ``duration_s`` seconds."""
    return int(np.clip(round(duration_s / BLOCK_S), MIN_BLOCKS, MAX_BLOCKS))


def _normal(A: np.ndarray, b: np.ndarray, w: np.ndarray, k: int, n: int):
    """Per-sample normal equations (k, p, p) and (k, p) of the weighted system."""
    Aw = (A * w[:, None]).reshape(k, n, -1)
    bw = (b * w).reshape(k, n)
    return np.einsum("kna,knb->kab", Aw, Aw), np.einsum("kna,kn->ka", Aw, bw)


def _refuse_flat(flat_vectors: np.ndarray, ratio: float, p: int) -> None:
    """Refuse a flat direction that moves the first p unknowns.

    ``flat_vectors``: the flat directions as rows (unit, in column-scaled unknowns). One
    that leaves the first p alone (a still joint's friction column, say) is let through.

    Raises:
        UnobservableError: naming the unknowns it mixes (the payload's parameters when p is
            10).
    """
    if not len(flat_vectors):
        return
    part = flat_vectors[:, :p]
    worst = part[np.argmax(np.linalg.norm(part, axis=1))]
    if np.linalg.norm(worst) > 1e-3:
        names = PAYLOAD_NAMES if p == len(PAYLOAD_NAMES) else [f"unknown {i}" for i in range(p)]
        mixed = [names[i] for i in np.flatnonzero(np.abs(worst) > 0.2 * np.abs(worst).max())]
        raise UnobservableError(
            f"the motion does not determine {' + '.join(mixed)} ({len(flat_vectors)} flat "
            f"direction(s), scaled singular value ratio {max(ratio, 1e-16):.0e}): a pseudo-"
            "inverse would give it zero variance; move every joint, the wrist's too"
        )


def _column_scale(Aw: np.ndarray) -> np.ndarray:
    scale = np.linalg.norm(Aw, axis=0)
    return np.where(scale > 0, scale, 1.0)


def white_cov(A, b, w, p: int = 10) -> np.ndarray:
    """(p, p) the LS fit's covariance with white, independent rows (residual-scaled).

    The normal matrix is inverted with its columns scaled to unit diagonal; a direction
    below ``FLAT_RCOND`` (in singular values) is dropped only where it leaves the first p
    unknowns alone.

    Raises:
        UnobservableError: the rows do not determine the first p unknowns (``_refuse_flat``).
    """
    Aw = A * w[:, None]
    beta, *_ = np.linalg.lstsq(Aw, b * w, rcond=None)
    r = Aw @ beta - b * w
    s2 = float(r @ r) / max(len(b) - A.shape[1], 1)
    scale = _column_scale(Aw)
    e, V = np.linalg.eigh((Aw / scale).T @ (Aw / scale))
    flat = e < FLAT_RCOND**2 * e[-1]
    _refuse_flat(V[:, flat].T, np.sqrt(max(e[0], 0.0) / e[-1]), p)
    Vk = V[:p, ~flat] / scale[:p, None]
    return s2 * (Vk / e[~flat]) @ Vk.T


def sensitivity(A: np.ndarray, w: np.ndarray, p: int = 10) -> np.ndarray:
    """(p, r) d pi / d b of the weighted least squares (its first p unknowns).

    The first p rows of the column-scaled system's pseudo-inverse, a flat direction dropped
    only where it leaves them alone.

    Raises:
        UnobservableError: the rows do not determine the first p unknowns (``_refuse_flat``).
    """
    Aw = A * w[:, None]
    scale = _column_scale(Aw)
    U, s, Vt = np.linalg.svd(Aw / scale, full_matrices=False)
    flat = s < FLAT_RCOND * s[0]
    _refuse_flat(Vt[flat], s[-1] / s[0], p)
    Vk = Vt[~flat, :p].T / scale[:p, None]
    return (Vk / s[~flat]) @ U[:, ~flat].T * w[None, :]


def relative_gain_cov(gain_cov, gains, n: int) -> np.ndarray | None:
    """(n, n) the drive gains' relative covariance gain_cov / outer(K, K), or None.

    ``gain_cov``: the gains' absolute covariance ((N m / A)^2, ``Gains.cov``); ``gains``: the
    log's ``current_gains`` (N m / A). None: no gains' covariance, or a log of torques.

    Raises:
        InvalidInputError: a covariance or gains of the wrong shape, or not finite.
    """
    if gain_cov is None or gains is None:
        return None
    g = np.asarray(gains, dtype=float)
    c = np.asarray(gain_cov, dtype=float)
    if c.shape != (n, n) or not np.all(np.isfinite(c)):
        raise InvalidInputError(
            f"gain_cov must be a finite ({n}, {n}) covariance of the drive gains ((N m / A)^2), "
            f"got shape {c.shape}"
        )
    if g.shape != (n,):
        raise InvalidInputError(f"the log's current_gains must be ({n},), got shape {g.shape}")
    return c / np.outer(g, g)


def gains_jacobian(P: np.ndarray, b_gain: np.ndarray) -> np.ndarray:
    """(p, n) d pi / d delta_j, delta_j the relative error of joint j's gain."""
    n = b_gain.shape[1]
    return np.column_stack([P[:, j::n] @ b_gain[:, j] for j in range(n)])


def held_out(A_pi, A_x, b, w, t, k: int, n: int, folds: int = FOLDS) -> Validation:
    """Fit on all folds but one, predict that one: every sample predicted out of sample."""
    A = np.column_stack([A_pi, A_x])
    Gs, gs = _normal(A, b, w, k, n)
    G, g = Gs.sum(axis=0), gs.sum(axis=0)
    measured, predicted = np.empty((k, n)), np.empty((k, n))
    for idx in contiguous_blocks(k, folds):
        beta = np.linalg.lstsq(G - Gs[idx].sum(0), g - gs[idx].sum(0), rcond=None)[0]
        rows = (idx[:, None] * n + np.arange(n)).ravel()
        offsets = A_x[rows] @ beta[A_pi.shape[1] :]
        measured[idx] = (b[rows] - offsets).reshape(-1, n)
        predicted[idx] = (A_pi[rows] @ beta[: A_pi.shape[1]]).reshape(-1, n)
    return _validation(measured, predicted, w, t, folds)


def predicted_on(Y, A_x, b, w, t, pi: np.ndarray) -> Validation:
    """A fitted payload ``pi`` predicting another log's payload torques.

    Only the other log's own nuisances (offsets, drift, friction, delay: ``A_x``) are fitted
    to it; the payload is not. Y: (k, n, 10); b: (k, n); w: (k n,) row weights.
    """
    k, n = b.shape
    predicted = (Y.reshape(-1, 10) @ pi).reshape(k, n)
    x = np.linalg.lstsq(A_x * w[:, None], (b.reshape(-1) - predicted.reshape(-1)) * w,
                        rcond=None)[0]  # fmt: skip
    measured = b - (A_x @ x).reshape(k, n)
    return _validation(measured, predicted, w, t, 1)


def _validation(measured, predicted, w, t, folds: int) -> Validation:
    """The scores of a prediction ((k, n) each): RMS and share explained, per joint and all."""
    res = measured - predicted
    explained = 1 - np.sum(res**2, axis=0) / np.maximum(np.sum(measured**2, axis=0), 1e-300)
    W = w.reshape(measured.shape)  # pooled in each joint's noise units: N and N m not mixed
    total = 1 - float(np.sum((W * res) ** 2) / max(np.sum((W * measured) ** 2), 1e-300))
    rms = np.sqrt(np.mean(res**2, axis=0))
    return Validation(rms, explained, total, np.asarray(t), measured, predicted, folds)


def split_halves(A, b, w, k: int, n: int, p: int = 10):
    """Per half of the motion: (pi (p,), white cov (p, p), rows mask); unconstrained LS."""
    out = []
    for idx in contiguous_blocks(k, 2):
        rows = (idx[:, None] * n + np.arange(n)).ravel()
        Aw = A[rows] * w[rows, None]
        beta, *_ = np.linalg.lstsq(Aw, b[rows] * w[rows], rcond=None)
        out.append((beta[:p], white_cov(A[rows], b[rows], w[rows], p), rows))
    return out
