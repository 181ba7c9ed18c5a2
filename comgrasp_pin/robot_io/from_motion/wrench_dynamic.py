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

from dataclasses import dataclass

import numpy as np

from comgrasp_pin import validate
from comgrasp_pin.errors import InvalidInputError, MotionLogError, UnobservableError
from comgrasp_pin.estimation import ComEstimate
from comgrasp_pin.estimation.payload_regressor import condition_number, parameter_scale
from comgrasp_pin.robot import RobotModel
from comgrasp_pin.robot_io.from_motion import wrench_combined as wc
from comgrasp_pin.robot_io.from_motion import wrench_findings as wf
from comgrasp_pin.robot_io.from_motion.arm_model import ArmModel
from comgrasp_pin.robot_io.from_motion.dynamic_fit import (
    MotionRows,
    error_sources,
    fit_motion,
    motion_estimate,
)
from comgrasp_pin.robot_io.from_motion.motion_signals import CUTOFF_HZ, MIN_PEAK_SPEED
from comgrasp_pin.robot_io.from_motion.motion_system import prior_of, row_noise
from comgrasp_pin.robot_io.from_motion.payload_system import ARM_MODEL, EMPTY_RUN, payload_system
from comgrasp_pin.robot_io.from_motion.wrench_system import (
    as_joint_log,
    gravity_in_sensor,
    nominal_tool,
    wrench_system,
)
from comgrasp_pin.robot_io.log_files.log_types import WrenchLog
from comgrasp_pin.robot_io.results.estimate_result import (
    TOOL_EMPTY_RUN,
    TOOL_GIVEN,
    TOOL_NOMINAL,
    Motion,
    PayloadEstimate,
    Wrench,
)
from comgrasp_pin.robot_io.results.trust import motion_reasons


@dataclass(frozen=True)
class _Tool:
    params: np.ndarray  # (10,) ee frame
    cov: np.ndarray  # (10, 10)
    source: str


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
    tool = _tool(robot, log, empty_log, empty_window, cutoff_hz, tool_params, tool_cov)
    J, note = None, None
    if combine_joint_torques and log.effort is not None:
        J, note = _joint_system(robot, log, empty_log, window, empty_window, cutoff_hz, arm_model)
    W, arm, st, fits, duration = _stacked(robot, log, window, cutoff_hz, tool, J, arm_model)
    k, r = st.b.shape
    A_pi, A_x, b, w = st.A_pi.reshape(-1, 10), st.A_x.reshape(k * r, -1), st.b.reshape(-1), st.w
    A = np.column_stack([A_pi, A_x])
    m = fit_motion(MotionRows(A_pi, A_x, b, w, W.S.t, (k, r)), prior_of(prior), None,
                   arm_model=arm, arm_jac=st.arm_jac,
                   extra_cov=lambda err: wf.tool_cov(err.sensitivity, st, tool.cov),
                   observe=lambda solve: _observable(robot, W, solve))  # fmt: skip
    fit, err, validation = m.fit, m.err, m.validation
    cov_tool = m.extra_cov
    agree = wc.agreement(fits, tool.cov) if J is not None else None
    findings = motion_reasons(m.checks) + wf.wrench_reasons(tool, agree, J and J.source)
    payload, predicted = (b - A_x @ fit.x).reshape(k, r), (A_pi @ fit.pi).reshape(k, r)
    bias, bias_std, drift, delay = wf.sensor_bias(A, b, w, st, duration, fit.x, tool.cov)
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
    joints = wf.joint_part(J, fit.x, W.A_x.shape[1], st, predicted, payload, note)
    return motion_estimate(robot, fit, m.params_cov, motion, findings,
                           wc.contributions(st, fit.pi, prior_of(prior)),
                           wf.std_parts(fit.data_cov, cov_tool, tool, err.arm if arm else None),
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


def _tool(robot, log, empty_log, empty_window, cutoff_hz, tool_params, tool_cov) -> _Tool:
    """The tool's parameters beyond the sensor (ee frame) and their covariance."""
    if empty_log is not None and tool_params is not None:
        raise InvalidInputError("give an empty run or the tool's parameters, not both")
    if tool_params is not None:
        p = validate.real_array(tool_params, "tool_params")
        c = np.zeros((10, 10)) if tool_cov is None else validate.real_array(tool_cov, "tool_cov")
        if p.shape != (10,) or c.shape != (10, 10) or not np.all(np.isfinite(c)):
            raise InvalidInputError(
                f"tool_params must be (10,) (m, m c, I at the ee origin) and tool_cov (10, 10), "
                f"finite; got shapes {p.shape} and {c.shape}"
            )
        return _Tool(p, 0.5 * (c + c.T), TOOL_GIVEN)
    if empty_log is None:
        return _Tool(nominal_tool(robot, log.sensor_frame), np.zeros((10, 10)), TOOL_NOMINAL)
    if empty_log.sensor_frame != log.sensor_frame:
        raise InvalidInputError(
            f"the empty run's sensor frame {empty_log.sensor_frame!r} is not the loaded run's "
            f"{log.sensor_frame!r}: both must be the same sensor"
        )
    E = wrench_system(robot, empty_log, empty_window, cutoff_hz)
    k = len(E.S.t)
    A, b = np.column_stack([E.A_pi.reshape(-1, 10), E.A_x]), E.b.reshape(-1)
    w = np.tile(1 / row_noise(A, b, k, 6), k)
    err = _observable(robot, E, lambda: error_sources(
        A, b, w, (k, 6), float(E.S.t[-1] - E.S.t[0]), None, None, None, None),
        "the empty run")  # fmt: skip
    return _Tool(err.sensitivity @ b, err.data_cov,
                 TOOL_EMPTY_RUN)  # fmt: skip


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


def _observable(robot, W, solve, what="the loaded run"):
    """``solve()``, its UnobservableError said in the motion's terms: what to move."""
    try:
        return solve()
    except UnobservableError as exc:
        peak = np.max(np.abs(W.S.qd), axis=0)
        still = [f"{n} ({p:.2f} rad/s)" for n, p in zip(robot.joint_names, peak)
                 if p < MIN_PEAK_SPEED]  # fmt: skip
        sid = robot.model.getFrameId(W.sensor_frame)
        g = gravity_in_sensor(robot, sid, W.S.q)
        g /= np.linalg.norm(g, axis=1, keepdims=True)
        mean = g.mean(axis=0) / np.linalg.norm(g.mean(axis=0))
        turn = float(np.degrees(np.arccos(np.clip(g @ mean, -1, 1)).max()))
        raise UnobservableError(
            f"{what}'s wrench: {exc}. Gravity turns by at most {turn:.0f} deg in the sensor "
            f"frame (the mass, the CoM and the bias need it turned by tens of degrees about two "
            f"axes); joints below {MIN_PEAK_SPEED} rad/s: {', '.join(still) or 'none'}. Move "
            "every joint, tilt and spin the wrist (comgrasp plan-motion plans such a motion)"
        ) from None
