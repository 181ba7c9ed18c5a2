"""Weigh it once: the drive gains of an arm that logs motor currents (``comgrasp calibrate-gains``).

A UR logs motor currents I, not joint torques; tau_j = K_j I_j with K_j (N m per A) the
drive's gain, known from a data sheet only to some per cent. With a payload of known mass
m0 moved along the same motion loaded and empty, the payload's torques are

    K_j (I_loaded - I_empty)_j - (rnea_loaded - rnea_empty)_j = Y_j pi + offsets_j(t)

and with m = m0 known, pi = (m0, pi'). Written for the measured currents,

    dI_j = c_j (Y_j pi + drnea_j) + offsets_j(t),   c_j = 1 / K_j,

the noise stays on the left (the currents on the regressor side would pull a gain whose
joint sees little payload towards zero: 7 % on a UR5's wrist 3 in MuJoCo), and
Gauss-Newton (``GN_ITERATIONS``, from the linear estimate) gives every gain, the payload's
other nine parameters and the offsets. The gains' covariance: the white Laplace widened by
the same delete-a-block jackknife as a payload's (``dynamic_uncertainty``), plus the
known mass's own uncertainty.
The payload's CoM and inertia need not be known; the motion must excite each joint.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from comgrasp_pin.errors import InvalidInputError
from comgrasp_pin.estimation.payload_regressor import regressor_rows
from comgrasp_pin.robot import RobotModel
from comgrasp_pin.robot_io import dynamic_uncertainty as du
from comgrasp_pin.robot_io.alignment import align_empty
from comgrasp_pin.robot_io.logs import JointLog
from comgrasp_pin.robot_io.motion_signals import CUTOFF_HZ, motion_samples
from comgrasp_pin.robot_io.motion_system import joint_columns, offset_columns, row_noise
from comgrasp_pin.robot_io.parallel_filter import fast_signals, lowpassed
from comgrasp_pin.robot_io.payload_system import rnea

GN_ITERATIONS = 20
"""Gauss-Newton steps at most (it converges in a few: the problem is bilinear)."""


@dataclass(frozen=True)
class GainCalibration:
    """Drive gains calibrated on a known mass.

    Attributes:
        gains: (n,) N m per A.
        cov: (n, n) their covariance.
        nominal: (n,) the gains the logs were read with (ones where none were given).
        known_mass_kg, known_mass_std_kg: the payload's weighed mass and its std.
        com_m: (3,) the payload's CoM found alongside (ee frame, m).
        residual_rms_Nm: (n,) per joint.
        alignment: the empty run's alignment (``Alignment.as_dict``).
        duration_s: the motion's length fitted.
    """

    gains: np.ndarray
    cov: np.ndarray
    nominal: np.ndarray
    known_mass_kg: float
    known_mass_std_kg: float
    com_m: np.ndarray
    residual_rms_Nm: np.ndarray
    alignment: dict
    duration_s: float


def calibrate_gains(
    robot: RobotModel,
    loaded: JointLog,
    empty: JointLog,
    known_mass_kg: float,
    known_mass_std_kg: float = 0.0,
    cutoff_hz: float = CUTOFF_HZ,
) -> GainCalibration:
    """Per-joint drive gains from a loaded and an empty run of the same motion.

    Raises:
        InvalidInputError: logs without currents, a mass that is not positive.
        MotionLogError: the runs are not the same motion, too short, still.
    """
    if not (np.isfinite(known_mass_kg) and known_mass_kg > 0):
        raise InvalidInputError(f"the known mass must be > 0 kg, got {known_mass_kg}")
    if not (np.isfinite(known_mass_std_kg) and known_mass_std_kg >= 0):
        raise InvalidInputError(f"the known mass's std must be >= 0 kg, got {known_mass_std_kg}")
    for log in (loaded, empty):
        if log.current_gains is None:
            raise InvalidInputError(
                f"{log.source or 'a log'} holds joint torques, not motor currents: gains are "
                "calibrated from a UR recording's actual_current columns"
            )
    nominal = np.asarray(loaded.current_gains, float)
    if not np.allclose(nominal, np.asarray(empty.current_gains, float)):
        raise InvalidInputError("read both logs with the same --current-gains")
    S = motion_samples(robot, loaded, None, cutoff_hz, crop=True)
    E, found = align_empty(robot, S, empty, None, cutoff_hz)
    k, n = S.q.shape
    dI = (S.tau - E.tau) / nominal  # A
    fast_loaded = fast_signals(robot, loaded, None, cutoff_hz)
    fast_empty = fast_signals(robot, empty, None, cutoff_hz)

    d_rnea = lowpassed(fast_loaded, cutoff_hz, lambda F: rnea(robot, F), S.t) - lowpassed(
        fast_empty, cutoff_hz, lambda F: rnea(robot, F), E.t
    )
    Y = lowpassed(
        fast_loaded, cutoff_hz, lambda F: regressor_rows(robot, F.q, F.qd, F.qdd), S.t
    ).reshape(-1, 10)
    O = joint_columns(offset_columns(S))
    # a first, linear estimate: currents on the regressor side (biased towards zero gains
    # where a joint's current is small against its noise), the start of Gauss-Newton
    A = np.column_stack([joint_columns([dI]), -Y[:, 1:], -O])
    b = Y[:, 0] * known_mass_kg + d_rnea.reshape(-1)
    start = np.linalg.lstsq(A, b, rcond=None)[0]
    theta = np.concatenate([1.0 / start[:n], start[n : n + 9], np.zeros(O.shape[1])])
    y, w = dI.reshape(-1), np.ones(k * n)
    for _ in range(GN_ITERATIONS):  # the measured currents alone on the left
        M, model = _current_model(theta, Y, d_rnea.reshape(-1), O, known_mass_kg, n)
        step = np.linalg.lstsq(M * w[:, None], (y - model) * w, rcond=None)[0]
        theta = theta + step
        w = np.tile(1.0 / row_noise(M, y - model + M @ theta, k, n), k)
        if np.max(np.abs(step[:n] / theta[:n])) < 1e-10:
            break
    M, model = _current_model(theta, Y, d_rnea.reshape(-1), O, known_mass_kg, n)
    b_lin = y - model + M @ theta  # the linearised problem whose solution is theta
    blocks = du.contiguous_blocks(k, du.block_count(float(S.t[-1] - S.t[0])))
    white = du.white_cov(M, b_lin, w, n)
    jk = du.jackknife_cov(M, b_lin, w, k, n, blocks, n)
    factor = np.sqrt(np.maximum(np.diag(jk) / np.maximum(np.diag(white), 1e-300), 1.0))
    c = theta[:n]
    dc_dm = -du.sensitivity(M, w, n) @ (np.tile(c, k) * Y[:, 0])  # d model / d m0
    cov_c = white * np.outer(factor, factor) + known_mass_std_kg**2 * np.outer(dc_dm, dc_dm)
    J = np.diag(-1.0 / c**2)  # K = 1 / c
    cov = J @ cov_c @ J.T
    beta = np.concatenate([1.0 / c, theta[n:]])
    residual = ((y - model) / np.tile(c, k)).reshape(k, n)  # in N m
    return GainCalibration(
        beta[:n], 0.5 * (cov + cov.T), nominal, float(known_mass_kg), float(known_mass_std_kg),
        beta[n : n + 3] / known_mass_kg, np.sqrt(np.mean(residual**2, axis=0)),
        found.as_dict(), float(S.t[-1] - S.t[0]),
    )  # fmt: skip


def _current_model(theta, Y, d_rnea, O, m0: float, n: int):
    """(M, model): the currents' model c_j (Y_j pi + drnea_j) + offsets and its Jacobian.

    theta = (c (n): 1 / gain, pi' (9): m c and I, offsets); pi = (m0, pi').
    """
    c, pi_rest, off = theta[:n], theta[n : n + 9], theta[n + 9 :]
    r = len(d_rnea)
    c_rows = np.tile(c, r // n)
    torque = Y[:, 0] * m0 + Y[:, 1:] @ pi_rest + d_rnea
    model = c_rows * torque + O @ off
    J_c = joint_columns([torque.reshape(-1, n)])
    return np.column_stack([J_c, c_rows[:, None] * Y[:, 1:], O]), model
