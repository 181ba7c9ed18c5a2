"""The block sandwich (CR2) and its degrees of freedom (estimation.dynamic_uncertainty).

Independent references: a dense implementation written here from the formulas (the hat
matrix H = A M A^T in full, (I - H_bb)^(-1/2) by an eigendecomposition, Bell and McCaffrey's
G matrix in full); Monte Carlo over white noise, where CR2 is unbiased and the delete-a-block
jackknife is not; Student's t for the quantiles.
"""

import numpy as np
import pytest
from scipy import stats

from comgrasp_pin.estimation import block_sandwich as bs
from comgrasp_pin.estimation import dynamic_uncertainty as du
from comgrasp_pin.estimation.trust import Z95, t95


def design(seed=0, k=60, n=3, p=5):
    rng = np.random.default_rng(seed)
    A = rng.standard_normal((k * n, p))
    A[:, 0] = np.repeat(np.linspace(-1, 1, k) ** 3, n)  # leverage at the ends
    w = np.tile(rng.uniform(0.5, 2.0, n), k)
    return A, w, k, n


def dense_reference(A, b, w, k, n, blocks, c):
    """Replicates and Bell-McCaffrey dof from the full hat matrix (no low-rank algebra)."""
    Aw, bw = A * w[:, None], b * w
    M = np.linalg.inv(Aw.T @ Aw)
    H = Aw @ M @ Aw.T
    I_H = np.eye(len(b)) - H
    r = I_H @ bw
    reps, G = [], []
    for idx in blocks:
        rows = (idx[:, None] * n + np.arange(n)).ravel()
        e, V = np.linalg.eigh(np.eye(len(rows)) - H[np.ix_(rows, rows)])
        S = V @ np.diag(e**-0.5) @ V.T
        reps.append(M @ Aw[rows].T @ S @ r[rows])
        G.append(I_H[:, rows] @ S @ Aw[rows] @ M @ c)
    G = np.array(G).T
    lam = np.linalg.eigvalsh(G.T @ G)
    return np.array(reps), lam.sum() ** 2 / (lam**2).sum()


def test_the_sandwich_matches_a_dense_implementation():
    A, w, k, n = design()
    b = np.random.default_rng(1).standard_normal(k * n)
    blocks = du.contiguous_blocks(k, 12)
    c = np.array([1.0, -0.5, 0.0, 2.0, 0.3])
    got = bs.block_sandwich(A, b, w, k, n, blocks, p=A.shape[1])
    reps, dof = dense_reference(A, b, w, k, n, blocks, c)
    np.testing.assert_allclose(got.replicates, reps, rtol=1e-8, atol=1e-12)
    assert got.dof(c) == pytest.approx(dof, rel=1e-8)
    assert 1 <= got.dof(c) <= len(blocks) - 1


def test_white_noise_gives_an_unbiased_variance_where_the_jackknife_overstates():
    """Mean over 2000 white-noise draws of each estimate against the exact (A^T W^2 A)^-1."""
    A, w, k, n = design(seed=2)
    sigma = 1.0 / w  # rows weighted by 1 / their noise: white in weighted units
    exact = np.linalg.inv((A * w[:, None]).T @ (A * w[:, None]))
    blocks = du.contiguous_blocks(k, 12)
    rng = np.random.default_rng(3)
    cr2, jk = np.zeros(A.shape[1]), np.zeros(A.shape[1])
    draws = 2000
    for _ in range(draws):
        b = sigma * rng.standard_normal(k * n)
        cr2 += np.diag(bs.block_cov(A, b, w, k, n, blocks, A.shape[1])) / draws
        R = _jackknife(A, b, w, k, n, blocks)
        jk += np.diag(R.T @ R) / draws
    ratio_cr2, ratio_jk = cr2 / np.diag(exact), jk / np.diag(exact)
    np.testing.assert_allclose(ratio_cr2, 1.0, atol=0.08)  # MC spread about 0.03
    assert ratio_jk[0] > 1.15  # the high-leverage column: the jackknife overstates it


def _jackknife(A, b, w, k, n, blocks):
    """The delete-a-block jackknife, written out: what the sandwich replaced."""
    Aw, bw = A * w[:, None], b * w
    est = []
    for idx in blocks:
        keep = np.ones(k * n, bool)
        keep[(idx[:, None] * n + np.arange(n)).ravel()] = False
        est.append(np.linalg.lstsq(Aw[keep], bw[keep], rcond=None)[0])
    est = np.array(est)
    B = len(blocks)
    return np.sqrt((B - 1) / B) * (est - est.mean(axis=0))


@pytest.mark.parametrize("column", [0, 1])
def test_intervals_with_the_stated_dof_cover_95_percent(column):
    """White noise: |error| <= t95(dof) * std in 95 % of 1000 draws (binomial +-1.4 %; 96.5 %
    on the ordinary column, 6 dof; Satterthwaite errs on the safe side where leverage leaves
    2 dof, 98.5 %); the normal's 1.96 covers 92 and 85 % there."""
    A, w, k, n = design(seed=4, k=40)
    blocks = du.contiguous_blocks(k, 8)
    rng = np.random.default_rng(5)
    c = np.eye(A.shape[1])[column]
    inside_t, inside_z = [], []
    for _ in range(1000):
        b = rng.standard_normal(k * n) / w
        s = bs.block_sandwich(A, b, w, k, n, blocks, A.shape[1])
        err = np.linalg.lstsq(A * w[:, None], b * w, rcond=None)[0][column]
        std = np.sqrt(s.cov[column, column])
        inside_t.append(abs(err) <= t95(s.dof(c)) * std)
        inside_z.append(abs(err) <= Z95 * std)
    assert 0.935 <= np.mean(inside_t) <= 0.99
    assert np.mean(inside_z) < np.mean(inside_t) - 0.02


def test_t95_is_students_quantile():
    assert t95(np.inf) == Z95
    assert t95(10) == pytest.approx(stats.t.ppf(0.975, 10))
    np.testing.assert_allclose(t95(np.array([3.0, np.inf])), [stats.t.ppf(0.975, 3), Z95])
