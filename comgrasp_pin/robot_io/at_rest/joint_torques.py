"""From a log to a payload estimate: paired static windows -> estimate_com (ee frame).

Per pose i: tau_before is averaged over ``before[i]``, tau_after over ``after[i]``. Where the
two configurations differ, the empty-arm model carries tau_before over to the after
configuration: tau_before_at_after = tau_before + g(q_after) - g(q_before), g the URDF
model's gravity torques. The pose is q_after.

Noise: ``torque_std`` is the std of one AVERAGED reading (N m), i.e. the per-sample std over
sqrt(number of samples in the window). Without it, it is estimated from the samples' spread
in the windows: per joint, the RMS over poses of sqrt((s_b^2 / n_b + s_a^2 / n_a) / 2), so
that the difference of a pose has the variance 2 torque_std^2 that estimate_com assumes.
That is right for white noise. A sensor that drifts (``drift_std`` N m / sqrt(s), a random
walk: the sensor's data sheet, or measured on a still arm) adds the drift over the time
between each pose's two windows, and shares it between poses whose intervals overlap: the
differences' full covariance (``estimation.drift``) then goes to estimate_com, which solves
the generalised least squares. A servo's sag between the windows is not in either
(``residual_rms`` against the std tells).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Sequence

import numpy as np

from comgrasp_pin.errors import InvalidInputError, LogError
from comgrasp_pin.estimation import ComEstimate, estimate_com
from comgrasp_pin.estimation.drift import difference_covariance
from comgrasp_pin.estimation.dynamic_uncertainty import relative_gain_cov
from comgrasp_pin.estimation.estimate import delta_method
from comgrasp_pin.estimation.regressor import stacked_regressor
from comgrasp_pin.estimation.side_friction import side_friction_cov, side_spreads
from comgrasp_pin.estimation.static_errors import residual_rules
from comgrasp_pin.estimation.trust import (
    arm_mass,
    judge,
    t95,
)
from comgrasp_pin.robot import RobotModel
from comgrasp_pin.robot_io.at_rest.windows import MAX_SPEED, StaticReading, read_pairs
from comgrasp_pin.robot_io.log_files.joint_readers import JointLog
from comgrasp_pin.robot_io.results.estimate_result import (
    JOINT_TORQUES,
    AtRest,
    JointTorques,
    PayloadEstimate,
    sole_source,
)

NOISE_FLOOR = 1e-6
"""Smallest torque std (N m) taken from the samples (a noise-free log has spread 0)."""
GAIN_STEP = 1e-4
"""Relative gain change of the central difference in ``_gains_covariance`` (the estimate's
(m, m c) is linear in it: any step is exact up to rounding; a small one keeps the stepped
estimates clear of the empty-gripper refusal)."""


def estimate_from_log(
    robot: RobotModel,
    log: JointLog,
    before: Sequence[tuple[float, ...]],
    after: Sequence[tuple[float, ...]],
    torque_std: float | None = None,
    method: str = "lstsq",
    max_speed: float = MAX_SPEED,
    drift_std: float = 0.0,
    gain_cov: np.ndarray | None = None,
    pose_errors: bool = False,
) -> PayloadEstimate:
    """Estimate the payload from paired static windows of ``log``.

    Args:
        robot: the arm (its model's gravity is the one the torques were measured under;
            see ``mount.load_robot``).
        log: readings of the arm's joints, in ``robot.joint_names`` order.
        before: empty-arm windows (t0, t1) in s, one per pose; spans joined (both sides of
            a pose, ``parse_windows``) measure the stuck friction (``side_friction``).
        after: holding windows (t0, t1) in s; after[i] pairs with before[i].
        torque_std: std of one averaged torque reading (N m), or None to take it from the
            samples' spread.
        method: "lstsq" or "ipopt" (estimate_com).
        max_speed: static threshold (rad/s).
        drift_std: the torque sensor's drift, a random walk (N m / sqrt(s)); > 0: the
            differences' covariance with the drift between and across the windows.
        gain_cov: (n, n) covariance of the drive gains ((N m / A)^2, absolute; ``Gains.cov``)
            the log's currents were turned into torques with. Where ``log.current_gains`` is
            set, its relative form gain_cov / outer(K, K) is propagated through the
            estimator (``_gains_covariance``) and added to the estimate's covariance
            (``JointTorques.gains_cov`` holds that part). Ignored for a log of torques.
        pose_errors: the covariance from the poses' block sandwich (``static_errors``):
            errors that stay over a pose (stuck friction), k >= 2.

    Raises:
        LogError: the log's joints are not the arm's, or a window is outside the log or
            has no partner.
        NotStaticError: a window moves.
        ComGraspError: the errors of ``estimate_com``.
    """
    rb, ra = _read_windows(robot, log, before, after, max_speed)
    rel = relative_gain_cov(gain_cov, log.current_gains, robot.nq)
    Q = np.array([r.q for r in ra])
    tau_a = np.array([r.tau for r in ra])
    tau_b = np.array(
        [b.tau + robot.gravity_torques(a.q) - robot.gravity_torques(b.q) for b, a in zip(rb, ra)]
    )
    sigma, noise_from = _reading_std(rb, ra, torque_std, robot.nq)
    cov = _drift_covariance(rb, ra, sigma, noise_from, drift_std)
    friction, cov = _side_friction(robot, Q, rb, ra, sigma, cov, tau_a - tau_b)

    def solve(factor: np.ndarray | None, how: str) -> ComEstimate:
        """The estimate with each joint's efforts scaled by ``factor`` (None: as read).

        The model's carry-over term (tau_b's g(q_after) - g(q_before)) is not scaled.
        """
        b, a = tau_b, tau_a
        if factor is not None:
            b = np.array([factor * r.tau for r in rb]) + (tau_b - np.array([r.tau for r in rb]))
            a = factor * tau_a
        return estimate_com(robot, Q, b, a, how, torque_std=None if cov is not None else sigma,
                            dtau_cov=cov)  # fmt: skip

    est = solve(None, method)
    est, dof, findings = residual_rules(robot, est, Q, sigma, cov, tau_a - tau_b, pose_errors,
                                        friction)  # fmt: skip
    gains_part = None
    if rel is not None:
        gains_part = _gains_covariance(lambda f: solve(f, "lstsq"), est, rel)
        total = gains_part.copy() if est.cov is None else est.cov + gains_part
        est = dataclasses.replace(est, cov=total)
    joints = JointTorques(
        sigma, noise_from, gains_cov=gains_part, drift_std=float(drift_std), tau_before=tau_b,
        tau_after=tau_a, side_friction=friction,
    )  # fmt: skip
    windows = {"before": [[r.t0, r.t1, r.n_samples] for r in rb],
               "after": [[r.t0, r.t1, r.n_samples] for r in ra]}  # fmt: skip
    return judged_at_rest(robot, est, Q, windows, sole_source(JOINT_TORQUES), findings,
                          dof=dof, joint_torques=joints)  # fmt: skip


def _side_friction(robot, Q, rb, ra, sigma, cov, dtau):
    """(``SideFriction`` or None, the differences' covariance with the friction left).

    Where each pose was read from both sides (``side_friction``); else (None, ``cov``).
    """
    spread = side_spreads(rb, ra)
    if spread is None:
        return None, cov
    base = cov if cov is not None else np.diag(np.tile(2.0 * sigma**2, len(Q)))
    found, with_friction = side_friction_cov(stacked_regressor(robot, Q)[0], dtau.ravel(), base,
                                             spread)  # fmt: skip
    return found, with_friction if found.share_left > 0 else cov


def judged_at_rest(
    robot: RobotModel,
    est: ComEstimate,
    q: np.ndarray,
    windows: dict,
    sources: dict,
    findings: list[str] | None = None,
    dof: float | np.ndarray = np.inf,
    **parts,
) -> PayloadEstimate:
    """A ``PayloadEstimate`` of readings at rest from the estimator's ``ComEstimate``.

    Judged by ``trust``: a CoM that one pose leaves unseen along gravity is not identified
    (a payload file would place it on that line's point nearest the origin). ``parts``: the
    sources' own (``joint_torques=``, ``wrench=``). The mass's std by source where the drive
    gains' part is known (``JointTorques.gains_cov``). ``findings``: the mode's own
    objections; ``dof``: the degrees of freedom of the covariance, one or (4,) for (mass,
    com_ee) (inf: known noise).
    """
    findings = list(findings or [])
    if est.unobservable_ee is not None:
        u = np.array2string(np.asarray(est.unobservable_ee), precision=3)
        findings.append(
            f"the CoM along {u} ({robot.ee_frame}) was not observed (gravity's direction at "
            "the single pose): add poses that turn the wrist against gravity (comgrasp "
            "plan-poses)"
        )
    dofs = np.broadcast_to(np.asarray(dof, dtype=float), (4,)).copy()
    verdict, reasons = judge(est.mass, est.com_ee, est.cov, arm_mass(robot), findings,
                             t95(dofs[0]))  # fmt: skip
    at_rest = AtRest(q, windows, est.method, est.solver_status, est.condition_number, est)
    joints = parts.get("joint_torques")
    std_parts = {}
    if joints is not None and joints.gains_cov is not None and est.cov is not None:
        gains = float(joints.gains_cov[0, 0])
        noise = float(est.cov[0, 0]) - gains
        std_parts = {"noise": float(np.sqrt(max(noise, 0.0))),
                     "gains": float(np.sqrt(max(gains, 0.0)))}  # fmt: skip
    return PayloadEstimate(
        est.mass, est.com_ee, est.cov, robot.ee_frame, verdict, reasons, sources, std_parts,
        est.unobservable_ee, at_rest, dof=dofs, **parts,
    )  # fmt: skip


def _read_windows(
    robot: RobotModel,
    log: JointLog,
    before: Sequence[tuple[float, ...]],
    after: Sequence[tuple[float, ...]],
    max_speed: float,
) -> tuple[tuple[StaticReading, ...], tuple[StaticReading, ...]]:
    """(before readings, after readings) of the paired windows, or a LogError saying why not."""
    if tuple(log.joint_names) != tuple(robot.joint_names):
        raise LogError(f"the log's joints {log.joint_names} are not the arm's {robot.joint_names}")
    return read_pairs(log, before, after, max_speed)


def _reading_std(rb, ra, torque_std: float | None, n: int) -> tuple[np.ndarray, str]:
    """(std of one averaged reading per joint (N m), "samples" or "given").

    Without ``torque_std``, per joint the RMS over poses of sqrt((s_b^2 + s_a^2) / 2) of the
    windows' means (their samples' spread), floored at NOISE_FLOOR.
    """
    if torque_std is None:
        var = np.array([(b.tau_mean_std**2 + a.tau_mean_std**2) / 2 for b, a in zip(rb, ra)])
        return np.maximum(np.sqrt(var.mean(axis=0)), NOISE_FLOOR), "samples"
    if not (np.isfinite(torque_std) and torque_std > 0):
        raise InvalidInputError(f"torque_std must be finite and > 0 (N m), got {torque_std}")
    return np.full(n, float(torque_std)), "given"


def _gains_covariance(
    solve: Callable[[np.ndarray], ComEstimate], est: ComEstimate, rel: np.ndarray
) -> np.ndarray:
    """(4, 4) covariance of (mass, com_ee) from the gains' relative covariance ``rel``.

    theta = (m, m c) is the weighted least squares' solution, linear in the torque
    differences; joint j's differences scale by (1 + delta_j), so d theta / d delta_j is
    exact by a central difference of the estimate re-run with joint j's efforts scaled by
    1 +- GAIN_STEP (the closed form: IPOPT's l2 fit has the same minimiser and weights).
    cov_theta = J rel J^T goes to (m, c) by the delta method at the estimate, as the noise's.
    Joints without a gains' variance are skipped.
    """
    n = rel.shape[0]
    J = np.zeros((4, n))
    for j in range(n):
        if not (np.any(rel[j]) or np.any(rel[:, j])):
            continue
        steps = []
        for sign in (1.0, -1.0):
            factor = np.ones(n)
            factor[j] += sign * GAIN_STEP
            e = solve(factor)
            steps.append(np.r_[e.mass, e.mass * e.com_ee])
        J[:, j] = (steps[0] - steps[1]) / (2 * GAIN_STEP)
    theta = np.r_[est.mass, est.mass * est.com_ee]
    part = delta_method(theta, J @ rel @ J.T)
    return (part + part.T) / 2


def _drift_covariance(rb, ra, sigma, noise_from, drift_std) -> np.ndarray | None:
    """The differences' covariance with the sensor's drift (``estimation.drift``), or None.

    None without drift. White noise: each window's own spread, or ``sigma`` where given.
    """
    if not (np.isfinite(drift_std) and drift_std >= 0):
        raise InvalidInputError(f"drift_std must be finite and >= 0 (N m / sqrt(s)), got "
                                f"{drift_std}")  # fmt: skip
    if drift_std == 0:
        return None
    readings = [*ra, *rb]
    k = len(ra)
    weights = np.hstack([np.eye(k), -np.eye(k)])
    white = np.array([r.tau_mean_std if noise_from == "samples" else sigma for r in readings])
    spans = [(r.t0, r.t1 - r.t0) for r in readings]
    return difference_covariance(spans, np.maximum(white, NOISE_FLOOR), weights, drift_std)
