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
the same block sandwich as a payload's (``dynamic_uncertainty``), plus the
known mass's own uncertainty.
The payload's CoM and inertia need not be known; the motion must excite each joint.
"""

from __future__ import annotations

from dataclasses import dataclass
from statistics import NormalDist

import numpy as np

from comgrasp_pin.errors import EmptyGripperError, InvalidInputError
from comgrasp_pin.estimation import block_sandwich as bs
from comgrasp_pin.estimation import dynamic_uncertainty as du
from comgrasp_pin.estimation.payload_regressor import regressor_rows
from comgrasp_pin.robot import RobotModel
from comgrasp_pin.robot_io.from_motion.alignment import align_empty
from comgrasp_pin.robot_io.from_motion.motion_signals import CUTOFF_HZ, motion_samples
from comgrasp_pin.robot_io.from_motion.motion_system import (
    fast_signals,
    joint_columns,
    lowpassed,
    offset_columns,
    row_noise,
)
from comgrasp_pin.robot_io.from_motion.payload_system import rnea
from comgrasp_pin.robot_io.log_files.joint_readers import JointLog

GN_ITERATIONS = 20
"""Gauss-Newton steps at most (it converges in a few: the problem is bilinear)."""
Z95 = NormalDist().inv_cdf(0.975)
"""The two-sided 95 % normal quantile: a payload shows where its mass's interval excludes 0."""


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
        EmptyGripperError: the runs show no payload, or a negative one (``_payload_shows``).
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
    blocks = du.contiguous_blocks(k, du.block_count(float(S.t[-1] - S.t[0])))
    _payload_shows(S.tau - E.tau, d_rnea, Y, O, blocks, known_mass_kg, loaded, empty, cutoff_hz)
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
    white = du.white_cov(M, b_lin, w, n)
    block = bs.block_cov(M, b_lin, w, k, n, blocks, n)
    factor = np.sqrt(np.maximum(np.diag(block) / np.maximum(np.diag(white), 1e-300), 1.0))
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


def _payload_shows(d_tau, d_rnea, Y, O, blocks, known_mass_kg: float, loaded, empty,
                   cutoff_hz: float) -> None:  # fmt: skip
    """Refuse runs whose torque difference shows no payload, or a negative one.

    The gains are the scale that turns the payload's currents into the torques of the known
    mass: where loaded minus empty holds no payload (the same run given twice, the payload
    left off), that scale is 0 / 0 and the fit returns any gains, of either sign. Whether a
    payload shows is the question the dynamic estimate asks of its mass (its 95 % interval
    excludes 0), asked here of the plain subtraction with the gains the logs were read with
    (``d_tau``, (k, n) N m, loaded minus empty): the mass fitted with the payload's nine
    other parameters and the offsets. Its std is the larger of the fit's own (white,
    widened by the same block sandwich as the gains') and the one the two runs'
    own sensor noise gives (``_sensor_noise``): a difference of two recordings carries the
    noise of both, except where the two are the same samples, whose difference has none
    and whose residuals would call a resampling error of 1e-5 N m a payload. Gains within a
    factor of a few of the true ones move the mass by that factor, never across 0: the test
    does not depend on them, and no threshold is tuned.

    Raises:
        EmptyGripperError: the mass's interval holds 0 (no payload in the difference), or
            lies below 0 (the runs swapped); the message says what to give instead.
    """
    k, n = d_tau.shape
    A = np.column_stack([Y, O])
    b = (d_tau - d_rnea).reshape(-1)
    noise = np.hypot(_sensor_noise(loaded, cutoff_hz), _sensor_noise(empty, cutoff_hz))
    w = np.tile(1.0 / noise, k)
    mass = float(np.linalg.lstsq(A * w[:, None], b * w, rcond=None)[0][0])
    var = max(du.white_cov(A, b, w, 1)[0, 0], bs.block_cov(A, b, w, k, n, blocks, 1)[0, 0],
              float(np.sum((du.sensitivity(A, w, 1)[0] * np.tile(noise, k)) ** 2)))  # fmt: skip
    std = float(np.sqrt(var))
    low, high = mass - Z95 * std, mass + Z95 * std
    if low > 0:
        return
    runs = f"the loaded run ({loaded.source}) and the empty run ({empty.source})"
    same = " (both are the same file)" if loaded.source == empty.source else ""
    found = (f"a mass of {mass:.3g} +- {std:.2g} kg (95 %: {low:.3g} to {high:.3g} kg) with the "
             "gains the logs were read with")  # fmt: skip
    give = (f"give as --csv a run holding the known {known_mass_kg:g} kg and as --empty-csv "
            "the same motion with nothing held")  # fmt: skip
    if high < 0:
        raise EmptyGripperError(
            f"{runs} show a negative payload: loaded minus empty is {found}; the runs look "
            f"swapped: {give}"
        )
    raise EmptyGripperError(
        f"{runs}{same} show no payload: loaded minus empty is at the noise level, {found}, "
        f"an interval that holds 0. Calibrating scales the gains until that difference weighs "
        f"the known {known_mass_kg:g} kg: with no payload in it, every gain is undetermined "
        f"(any size, either sign). {give[0].upper()}{give[1:]}"
    )


def _sensor_noise(log: JointLog, cutoff_hz: float) -> np.ndarray:
    """(n,) the std of a log's effort noise in one filtered sample (N m), model-free.

    White noise of std s on samples dt apart gives second differences of std s sqrt(6),
    while a motion below the cutoff barely moves them (its curvature times dt^2): s from
    their median absolute deviation (robust to the odd spike). Low-passed at ``cutoff_hz``
    and thinned to nearly independent samples, s^2 shrinks by 2 cutoff dt (the share of
    the band up to the Nyquist frequency the filter passes).
    """
    effort = np.asarray(log.effort, float)
    d2 = np.diff(effort, 2, axis=0)
    mad = np.median(np.abs(d2 - np.median(d2, axis=0)), axis=0)
    raw = mad / NormalDist().inv_cdf(0.75) / np.sqrt(6.0)  # MAD to a normal std
    dt = float(np.median(np.diff(np.asarray(log.time, float))))
    return np.maximum(raw * np.sqrt(min(2.0 * cutoff_hz * dt, 1.0)), 1e-9)
