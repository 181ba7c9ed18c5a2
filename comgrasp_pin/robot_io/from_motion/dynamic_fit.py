"""The payload's weighted least squares from a motion: its error sources, its fit.

``error_sources`` carries every error source through the weighted least squares of
``A [pi; x] = b`` (``dynamic_uncertainty``): the noise and the model's error (the block
sandwich, CR2), the drive gains' covariance, the arm model's; ``satterthwaite`` pools their
degrees of freedom for the t quantile of each 95 % interval.
``fit_payload`` fits the ten inertial parameters physically consistent where the mass's
95 % interval is above zero (``estimation.inertial_fit``), and reports the unconstrained
least squares where it is not (a consistent body of zero mass does not exist).
``std_parts`` names the mass's std by source.

``fit_motion`` is the one pipeline every source of rows goes through (the joint torques, a
wrist sensor's wrench, both stacked): error sources, the fit, the held-out prediction, the
halves and the checks; ``motion_estimate`` makes the result, its verdicts by ``trust``.
Parameters in the ee frame, SI units.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from comgrasp_pin.estimation import block_sandwich as bs
from comgrasp_pin.estimation import dynamic_uncertainty as du
from comgrasp_pin.estimation import trust
from comgrasp_pin.estimation.inertial_fit import fit_inertial
from comgrasp_pin.estimation.trust import Checks
from comgrasp_pin.robot_io.from_motion.arm_model import ArmModel
from comgrasp_pin.robot_io.from_motion.motion_system import about_com, derived_jacobian
from comgrasp_pin.robot_io.results.estimate_result import Inertia, Motion, PayloadEstimate


@dataclass(frozen=True)
class ErrorSources:
    """Every error source of the parameters [pi; x], linearised through the least squares.

    Attributes:
        factor: (p,) the block sandwich's ratio to each parameter's white-noise std: what
            the rows' correlation and the model's error add (or take: a white-noise
            estimate from the residuals is itself an estimate).
        white: (p, p) the parameters' covariance from white noise alone.
        sensitivity: (p, k n) the parameters' change per unit of each weighted row.
        rel_gain_cov: (n, n) the drive gains' relative covariance (zeros without gains).
        gains: (p, p) the covariance from the gains; arm: (p, p) from the arm model (zeros
            without one).
        sandwich: the block sandwich (its degrees of freedom per contrast).
        arm_dof: the arm model's blocks less one (its variance's degrees of freedom at most),
            or inf without an arm model.
    """

    factor: np.ndarray
    white: np.ndarray
    sensitivity: np.ndarray
    rel_gain_cov: np.ndarray
    gains: np.ndarray
    arm: np.ndarray
    sandwich: bs.BlockSandwich
    arm_dof: float = np.inf

    @property
    def data_cov(self) -> np.ndarray:
        """(p, p) the least squares' covariance from the data and the model: white, scaled."""
        return self.white * np.outer(self.factor, self.factor)


def error_sources(
    A: np.ndarray,
    b_rows: np.ndarray,
    w: np.ndarray,
    shape: tuple[int, int],
    duration_s: float,
    b_gain: np.ndarray | None,
    rel_gain_cov: np.ndarray | None,
    arm_model: ArmModel | None,
    arm_jac: np.ndarray | None,
) -> ErrorSources:
    """The error sources of the fit of ``A`` (k n, p) to ``b_rows`` (k n,), row weights ``w``.

    ``shape`` = (k samples, n joints) over ``duration_s`` s; ``b_gain``: the rows'
    derivative by the gains, or None for rows no gain scales (a wrench); ``rel_gain_cov``:
    (n, n) or None; ``arm_jac``: the rows'
    derivative by the arm model's parameters, or None.
    """
    k, n = shape
    blocks = du.contiguous_blocks(k, du.block_count(duration_s))
    white = du.white_cov(A, b_rows, w)
    sandwich = bs.block_sandwich(A, b_rows, w, k, n, blocks)
    factor = np.sqrt(np.diag(sandwich.cov) / np.maximum(np.diag(white), 1e-300))
    P = du.sensitivity(A, w)
    rel = np.zeros((n, n)) if rel_gain_cov is None else rel_gain_cov
    if b_gain is None:
        cov_gains = np.zeros((P.shape[0], P.shape[0]))
    else:
        J_gain = du.gains_jacobian(P, b_gain)
        cov_gains = J_gain @ rel @ J_gain.T
    cov_arm, arm_dof = np.zeros((10, 10)), np.inf
    if arm_model is not None and arm_jac is not None:
        D = P @ arm_jac @ arm_model.replicates.T  # each replicate's effect on pi
        cov_arm, arm_dof = D @ D.T, float(len(arm_model.replicates) - 1)
    return ErrorSources(factor, white, P, rel, cov_gains, cov_arm, sandwich, arm_dof)


@dataclass(frozen=True)
class PayloadFit:
    """The fitted parameters and their covariance from the data and the model.

    ``pi`` (10,) inertial, ``x`` the rest (offsets, drift, friction, delay), IPOPT's
    ``status`` (or why it did not run), ``data_cov`` their covariance from the data and the
    model, ``pi_ls`` the plain weighted least squares' parameters.
    """

    pi: np.ndarray
    x: np.ndarray
    status: str
    data_cov: np.ndarray
    pi_ls: np.ndarray


def fit_payload(A_pi: np.ndarray, A_x: np.ndarray, b_rows: np.ndarray, w: np.ndarray, prior,
                err: ErrorSources, q: float = trust.Z95) -> PayloadFit:  # fmt: skip
    """The payload's parameters: consistent where a payload is seen, else least squares.

    The consistent fit (``fit_inertial``, ``prior``: its prior or None) where the mass's
    95 % interval from the least squares (half-width ``q`` std) is above zero; else the
    unconstrained least squares (nothing held).
    """
    pi_ls = err.sensitivity @ b_rows
    data_cov = err.data_cov
    m_std = np.sqrt(data_cov[0, 0] + err.gains[0, 0] + err.arm[0, 0])
    if trust.payload_seen(pi_ls[0], m_std, q):
        fit = fit_inertial(A_pi, A_x, b_rows, w, prior)
        pi, x, status = fit.pi, fit.x, fit.return_status
        data_cov = fit.cov * np.outer(err.factor, err.factor)
    else:  # nothing held: a consistent body of zero mass does not exist
        A = np.column_stack([A_pi, A_x])
        beta = np.linalg.lstsq(A * w[:, None], b_rows * w, rcond=None)[0]
        pi, x, status = beta[:10], beta[10:], "not run: no payload seen"
    return PayloadFit(pi, x, status, data_cov, pi_ls)


DATA_PART = "data and model (block sandwich)"
"""``std_parts``' name of the data's and the model's part of the mass's std."""
PIPELINE_PART = "pipeline bias (measured on the motion)"


def std_parts(data_cov: np.ndarray, err: ErrorSources, gains: bool, arm: bool) -> dict:
    """The mass's std (kg) by source: data and model, the ``gains`` and ``arm`` model if given."""
    parts = {DATA_PART: float(np.sqrt(data_cov[0, 0]))}
    if gains:
        parts["gains"] = float(np.sqrt(err.gains[0, 0]))
    if arm:
        parts["arm model"] = float(np.sqrt(err.arm[0, 0]))
    return parts


def motion_estimate(
    robot,
    fit: PayloadFit,
    params_cov: np.ndarray,
    motion: Motion,
    findings: list[str],
    sources: dict,
    std_parts: dict,
    dof: Callable[[np.ndarray], float] | None = None,
    **parts,
) -> PayloadEstimate:
    """A motion's ``PayloadEstimate`` from its fit.

    pi about the CoM, the verdicts of the mass and CoM and of the inertia (``trust``), the
    per-source ``parts`` (``joint_torques=``, ``wrench=``). ``dof``: the degrees of freedom
    of a contrast c (10,) of pi's variance (``MotionFit.dof``), or None (a known variance).
    """
    mass, com, inertia_c, cov4, inertia_cov = about_com(fit.pi, params_cov)
    inertia_std = np.sqrt(np.clip(np.diag(inertia_cov), 0, None)).reshape(3, 3)
    # the derived quantities' (mass, CoM, inertia about the CoM), then the ten parameters'
    contrasts = np.vstack([derived_jacobian(fit.pi), np.eye(10)])
    dofs = np.array([np.inf if dof is None else dof(c) for c in contrasts])
    inertia_dof = float(dofs[4:13][[0, 1, 2, 4, 5, 8]].min())  # its six distinct entries
    word, reasons = trust.judge(mass, com, cov4, trust.arm_mass(robot), findings,
                                trust.t95(dofs[0]))  # fmt: skip
    i_word, i_reasons = trust.inertia_verdict(inertia_c, inertia_cov, trust.t95(inertia_dof))
    inertia = Inertia(inertia_c, inertia_cov, inertia_std, fit.pi, params_cov, fit.pi_ls,
                      i_word, i_reasons, inertia_dof, dofs[13:])  # fmt: skip
    return PayloadEstimate(mass, com, cov4, robot.ee_frame, word, reasons, sources, std_parts,
                           motion=motion, inertia=inertia, dof=dofs[:4], **parts)  # fmt: skip


@dataclass(frozen=True)
class MotionRows:
    """A motion's rows, every source stacked (rows in noise units through ``w``).

    Attributes:
        A_pi: (k r, 10) the payload's columns; A_x: (k r, e) the other unknowns' (offsets,
            drift, friction, bias, delay); b: (k r,) the readings; w: (k r,) row weights.
        t: (k,) the samples' times (s); shape: (k samples, r rows per sample).
    """

    A_pi: np.ndarray
    A_x: np.ndarray
    b: np.ndarray
    w: np.ndarray
    t: np.ndarray
    shape: tuple[int, int]


@dataclass(frozen=True)
class MotionFit:
    """What ``fit_motion`` found.

    The fit, its error sources, the parameters' covariance, the held-out prediction, the
    checks ``trust.motion_reasons`` weighs, and ``extra_cov``'s value (or None).
    """

    fit: PayloadFit
    err: ErrorSources
    params_cov: np.ndarray
    validation: du.Validation
    checks: Checks
    extra_cov: np.ndarray | None = None

    def dof(self, c: np.ndarray) -> float:
        """The degrees of freedom of the variance of c pi (c: (10,)); ``satterthwaite``."""
        extra = 0.0 if self.extra_cov is None else self.extra_cov
        return satterthwaite(c, self.fit.data_cov, self.err, extra)


def satterthwaite(c: np.ndarray, data_cov: np.ndarray, err: ErrorSources, extra=0.0) -> float:
    """The degrees of freedom of c pi's variance, its parts pooled (``bs.pooled_dof``).

    The data's part has the block sandwich's (``BlockSandwich.dof``), the arm model's its own
    blocks less one; the gains' and a known tool's (``extra``) are stated (infinite).
    """
    return bs.pooled_dof([(float(c @ data_cov @ c), err.sandwich.dof(c)),
                          (float(c @ err.arm @ c), err.arm_dof),
                          (float(c @ (err.gains + extra) @ c), np.inf)])  # fmt: skip


def fit_motion(
    rows: MotionRows,
    prior,
    arm_label: str | None,
    b_gain: np.ndarray | None = None,
    rel_gain_cov: np.ndarray | None = None,
    arm_model: ArmModel | None = None,
    arm_jac: np.ndarray | None = None,
    extra_cov: Callable[[ErrorSources], np.ndarray] | None = None,
    observe: Callable = lambda solve: solve(),
) -> MotionFit:
    """The payload from a motion's rows: the one pipeline of every source.

    Every error source, the fit, the held-out prediction and the two halves.

    Args:
        rows: the stacked rows.
        prior: ``motion_system.prior_of``'s (mean, cov) or None.
        arm_label: where the arm's own torques came from (joint torques), or None (a wrench).
        b_gain: the rows' derivative by the drive gains, or None (rows no gain scales).
        rel_gain_cov: (n, n) the gains' relative covariance, or None.
        arm_model: the arm's identified model, or None.
        arm_jac: the rows' derivative by the arm model's parameters, or None.
        extra_cov: the covariance of a known part subtracted from the rows (the tool's),
            from the error sources' sensitivity; None for none.
        observe: runs the error sources, to say an UnobservableError in the motion's terms.
    """
    k, r = rows.shape
    A = np.column_stack([rows.A_pi, rows.A_x])
    duration = float(rows.t[-1] - rows.t[0])
    err = observe(lambda: error_sources(A, rows.b, rows.w, (k, r), duration, b_gain,
                                        rel_gain_cov, arm_model, arm_jac))  # fmt: skip
    extra = None if extra_cov is None else extra_cov(err)
    err_fit = err if extra is None else replace(err, arm=err.arm + extra)
    q_mass = trust.t95(satterthwaite(np.eye(10)[0], err.data_cov, err,
                                     0.0 if extra is None else extra))  # fmt: skip
    fit = fit_payload(rows.A_pi, rows.A_x, rows.b, rows.w, prior, err_fit, q_mass)
    params_cov = fit.data_cov + err.gains + err.arm
    if extra is not None:
        params_cov = params_cov + extra
    validation = du.held_out(rows.A_pi, rows.A_x, rows.b, rows.w, rows.t, k, r)
    halves, halves_std = halves_check(A, rows.b, rows.w, k, r, err.factor, b_gain,
                                      err.rel_gain_cov)  # fmt: skip
    checks = Checks(float(fit.pi[0]), float(np.sqrt(params_cov[0, 0])), arm_label,
                    validation.explained_total, halves, halves_std)  # fmt: skip
    return MotionFit(fit, err, params_cov, validation, checks, extra)


def halves_check(A, b_rows, w, k, n, factor, b_gain=None, rel=None):
    """((m1, m2), std of m1 - m2): each half alone, its data std widened as the whole's.

    The drive gains' part is added where the rows have one (``b_gain``, ``rel``).
    """
    (p1, c1, r1), (p2, c2, r2) = du.split_halves(A, b_rows, w, k, n)
    var = (c1[0, 0] + c2[0, 0]) * factor[0] ** 2
    if b_gain is not None:
        J1 = du.gains_jacobian(du.sensitivity(A[r1], w[r1]), b_gain[: len(r1) // n])
        J2 = du.gains_jacobian(du.sensitivity(A[r2], w[r2]), b_gain[len(r1) // n :])
        d = J1[0] - J2[0]
        var = var + d @ rel @ d
    return (float(p1[0]), float(p2[0])), float(np.sqrt(var))
