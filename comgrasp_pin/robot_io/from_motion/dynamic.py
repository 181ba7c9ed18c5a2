"""The whole payload from a motion: mass, CoM and inertia, an interval that holds, a verdict.

The arm moves along an excitation motion (``comgrasp plan-motion``) holding the payload. Per
kept sample (``motion_signals``), the measured efforts minus the arm's own are the payload's:

    tau - tau_arm(q, qd, qdd) = Y(q, qd, qdd) pi + offsets(t) [+ friction]

with Y the payload regressor (``estimation.payload_regressor``, ee frame). The arm's own
torques come from one of three places, best first:
- an empty-arm run of the same motion (``empty_log``), found and aligned on positions
  (``alignment``): its residual against the URDF's model is subtracted sample by sample;
- the arm's identified model (``arm_model``, ``comgrasp identify-arm`` on any run): the
  loaded run may be of any motion;
- the URDF's nominal model, with friction identified alongside: the last resort, labelled
  so, and never ``identified`` in the verdict (its error on a real arm is not known).
Per joint an offset and its drift over the motion (a cubic) stay unknown in every case.

The ten parameters are fitted physically consistent (``estimation.inertial_fit``), the static
estimate as prior where one is given. Where the mass's interval holds zero nothing is held:
the unconstrained least squares is reported (a consistent body of zero mass does not exist)
and the verdict says no payload was seen. Uncertainty (``dynamic_uncertainty``): the noise
and the model's error by the block sandwich, the drive gains' and the arm model's
covariance propagated. Validation: each fifth of the motion predicted from the rest.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from comgrasp_pin.errors import InvalidInputError
from comgrasp_pin.estimation import ComEstimate
from comgrasp_pin.estimation import dynamic_uncertainty as du
from comgrasp_pin.estimation.payload_regressor import (
    condition_number,
    parameter_scale,
)
from comgrasp_pin.estimation.trust import MIN_EXPLAINED, UNRELIABLE, motion_reasons
from comgrasp_pin.robot import RobotModel
from comgrasp_pin.robot_io.from_motion.arm_model import ArmModel
from comgrasp_pin.robot_io.from_motion.dynamic_fit import (
    PIPELINE_PART,
    MotionFit,
    MotionRows,
    fit_motion,
    motion_estimate,
    std_parts,
)
from comgrasp_pin.robot_io.from_motion.motion_signals import CUTOFF_HZ
from comgrasp_pin.robot_io.from_motion.motion_system import DRIFT_DEGREE, prior_of, row_noise
from comgrasp_pin.robot_io.from_motion.payload_system import (
    EMPTY_RUN,
    NOMINAL,
    payload_system,
    pipeline_bias,
)
from comgrasp_pin.robot_io.log_files.joint_readers import JointLog
from comgrasp_pin.robot_io.results.estimate_result import (
    JOINT_TORQUES,
    JointTorques,
    Motion,
    PayloadEstimate,
    sole_source,
)


def estimate_payload_dynamic(
    robot: RobotModel,
    log: JointLog,
    empty_log: JointLog | None = None,
    window: tuple[float, float] | None = None,
    empty_window: tuple[float, float] | None = None,
    cutoff_hz: float = CUTOFF_HZ,
    prior: ComEstimate | tuple[np.ndarray, np.ndarray] | None = None,
    arm_model: ArmModel | None = None,
    gain_cov: np.ndarray | None = None,
    gains_source: str | None = None,
) -> PayloadEstimate:
    """Identify the held payload's ten inertial parameters from a motion's log.

    Args:
        robot: the arm; its model's gravity is the one the torques were measured under.
        log: the motion holding the payload (positions and efforts; velocities if logged).
        empty_log: the same motion with the empty arm, or None.
        window: (t0, t1) s of ``log`` to use, or None: the motion found in the log.
        empty_window: the same for ``empty_log``.
        cutoff_hz: the low-pass filter's cutoff (Hz).
        prior: a static estimate of the same payload in the same ee frame (a ComEstimate,
            or ((4,) mass and CoM, (4, 4) their covariance)), or None.
        arm_model: the arm's identified dynamics (``identify_arm``), instead of an empty run.
        gain_cov: (n, n) covariance of the drive gains (N m/A)^2 where the log's efforts
            were made from currents (``log.current_gains``), or None.
        gains_source: where the gains came from, for the report.

    Raises:
        InvalidInputError: both an empty run and an arm model; an arm model of other joints
            or gains.
        MotionLogError: a log too short, still, jerky, at a joint limit, with gaps; an
            empty run that does not cover the loaded motion.
        UnobservableError: the motion does not determine the parameters.
        SolverError: IPOPT did not converge.
    """
    if empty_log is not None and arm_model is not None:
        raise InvalidInputError("give an empty run or an arm model, not both")
    system = payload_system(robot, log, empty_log, window, empty_window, cutoff_hz, arm_model)
    S, source, b_gain = system.S, system.source, system.b_gain
    k, n = S.q.shape
    A_pi, A_x, b_rows = system.Y.reshape(-1, 10), system.A_x, system.b.reshape(-1)
    sigma = row_noise(np.column_stack([A_pi, A_x]), b_rows, k, n)
    rows = MotionRows(A_pi, A_x, b_rows, np.tile(1.0 / sigma, k), S.t, (k, n))
    rel = du.relative_gain_cov(gain_cov, log.current_gains, n)
    m = fit_motion(rows, prior_of(prior), source, b_gain, rel, arm_model, system.arm_jac)
    bias = pipeline_bias(robot, log, window, cutoff_hz, m.fit.pi)
    m = carry(m, np.outer(bias, bias))
    fit, err = m.fit, m.err
    parts = std_parts(fit.data_cov, err, log.current_gains is not None, arm_model is not None)
    parts[PIPELINE_PART] = abs(float(bias[0]))
    motion = Motion(k, float(S.t[-1] - S.t[0]), S.cutoff_hz, S.velocity_from, fit.status,
                    condition_number(system.Y, parameter_scale()), S.t, m.validation,
                    m.checks.halves_mass_kg, pipeline_bias=bias)  # fmt: skip
    gains = gains_source if log.current_gains is not None else None
    joints = _joint_part(system, sigma, fit, gains)
    sources = sole_source(JOINT_TORQUES, motion=True)
    return motion_estimate(robot, fit, m.params_cov, motion, motion_reasons(m.checks), sources,
                           parts, dof=m.dof, joint_torques=joints)  # fmt: skip


def carry(m: MotionFit, cov: np.ndarray) -> MotionFit:
    """``m`` with a known error's covariance (10, 10) added: stated, infinite dof.

    The pipeline's bias is carried as b b^T, not subtracted: its size is measured on a
    smoothed stand-in for the true motion (``pipeline_bias``), a size and not a correction.
    """
    extra = cov if m.extra_cov is None else m.extra_cov + cov
    return replace(m, params_cov=m.params_cov + cov, extra_cov=extra)


def _joint_part(system, sigma, fit, gains_source) -> JointTorques:
    """What the joint torques' fit found besides the payload: offsets, friction, delay."""
    k, n = system.b.shape
    x = fit.x
    tau_fit = (system.Y.reshape(-1, 10) @ fit.pi).reshape(k, n)
    tau_payload = (system.b.reshape(-1) - system.A_x @ x).reshape(k, n)
    extras = x[: system.per_joint * n].reshape(system.per_joint, n)
    return JointTorques(
        sigma, "residuals", system.source, gains_source,
        offsets=extras[0], offset_drift=2 * extras[1 : 1 + DRIFT_DEGREE : 2].sum(axis=0),
        friction=extras[1 + DRIFT_DEGREE :].T if system.source == NOMINAL else None,
        residual_rms=np.sqrt(np.mean((tau_fit - tau_payload) ** 2, axis=0)),
        delay_s=float(x[-1]) if system.source != EMPTY_RUN else None,
        alignment=system.alignment, tau_payload=tau_payload, tau_payload_fit=tau_fit,
    )  # fmt: skip


def check_on_log(
    robot: RobotModel,
    est: PayloadEstimate,
    log: JointLog,
    arm_model: ArmModel | None = None,
    cutoff_hz: float = CUTOFF_HZ,
) -> PayloadEstimate:
    """``est`` (a motion's) with its payload checked on a second log of the same payload.

    The arm's torques come from ``arm_model`` or the URDF's nominal model (a second log has
    no empty run of its own); the second log's offsets, drift, friction and delay are
    fitted to it, the payload is not. Where the payload explains less of the second log
    than ``trust.MIN_EXPLAINED``, the verdict becomes ``unreliable`` with that reason.
    """
    if est.inertia is None or est.motion is None:
        raise InvalidInputError("check_on_log takes a motion's estimate (its ten parameters)")
    system = payload_system(robot, log, None, None, None, cutoff_hz, arm_model)
    k, n = system.b.shape
    A = np.column_stack([system.Y.reshape(-1, 10), system.A_x])
    w = np.tile(1.0 / row_noise(A, system.b.reshape(-1), k, n), k)
    v = du.predicted_on(system.Y, system.A_x, system.b, w, system.S.t, est.inertia.params)
    word, reasons = est.verdict, est.reasons
    if v.explained_total < MIN_EXPLAINED:
        word = UNRELIABLE
        reasons = reasons + (
            f"the payload explains {100 * v.explained_total:.0f} % of the second log's torque "
            f"difference ({log.source}; at least {100 * MIN_EXPLAINED:.0f} % expected): it is "
            "not the same payload, or the payload moved in the gripper, or the arm model "
            "does not hold on that motion",
        )
    return replace(est, motion=replace(est.motion, second_log=v), verdict=word, reasons=reasons)
