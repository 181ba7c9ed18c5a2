"""The payload from a wrist force/torque sensor at rest: several orientations, or pairs.

Several orientations (``estimate_wrench_static``): mass, CoM and the sensor's bias.

The arm stands still in several orientations (``comgrasp plan-poses`` plans them); each still
window of the log gives one mean wrench and the sensor's orientation. ``estimation.wrench``
fits the mass, the CoM and the sensor's six offsets together: no empty-arm run is needed.

What the sensor carries: everything beyond it (gripper, camera, payload). The URDF's links
beyond the sensor frame (``tool_beyond``) are the tool the robot knows; their gravity wrench is
subtracted at each orientation, so that the estimate is what the URDF does not describe, the
payload. Give ``subtract_tool=False`` to estimate everything beyond the sensor (a tool's own
identification, or a URDF without the tool). An error in the URDF's tool goes straight into
the payload: check the tool once by running with nothing held (the mass's interval must then
hold zero).

Noise of a window's mean: the spread of its samples over sqrt(n), plus ``wrench_std`` (the
sensor's repeatability between windows, if known); the sensor's drift from its data sheet
(``drift_std``, a random walk, and ``drift_rate_std``, a rate fixed over the log), shared by
the windows as their times say (``estimation.drift``, from the log's start: what all windows
share goes into the fitted bias); and the residuals' excess over all of them
(``estimation.wrench``: the covariance is scaled by chi-square per degree of freedom above 1).

Before and after (``estimate_wrench_pairs``): still windows with the gripper empty and holding
the payload at the same poses, as the joint-torque path's (``estimate_from_log``). Per pose the
wrench's change is the payload's (the sensor's offset cancels), and where the log also has
joint efforts, their change is too: both go into one estimate (``estimation.wrench_com``),
each weighed by its windows' noise, and ``source_shares`` says how much each gave. Where a
pair's two configurations differ slightly, the URDF carries the empty readings over to the
after configuration (the tool's gravity wrench, the arm's gravity torques).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pinocchio as pin

from comgrasp_pin.errors import InvalidInputError, LogError
from comgrasp_pin.estimation.drift import difference_covariance
from comgrasp_pin.estimation.regressor import stacked_regressor
from comgrasp_pin.estimation.trust import Z95, arm_mass, judge, nominal_tool_reasons, t95
from comgrasp_pin.estimation.wrench import StaticWrenchFit, fit_static_wrench
from comgrasp_pin.estimation.wrench_com import (
    UNKNOWNS,
    T_sensor_ee,
    estimate_com_wrench,
    source_shares,
    tool_beyond,
    tool_wrench,
    wrench_regressor,
)
from comgrasp_pin.robot import RobotModel
from comgrasp_pin.robot_io.at_rest.joint_torques import judged_at_rest
from comgrasp_pin.robot_io.at_rest.windows import (
    MAX_SPEED,
    MIN_STATIC_S,
    find_static_windows,
    read_pairs,
    read_window,
)
from comgrasp_pin.robot_io.log_files.log_types import WrenchLog
from comgrasp_pin.robot_io.results.estimate_result import (
    JOINT_TORQUES,
    TOOL_NOMINAL,
    WRENCH,
    AtRest,
    JointTorques,
    PayloadEstimate,
    Wrench,
    sole_source,
)

MAX_CHI2_DOF = 25.0
"""Residuals above 5 times the windows' noise (chi-square per degree of freedom above
25): the rigid-body model does not explain the readings (a contact, a cable pulling, a
payload that moves in the gripper); the verdict is then ``unreliable``."""
TOOL_BEFORE, TOOL_NONE = "the tool identified before", "none (everything beyond the sensor)"


def estimate_wrench_static(
    robot: RobotModel,
    log: WrenchLog,
    windows: list[tuple[float, float]] | None = None,
    max_speed: float = MAX_SPEED,
    min_duration: float = MIN_STATIC_S,
    wrench_std: tuple[float, float] | None = None,
    subtract_tool: bool = True,
    tool: tuple[np.ndarray, np.ndarray] | None = None,
    drift_std: tuple[float, float] = (0.0, 0.0),
    drift_rate_std: tuple[float, float] = (0.0, 0.0),
) -> PayloadEstimate:
    """Mass, CoM (ee frame) and the sensor's bias from the still windows of ``log``.

    Args:
        robot: the arm's model; ``log.sensor_frame`` must be a frame of it on the last link.
        log: the wrench and joint positions.
        windows: still windows (s), one per orientation; None finds them (``--auto``).
        max_speed: a window is still while every joint is slower than this (rad/s).
        min_duration: shortest still window found automatically (s).
        wrench_std: (force N, torque N m) the sensor's repeatability between windows, added
            to each window's own noise; None for none.
        subtract_tool: subtract the URDF's links beyond the sensor (see the module docstring).
        tool: ((4,) m, m c in the sensor frame (kg, kg m), (4, 4) their covariance): the
            tool identified before (a run with nothing held and ``subtract_tool=False``,
            ``theta_sensor`` in its RESULT.json), subtracted instead of the URDF's, its
            covariance added; None for the URDF's.
        drift_std: (force N / sqrt(s), torque N m / sqrt(s)) the sensor's random-walk drift
            (its data sheet; ``WrenchSensorConfig.drift_std``), (0, 0) for none.
        drift_rate_std: (force N / s, torque N m / s) the std of a drift rate fixed over the
            log (temperature; ``WrenchSensorConfig.drift_rate_std``), (0, 0) for none.

    Raises:
        InvalidInputError: the sensor frame is not in the URDF or not on the ee's link.
        LogError: no still window, or one outside the log.
        UnobservableError: the orientations do not determine the payload and the bias (the
            message names the missing rotation).
    """
    if list(log.joint_names) != list(robot.joint_names):
        raise LogError(
            f"{log.source}: joints {list(log.joint_names)} do not match the URDF's arm joints "
            f"{list(robot.joint_names)}"
        )
    T_se = T_sensor_ee(robot, log.sensor_frame)  # checks the frame is on the ee's link
    if windows is None:
        windows = find_static_windows(log, max_speed, min_duration)
        if not windows:
            raise LogError(
                f"{log.source}: no still window (every joint below {max_speed:g} rad/s for "
                f"{min_duration:g} s); give --windows T0:T1,... or record the arm at rest"
            )
    readings = [read_window(log, t0, t1, max_speed, "window", log.wrench) for t0, t1 in windows]
    g_world = robot.model.gravity.linear
    g_sensor = np.array(
        [robot.frame_pose(r.q, log.sensor_frame)[:3, :3].T @ g_world for r in readings]
    )
    wrench = np.array([r.tau for r in readings])
    known_cov = None
    if tool is not None:
        theta_tool, known_cov = (np.asarray(v, dtype=float) for v in tool)
        if theta_tool.shape != (4,) or known_cov.shape != (4, 4):
            raise InvalidInputError("tool must be ((4,) m, m c; (4, 4) their covariance)")
        tool_mass, tool_moment = float(theta_tool[0]), theta_tool[1:]
        noise_from_tool = "the tool identified before (its covariance added)"
        tool_from = TOOL_BEFORE
    else:
        urdf_tool = tool_beyond(robot, log.sensor_frame) if subtract_tool else pin.Inertia.Zero()
        tool_mass, tool_moment = urdf_tool.mass, urdf_tool.mass * urdf_tool.lever
        noise_from_tool = ""
        tool_from = TOOL_NOMINAL if subtract_tool else TOOL_NONE
    wrench -= np.array([np.r_[tool_mass * g, np.cross(tool_moment, g)] for g in g_sensor])
    std, cov, noise_from = _window_noise(readings, wrench_std, drift_std, drift_rate_std)
    fit = fit_static_wrench(g_sensor, wrench, std, log.sensor_frame, known_cov, cov)
    if noise_from_tool:
        noise_from += f"; {noise_from_tool}"
    tool_com = tool_moment / tool_mass if tool_mass > 0 else np.zeros(3)
    tool_found = (tool_from, tool_mass, tool_com)
    return _estimate(robot, fit, T_se, log, windows, readings, tool_found, noise_from)


def _pair(value, name: str) -> np.ndarray:
    """(6,) a (force, torque) pair of numbers >= 0 spread over the three axes of each."""
    pair = np.asarray(value, dtype=float).ravel()
    if pair.shape != (2,) or not (np.all(np.isfinite(pair)) and np.all(pair >= 0)):
        raise InvalidInputError(f"{name} must be two numbers >= 0 (force, torque), got {value}")
    return np.repeat(pair, 3)


def _window_noise(readings, wrench_std, drift_std, drift_rate_std):
    """The windows' noise (the module docstring).

    Returns:
        Each window's std (k, 6), the readings' full covariance (6 k, 6 k) where the sensor
        drifts (None where not), and how they were set (one line).
    """
    std = np.array([r.tau_mean_std for r in readings])
    noise_from = "each window's sample spread / sqrt(n)"
    if wrench_std is not None:
        between = _pair(wrench_std, "wrench_std")
        std = np.sqrt(std**2 + between**2)
        noise_from += f", plus {between[0]:g} N and {between[3]:g} N m between windows"
    std = np.maximum(std, 1e-9)  # a noise-free log (simulation): its residuals decide
    drift, rate = _pair(drift_std, "drift_std"), _pair(drift_rate_std, "drift_rate_std")
    if not (drift.any() or rate.any()):
        return std, None, noise_from
    spans = [(r.t0, r.t1 - r.t0) for r in readings]
    cov = difference_covariance(spans, std, np.eye(len(readings)), drift)
    middle = np.array([r.t0 + 0.5 * (r.t1 - r.t0) for r in readings])
    cov += np.kron(np.outer(middle, middle), np.diag(rate**2))
    noise_from += (
        f"; the sensor's drift shared by the windows: {drift[0]:g} N and {drift[3]:g} N m per "
        f"sqrt(s), a rate of {rate[0]:g} N/s and {rate[3]:g} N m/s"
    )
    return std, cov, noise_from


def _rotated_cov(fit: StaticWrenchFit, G: np.ndarray) -> np.ndarray:
    """(4, 4) the covariance of (mass, CoM) in the ee axes.

    Where nothing is held the CoM's rows are NaN and the mass's variance is kept.
    """
    cov = G @ np.nan_to_num(fit.cov) @ G.T
    if not fit.held:
        cov[1:, :] = cov[:, 1:] = np.nan
        cov[0, 0] = fit.cov[0, 0]
    return cov


def _estimate(robot, fit, T_sensor_ee, log, windows, readings, tool, noise_from):
    """The ``PayloadEstimate``: the fit in the ee frame, judged by ``trust``."""
    T_ee_sensor = np.linalg.inv(T_sensor_ee)
    R = T_ee_sensor[:3, :3]
    G = np.eye(4)
    G[1:, 1:] = R
    findings = nominal_tool_reasons(tool[0] == TOOL_NOMINAL, float(tool[1]))
    if fit.chi2_dof > MAX_CHI2_DOF:
        findings.append(
            f"the residuals are {np.sqrt(fit.chi2_dof):.1f} times the windows' noise: the "
            "readings do not follow a rigid payload (contact, cable, a part moving)"
        )
    if not fit.held and fit.mass - Z95 * np.sqrt(fit.cov[0, 0]) > 0:
        findings.append(
            f"the mass {fit.mass:.4g} kg is within 3 standard deviations "
            f"({np.sqrt(fit.cov[0, 0]):.2g} kg) of zero: the CoM is not determined"
        )
    com_ee = R @ fit.com_sensor + T_ee_sensor[:3, 3]
    cov = _rotated_cov(fit, G)
    verdict, reasons = judge(fit.mass, com_ee, cov, arm_mass(robot), findings, t95(fit.cov_dof))
    res = fit.residuals
    residual_rms = np.sqrt([np.mean(res[:, :3] ** 2), np.mean(res[:, 3:] ** 2)])
    q = np.array([r.q for r in readings])
    still = [[float(a), float(b)] for a, b in windows]
    wrench = Wrench(
        log.sensor_frame, fit.bias, fit.bias_std, com_sensor=fit.com_sensor, tool=tool[0],
        tool_mass=float(tool[1]), tool_com_sensor=np.array(tool[2]), noise_from=noise_from,
        residual_rms=residual_rms, fit=fit,
    )  # fmt: skip
    return PayloadEstimate(
        fit.mass, com_ee, cov, robot.ee_frame, verdict, reasons, sole_source(WRENCH),
        at_rest=AtRest(q, {"still": still}, "closed form", "closed_form"), wrench=wrench,
        dof=np.full(4, fit.cov_dof),
    )  # fmt: skip


def estimate_wrench_pairs(
    robot: RobotModel,
    log: WrenchLog,
    before: Sequence[tuple[float, ...]],
    after: Sequence[tuple[float, ...]],
    max_speed: float = MAX_SPEED,
    use_joint_torques: bool = True,
    method: str = "lstsq",
) -> PayloadEstimate:
    """Mass and CoM (ee frame) from the wrench (and the efforts) before/after at k poses.

    Raises:
        LogError: windows unpaired, outside the log or not still; InvalidInputError,
            UnobservableError, EmptyGripperError: as ``estimate_com_wrench``.
    """
    frame = log.sensor_frame
    wb, wa = read_pairs(log, before, after, max_speed, log.wrench)
    q = np.array([r.q for r in wa])
    w_b = np.array([b.tau + tool_wrench(robot, a.q, frame) - tool_wrench(robot, b.q, frame)
                    for b, a in zip(wb, wa)])  # fmt: skip
    w_std = np.concatenate([np.hypot(b.tau_mean_std, a.tau_mean_std) for b, a in zip(wb, wa)])
    w_std = np.maximum(w_std, 1e-9)
    blocks = {WRENCH: (wrench_regressor(robot, q, frame)[0], np.diag(w_std**2))}
    torques = None
    if use_joint_torques and log.effort is not None:
        tb, ta = read_pairs(log, before, after, max_speed, log.effort)
        tau_b = np.array([b.tau + robot.gravity_torques(a.q) - robot.gravity_torques(b.q)
                          for b, a in zip(tb, ta)])  # fmt: skip
        t_std = np.concatenate([np.hypot(b.tau_mean_std, a.tau_mean_std) for b, a in zip(tb, ta)])
        cov_t = np.diag(np.maximum(t_std, 1e-6) ** 2)
        torques = (tau_b, np.array([a.tau for a in ta]), cov_t)
        blocks[JOINT_TORQUES] = (stacked_regressor(robot, q)[0], cov_t)
    est = estimate_com_wrench(robot, q, w_b, np.array([a.tau for a in wa]), frame,
                              wrench_std=w_std, method=method, torques=torques)  # fmt: skip
    windows = {"before": [[r.t0, r.t1, r.n_samples] for r in wb],
               "after": [[r.t0, r.t1, r.n_samples] for r in wa]}  # fmt: skip
    parts: dict = {"wrench": Wrench(frame, tool="cancels in the before/after differences")}
    if torques is not None:  # torque_std: (k n,) each pose's difference's, per joint
        std = np.sqrt(np.diag(torques[2]))
        parts["joint_torques"] = JointTorques(std, "samples", tau_before=tau_b,
                                              tau_after=torques[1])  # fmt: skip
    shares = {name: {"mass_kg": s["mass"], "first_moment_kgm": [s[u] for u in UNKNOWNS[1:]]}
              for name, s in source_shares(blocks).items()}  # fmt: skip
    return judged_at_rest(robot, est, q, windows, shares, **parts)
