"""A loaded run's linear system: what the payload's torques are, and what else is unknown.

    b = tau - tau_arm = Y pi + A_x x

per kept sample and joint (rows sample-major), with the arm's own torques from an aligned
empty run of the same motion, the arm's identified model, or the URDF's nominal model
(``dynamic``'s three sources), the model's terms filtered like the torques
(``motion_system``). x: per joint an offset and its drift (a cubic), viscous and Coulomb
friction with the nominal model, and the efforts' delay behind the positions (not with an
empty run: the same delay in both runs cancels). Used by the payload's fit and to check a
fitted payload on a second log. ``pipeline_bias``: what this pipeline does to a payload on
the logged motion (a parametric bootstrap).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
import pinocchio as pin

from comgrasp_pin.estimation.payload_regressor import regressor_rows
from comgrasp_pin.robot import RobotModel
from comgrasp_pin.robot_io.from_motion import motion_system
from comgrasp_pin.robot_io.from_motion.alignment import align_empty
from comgrasp_pin.robot_io.from_motion.arm_model import ArmModel, arm_columns, check_matches
from comgrasp_pin.robot_io.from_motion.motion_signals import MotionSamples, motion_samples
from comgrasp_pin.robot_io.log_files.joint_readers import JointLog
from comgrasp_pin.robot_io.log_files.log_values import on_grid

EMPTY_RUN, ARM_MODEL, NOMINAL = "empty run", "identified arm model", "URDF model + friction"


@dataclass(frozen=True)
class PayloadSystem:
    """The loaded run's system.

    Attributes:
        S: the kept samples.
        Y: (k, n, 10) the payload regressor, filtered like the torques.
        b: (k, n) the payload's torques as measured: efforts minus the arm's own (N m).
        b_gain: (k, n) the part of b that scales with each joint's drive gain.
        A_x: (k n, e) the extra unknowns' columns.
        per_joint: how many of A_x's columns come per joint (offset, drift, friction);
            a last column, the delay, follows unless ``source`` is ``EMPTY_RUN``.
        source: ``EMPTY_RUN``, ``ARM_MODEL`` or ``NOMINAL``.
        arm_jac: (k n, p) the arm model's columns (tau_arm = arm_jac @ params), or None.
        alignment: the empty run's (``Alignment.as_dict``), or None.
    """

    S: MotionSamples
    Y: np.ndarray
    b: np.ndarray
    b_gain: np.ndarray
    A_x: np.ndarray
    per_joint: int
    source: str
    arm_jac: np.ndarray | None
    alignment: dict | None


def payload_system(
    robot: RobotModel,
    log: JointLog,
    empty_log: JointLog | None,
    window,
    empty_window,
    cutoff_hz: float,
    arm_model: ArmModel | None,
) -> PayloadSystem:
    """The system of ``log`` with the arm's torques from the best source given."""
    S, fast, Y = payload_columns(robot, log, window, cutoff_hz, crop=empty_log is not None)
    k, n = S.q.shape

    def filtered(terms, source=fast, times=S.t):  # the model's terms filtered like tau
        return motion_system.lowpassed(source, cutoff_hz, terms, times)

    alignment, arm_jac = None, None
    if empty_log is not None:
        E, found = align_empty(robot, S, empty_log, empty_window, cutoff_hz)
        alignment = found.as_dict()
        fast_empty = motion_system.fast_signals(robot, empty_log, empty_window, cutoff_hz)
        rnea_empty = filtered(lambda F: rnea(robot, F), fast_empty, E.t)
        b = (S.tau - filtered(lambda F: rnea(robot, F))) - (E.tau - rnea_empty)
        b_gain, columns, source = S.tau - E.tau, motion_system.offset_columns(S), EMPTY_RUN
    elif arm_model is not None:
        check_matches(arm_model, robot, log)
        arm_jac = filtered(
            lambda F: arm_columns(robot, arm_model.base_columns, F).reshape(len(F.t), n, -1)
        ).reshape(k * n, -1)
        b = S.tau - (arm_jac @ arm_model.params).reshape(k, n)
        b_gain, columns, source = b, motion_system.offset_columns(S), ARM_MODEL
    else:
        b = S.tau - filtered(lambda F: rnea(robot, F))
        friction = filtered(lambda F: np.stack(motion_system.friction_columns(F), axis=1))
        b_gain, source = S.tau, NOMINAL
        columns = motion_system.offset_columns(S) + [friction[:, 0], friction[:, 1]]
    A_x = motion_system.joint_columns(columns)
    if source != EMPTY_RUN:
        A_x = np.column_stack([A_x, motion_system.delay_column(fast, S)])
    return PayloadSystem(S, Y, b, b_gain, A_x, len(columns), source, arm_jac, alignment)


def payload_columns(robot: RobotModel, log: JointLog, window, cutoff_hz: float, crop: bool):
    """(S, fast, Y): the kept samples, the signals to differentiate, the payload regressor.

    Y (k, n, 10) is computed on ``fast`` and low-passed like the torques (``lowpassed``).
    """
    S = motion_samples(robot, log, window, cutoff_hz, crop=crop)
    fast = motion_system.fast_signals(robot, log, window, cutoff_hz)
    Y = motion_system.lowpassed(
        fast, cutoff_hz, lambda F: regressor_rows(robot, F.q, F.qd, F.qdd), S.t
    )
    return S, fast, Y


def rnea(robot: RobotModel, S: MotionSamples) -> np.ndarray:
    """(k, n) the URDF model's inverse dynamics (RNEA) at the samples (N m)."""
    model, data = robot.model, robot.data
    return np.array([pin.rnea(model, data, q, qd, qdd).copy()
                     for q, qd, qdd in zip(S.q, S.qd, S.qdd)])  # fmt: skip


TRUTH_HZ = 25.0
"""The logged positions smoothed at this cutoff (Hz; at most 0.4 of the Nyquist rate) stand
for the true motion in ``pipeline_bias``: far above the 4 Hz identification band, so that
what the pipeline's own filters and derivatives do to that band shows (10 and 20 Hz gave the
same bias to 1e-7 kg on a MuJoCo UR5 motion)."""


def pipeline_bias(robot: RobotModel, log: JointLog, window, cutoff_hz: float,
                  pi: np.ndarray) -> np.ndarray:  # fmt: skip
    """(10,) what the pipeline adds to the payload ``pi`` on this log's motion.

    A parametric bootstrap: the payload's exact torques along the logged motion (positions
    on a uniform grid, ``log_values.on_grid``, smoothed at ``TRUTH_HZ``, a cubic spline's
    derivatives at the log's own times, ``regressor_rows``) go through the same filtering,
    differentiation, grid and least squares as the log (its offsets fitted, as with an empty
    run), and come back as pi + bias. The bias is what the filters' passbands and the
    numerical derivatives do to the payload's torques on this motion; the noise and the
    arm's model are not in it (they are in the block sandwich).
    """
    from scipy.interpolate import CubicSpline
    from scipy.signal import butter, sosfiltfilt

    t = np.asarray(log.time, float)
    rate = 1.0 / float(np.median(np.diff(t)))
    grid, q_grid = on_grid(t, rate, log.position)  # the filter needs a uniform grid
    sos = butter(4, min(TRUTH_HZ, 0.4 * rate / 2), fs=rate, output="sos")
    spline = CubicSpline(grid, sosfiltfilt(sos, q_grid, axis=0))
    q, qd, qdd = spline(t), spline(t, 1), spline(t, 2)
    exact = replace(log, position=q, effort=regressor_rows(robot, q, qd, qdd) @ pi,
                    current_gains=None, velocity=None if log.velocity is None else qd)  # fmt: skip
    S, _, Y = payload_columns(robot, exact, window, cutoff_hz, crop=True)
    A = np.column_stack(
        [Y.reshape(-1, 10), motion_system.joint_columns(motion_system.offset_columns(S))]
    )
    return np.linalg.lstsq(A, S.tau.reshape(-1), rcond=None)[0][:10] - pi
