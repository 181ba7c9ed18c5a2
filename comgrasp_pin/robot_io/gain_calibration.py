"""Weigh it once: the drive gains of an arm that logs motor currents (``comgrasp calibrate-gains``).

A UR logs motor currents I, not joint torques; tau_j = K_j I_j with K_j (N m per A) the
drive's gain, known from a data sheet only to some per cent. With a payload of known mass
m0 moved along the same motion loaded and empty, the payload's torques are

    K_j (I_loaded - I_empty)_j - (rnea_loaded - rnea_empty)_j = Y_j pi + offsets_j(t)

and with m = m0 known, pi = (m0, pi') and the equation is linear in (K, pi', offsets):

    K_j dI_j - Y_j' pi' - offsets_j(t) = Y_j,m m0 + drnea_j

so one weighted least squares gives every gain, the payload's other nine parameters and
the offsets. The gains' covariance: the white Laplace widened by the same delete-a-block
jackknife as a payload's (``dynamic_uncertainty``), plus the known mass's own uncertainty.
The payload's CoM and inertia need not be known; the motion must excite each joint.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from comgrasp_pin.errors import InvalidInputError
from comgrasp_pin.estimation.payload_regressor import regressor_rows
from comgrasp_pin.robot import RobotModel
from comgrasp_pin.robot_io import dynamic_uncertainty as du
from comgrasp_pin.robot_io.alignment import align_empty
from comgrasp_pin.robot_io.logs import JointLog
from comgrasp_pin.robot_io.motion_signals import CUTOFF_HZ, motion_samples
from comgrasp_pin.robot_io.motion_system import joint_columns, offset_columns, row_noise


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
    d_rnea = np.array([pin.rnea(robot.model, robot.data, *s) - pin.rnea(robot.model, robot.data, *e)
                       for s, e in zip(zip(S.q, S.qd, S.qdd), zip(E.q, E.qd, E.qdd))])  # fmt: skip
    Y = regressor_rows(robot, S.q, S.qd, S.qdd).reshape(-1, 10)
    A = np.column_stack([joint_columns([dI]), -Y[:, 1:], -joint_columns(offset_columns(S))])
    b = Y[:, 0] * known_mass_kg + d_rnea.reshape(-1)
    sigma = row_noise(A, b, k, n)
    w = np.tile(1.0 / sigma, k)
    beta = np.linalg.lstsq(A * w[:, None], b * w, rcond=None)[0]
    blocks = du.contiguous_blocks(k, du.block_count(float(S.t[-1] - S.t[0])))
    white = du.white_cov(A, b, w, n)
    jk = du.jackknife_cov(A, b, w, k, n, blocks, n)
    factor = np.sqrt(np.maximum(np.diag(jk) / np.maximum(np.diag(white), 1e-300), 1.0))
    dK_dm = du.sensitivity(A, w, n) @ Y[:, 0]  # the gains scale with the known mass
    cov = white * np.outer(factor, factor) + known_mass_std_kg**2 * np.outer(dK_dm, dK_dm)
    residual = (A @ beta - b).reshape(k, n)
    return GainCalibration(
        beta[:n], 0.5 * (cov + cov.T), nominal, float(known_mass_kg), float(known_mass_std_kg),
        beta[n : n + 3] / known_mass_kg, np.sqrt(np.mean(residual**2, axis=0)),
        found.as_dict(), float(S.t[-1] - S.t[0]),
    )  # fmt: skip
