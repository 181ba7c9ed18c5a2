"""The whole payload from a motion seen by a wrist force/torque sensor (and the joint torques).

The wrench the tool side applies to the sensor is linear in its ten inertial parameters given
the sensor frame's velocity, acceleration and gravity (``wrench_system``): per kept sample six
rows, with the sensor's bias, its drift over the motion (a cubic per axis, as the joint
torques' offsets) and the wrench's delay behind the positions unknown alongside. The fit, its
error bars, the validation and the verdict are the joint-torque path's (``dynamic``): weights
per axis from the residual noise, a physically consistent fit (``fit_payload``), a
block sandwich for the noise and the model's error, each fifth of the motion
predicted from the rest, the two halves compared, and nothing held where the mass's 95 %
interval holds zero.

The sensor carries the tool (gripper, camera) as well as the payload, and the tool's gravity
wrench turns with the sensor, so no bias absorbs it. Its parameters are subtracted, with
their covariance, from the best source given:
- ``empty_log``: a run with the tool and no payload, of any motion: the tool's ten parameters
  are fitted from it (with its own bias, drift and delay);
- ``tool_params``: known (ee frame), with ``tool_cov`` if known;
- the URDF's links beyond the sensor frame (``wrench_static.tool_beyond``): the last resort,
  never ``identified`` in the verdict (its error on a real tool is not known).

Where the log holds joint torques too (``WrenchLog.effort``) and ``combine_joint_torques``,
their rows (``payload_system``, the arm's own torques from ``arm_model``, else the empty run
if it is the same motion, else the URDF's model with friction) are stacked with the wrench's
and one payload is fitted (``wrench_combined``); ``contributions`` says what share of the
information about the mass, the CoM and the principal moments came from each, and the two
sources alone must agree.
"""

from __future__ import annotations

import numpy as np

from comgrasp_pin.errors import MotionLogError
from comgrasp_pin.estimation import ComEstimate
from comgrasp_pin.estimation import block_sandwich as bs
from comgrasp_pin.estimation import dynamic_uncertainty as du
from comgrasp_pin.estimation.payload_regressor import condition_number, parameter_scale
from comgrasp_pin.estimation.trust import motion_reasons, nominal_tool_reasons
from comgrasp_pin.robot import RobotModel
from comgrasp_pin.robot_io.from_motion import wrench_combined as wc
from comgrasp_pin.robot_io.from_motion.arm_model import ArmModel
from comgrasp_pin.robot_io.from_motion.dynamic_fit import (
    DATA_PART,
    MotionRows,
    fit_motion,
    motion_estimate,
)
from comgrasp_pin.robot_io.from_motion.motion_signals import CUTOFF_HZ
from comgrasp_pin.robot_io.from_motion.motion_system import DRIFT_DEGREE, prior_of
from comgrasp_pin.robot_io.from_motion.payload_system import (
    ARM_MODEL,
    EMPTY_RUN,
    NOMINAL,
    payload_system,
)
from comgrasp_pin.robot_io.from_motion.wrench_system import (
    as_joint_log,
    observable,
    tool_of,
    wrench_system,
)
from comgrasp_pin.robot_io.log_files.log_types import WrenchLog
from comgrasp_pin.robot_io.results.estimate_result import (
    TOOL_NOMINAL,
    JointTorques,
    Motion,
    PayloadEstimate,
    Wrench,
)


def estimate_wrench_dynamic(
    robot: RobotModel,
    log: WrenchLog,
    window: tuple[float, float] | None = None,
    cutoff_hz: float = CUTOFF_HZ,
    prior: ComEstimate | tuple[np.ndarray, np.ndarray] | None = None,
    combine_joint_torques: bool = True,
    arm_model: ArmModel | None = None,
    empty_log: WrenchLog | None = None,
    empty_window: tuple[float, float] | None = None,
    tool_params: np.ndarray | None = None,
    tool_cov: np.ndarray | None = None,
) -> PayloadEstimate:
    """Identify the held payload's ten inertial parameters (ee frame) from a motion's wrench.

    Args:
        robot: the arm; its model's gravity is the one the wrench was measured under;
            ``log.sensor_frame`` must be one of its frames, rigidly joined to the ee frame.
        log: the motion holding the payload: positions, the wrench (and joint torques).
        window: (t0, t1) s of ``log`` to use, or None: the whole log.
        cutoff_hz: the low-pass filter's cutoff (Hz).
        prior: a static estimate of the same payload in the ee frame (a ComEstimate, or
            ((4,) mass and CoM, (4, 4) their covariance)), or None.
        combine_joint_torques: use ``log.effort`` too where the log has it.
        arm_model: the arm's identified dynamics, for the joint-torque rows.
        empty_log: the tool without the payload, any motion, the same sensor frame.
        empty_window: (t0, t1) s of ``empty_log``, or None.
        tool_params: (10,) the tool's parameters (ee frame, Pinocchio's order), instead of
            an empty run.
        tool_cov: (10, 10) their covariance (default zero).

    Raises:
        InvalidInputError: a sensor frame not rigidly joined to the ee frame; an empty run of
            another sensor frame; both an empty run and tool parameters; bad tool parameters.
        MotionLogError: a log too short, still, jerky, at a joint limit, with gaps.
        UnobservableError: the motion does not determine the parameters (the message names
            the joints that barely move and how far gravity turns in the sensor frame).
        SolverError: IPOPT did not converge.
    """
    tool = tool_of(robot, log, empty_log, empty_window, cutoff_hz, tool_params, tool_cov)
    J, note = None, None
    if combine_joint_torques and log.effort is not None:
        J, note = _joint_system(robot, log, empty_log, window, empty_window, cutoff_hz, arm_model)
    W, arm, st, fits, duration = _stacked(robot, log, window, cutoff_hz, tool, J, arm_model)
    k, r = st.b.shape
    A_pi, A_x, b, w = st.A_pi.reshape(-1, 10), st.A_x.reshape(k * r, -1), st.b.reshape(-1), st.w
    A = np.column_stack([A_pi, A_x])
    m = fit_motion(MotionRows(A_pi, A_x, b, w, W.S.t, (k, r)), prior_of(prior), None,
                   arm_model=arm, arm_jac=st.arm_jac,
                   extra_cov=lambda err: _tool_cov(err.sensitivity, st, tool.cov),
                   observe=lambda solve: observable(robot, W, solve))  # fmt: skip
    fit, err, validation = m.fit, m.err, m.validation
    cov_tool = m.extra_cov
    agree = wc.agreement(fits, tool.cov) if J is not None else None
    findings = motion_reasons(m.checks) + _wrench_reasons(tool, agree, J and J.source)
    payload, predicted = (b - A_x @ fit.x).reshape(k, r), (A_pi @ fit.pi).reshape(k, r)
    bias, bias_std, drift, delay = _sensor_bias(A, b, w, st, duration, fit.x, tool.cov)
    motion = Motion(
        k, duration, W.S.cutoff_hz, W.S.velocity_from, fit.status,
        condition_number(A_pi * w[:, None], parameter_scale()), W.S.t, validation,
        m.checks.halves_mass_kg,
    )  # fmt: skip
    wrench = Wrench(
        log.sensor_frame, bias, bias_std, drift, tool=tool.source, tool_params=tool.params,
        tool_cov=tool.cov,
        residual_rms=np.sqrt(np.mean((predicted - payload)[:, :6] ** 2, axis=0)),
        wrench_std=st.noise[:6], delay_s=delay, wrench_payload=payload[:, :6],
        wrench_payload_fit=predicted[:, :6], agreement=agree,
        alone_refused={name: (f if isinstance(f, str) else None) for name, f in fits.items()},
    )  # fmt: skip
    joints = _joint_part(J, fit.x, W.A_x.shape[1], st, predicted, payload, note)
    return motion_estimate(robot, fit, m.params_cov, motion, findings,
                           wc.contributions(st, fit.pi, prior_of(prior)),
                           _std_parts(fit.data_cov, cov_tool, tool, err.arm if arm else None),
                           dof=m.dof, joint_torques=joints,
                           wrench=wrench)  # fmt: skip


def _stacked(robot, log, window, cutoff_hz, tool, J, arm_model):
    """(wrench system, arm model for the joints or None, stacked system, fits, duration s).

    The wrench's samples are the joint torques' (the motion cropped where an empty run
    serves them); the tool is subtracted from the wrench's rows; each source is fitted alone
    (``wrench_combined.alone``) and weighted by it (``wrench_combined.reweighted``).
    """
    W = wrench_system(robot, log, window, cutoff_hz, crop=J is not None and J.source == EMPTY_RUN)
    arm = arm_model if J is not None and J.source == ARM_MODEL else None
    duration = float(W.S.t[-1] - W.S.t[0])
    st = wc.stack(W, W.b - W.A_pi @ tool.params, J)
    fits = {name: wc.alone(st, name, duration, arm) for name in st.groups}
    return W, arm, wc.reweighted(st, fits), fits, duration


def _joint_system(robot, log, empty_log, window, empty_window, cutoff_hz, arm_model):
    """The joint torques' system and a note where the empty run could not serve it."""
    joints = as_joint_log(log, "effort")
    if arm_model is None and empty_log is not None and empty_log.effort is not None:
        try:
            return payload_system(robot, joints, as_joint_log(empty_log, "effort"), window,
                                  empty_window, cutoff_hz, None), None  # fmt: skip
        except MotionLogError as exc:
            note = (f"the empty run does not serve the joint torques ({exc}); the URDF's model "
                    "stands for the arm")  # fmt: skip
            return payload_system(robot, joints, None, window, None, cutoff_hz, None), note
    return payload_system(robot, joints, None, window, None, cutoff_hz, arm_model), None


def _tool_cov(P: np.ndarray, st: wc.Stacked, cov: np.ndarray) -> np.ndarray:
    """The tool's (10, 10) covariance ``cov`` carried to the unknowns of ``P`` (d them / d b).

    The tool's parameters enter the wrench's rows of ``st`` as A_pi (subtracted), so
    d unknowns / d tool = -P A_pi over those rows.
    """
    rows = st.rows(wc.WRENCH)
    D = -P[:, rows] @ st.A_pi.reshape(-1, 10)[rows]
    return D @ cov @ D.T


def _std_parts(data_cov, cov_tool, tool, cov_arm) -> dict:
    """The mass's std (kg) by source: the data and the model, the tool, the arm model."""
    parts = {DATA_PART: float(np.sqrt(data_cov[0, 0]))}
    if tool.cov.any():
        parts[f"tool ({tool.source})"] = float(np.sqrt(cov_tool[0, 0]))
    if cov_arm is not None:
        parts["arm model"] = float(np.sqrt(cov_arm[0, 0]))
    return parts


def _sensor_bias(A, b, w, st, duration, x, tool_params_cov):
    """The sensor's bias (mean over the motion), its std, its drift and the wrench's delay.

    ``x``: the fit's extra unknowns, the wrench's first (bias, drift, delay); the bias's std
    from white noise widened by the block sandwich, plus the tool's (``tool_params_cov``).
    """
    k, r = st.b.shape
    p = 16  # pi and the six biases
    blocks = du.contiguous_blocks(k, du.block_count(duration))
    white = du.white_cov(A, b, w, p)[10:, 10:]
    block = bs.block_cov(A, b, w, k, r, blocks, p)[10:, 10:]
    var = np.maximum(np.diag(white), np.diag(block))
    var += np.diag(_tool_cov(du.sensitivity(A, w, p)[10:], st, tool_params_cov))
    extras = x[: 6 * (1 + DRIFT_DEGREE)].reshape(1 + DRIFT_DEGREE, 6)
    drift = 2 * extras[1 : 1 + DRIFT_DEGREE : 2].sum(axis=0)
    return extras[0], np.sqrt(var), drift, float(x[6 * (1 + DRIFT_DEGREE)])


def _wrench_reasons(tool, agree, joint_source) -> list[str]:
    """The wrench path's own objections: the URDF's tool, the two sources' agreement.

    ``trust.motion_reasons`` has the ones every motion shares.
    """
    reasons = nominal_tool_reasons(tool.source == TOOL_NOMINAL, float(tool.params[0]))
    if agree is not None and agree["disagree"]:
        m = agree["mass_kg"]
        ratio = np.abs(agree["z"]) / np.array(agree["max_z"])
        i = int(np.argmax(ratio))
        reasons.append(
            f"the wrench and the joint torques disagree ({['mass', 'm c_x', 'm c_y', 'm c_z'][i]}"
            f" {abs(agree['z'][i]):.1f} std apart, at most {agree['max_z'][i]:.1f} for its "
            f"{agree['cov_dof'][i]:.0f} degrees of freedom; masses {m['wrench']:.3f} "
            f"and {m['joint_torques']:.3f} kg): "
            + ("the URDF's model of the arm is the likely cause; give an empty run of the same "
               "motion or an identified arm model, or leave the joint torques out"
               if joint_source == NOMINAL else
               "a sensor's scale, the tool, or the arm model is wrong")
        )  # fmt: skip
    return reasons


def _joint_part(J, x, e_w, st, predicted, payload, note) -> JointTorques | None:
    """The joint torques' own findings in the combined fit, or None without them."""
    if J is None:
        return None
    cols = st.groups[wc.JOINT_TORQUES][0]
    n = len(cols)
    extras = x[e_w : e_w + J.per_joint * n].reshape(J.per_joint, n)
    res = predicted[:, cols] - payload[:, cols]
    return JointTorques(
        st.noise[6:], "residuals", J.source, offsets=extras[0],
        offset_drift=2 * extras[1 : 1 + DRIFT_DEGREE : 2].sum(axis=0),
        friction=extras[1 + DRIFT_DEGREE :].T if J.source == NOMINAL else None,
        residual_rms=np.sqrt(np.mean(res**2, axis=0)),
        delay_s=None if J.alignment is not None else float(x[-1]), alignment=J.alignment,
        tau_payload=payload[:, cols], tau_payload_fit=predicted[:, cols], note=note,
    )  # fmt: skip
