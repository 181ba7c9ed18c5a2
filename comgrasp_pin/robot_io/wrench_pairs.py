"""The payload from a wrist sensor at the same poses before and after a grasp.

The log holds still windows with the gripper empty (``before``) and holding the payload at
the same poses (``after``), as the joint-torque path's (``estimate_from_log``). Per pose the
wrench's change is the payload's (the sensor's offset cancels), and where the log also has
joint efforts, their change is too: both go into one estimate (``estimation.wrench_com``),
each weighed by its windows' noise, and ``source_shares`` says how much each gave. Where a
pair's two configurations differ slightly, the URDF carries the empty readings over to the
after configuration (the tool's gravity wrench, the arm's gravity torques).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from comgrasp_pin.estimation import ComEstimate
from comgrasp_pin.estimation.regressor import stacked_regressor
from comgrasp_pin.estimation.wrench_com import (
    UNKNOWNS,
    estimate_com_wrench,
    source_shares,
    tool_wrench,
    wrench_regressor,
)
from comgrasp_pin.robot import RobotModel
from comgrasp_pin.robot_io.joint_log import JointLog
from comgrasp_pin.robot_io.static_report import estimate_fields
from comgrasp_pin.robot_io.windows import MAX_SPEED, read_pairs
from comgrasp_pin.robot_io.wrench_log import WrenchLog

WRENCH, JOINT_TORQUES = "wrench", "joint torques"


@dataclass(frozen=True)
class WrenchPairEstimate:
    """The payload from before/after pairs of still windows (ee frame, SI units).

    Attributes:
        estimate: mass, CoM (ee frame) and covariance (``ComEstimate``).
        sources: what it came from: ("wrench",) or ("wrench", "joint torques").
        shares: per source, its share of the information on each of (m, m c) (sums to 1).
        sensor_frame: the wrench's frame.
        q: (k, n) the after windows' mean configurations (rad).
    """

    estimate: ComEstimate
    sources: tuple[str, ...]
    shares: dict
    sensor_frame: str
    q: np.ndarray


def estimate_wrench_pairs(
    robot: RobotModel,
    log: WrenchLog,
    before: list[tuple[float, float]],
    after: list[tuple[float, float]],
    max_speed: float = MAX_SPEED,
    use_joint_torques: bool = True,
    method: str = "lstsq",
) -> WrenchPairEstimate:
    """Mass and CoM (ee frame) from the wrench (and the efforts) before/after at k poses.

    Raises:
        LogError: windows unpaired, outside the log or not still; InvalidInputError,
            UnobservableError, EmptyGripperError: as ``estimate_com_wrench``.
    """
    frame = log.sensor_frame
    wlog = JointLog(log.time, log.joint_names, log.position, log.wrench, log.source)
    wb, wa = read_pairs(wlog, before, after, max_speed)
    q = np.array([r.q for r in wa])
    w_b = np.array([b.tau + tool_wrench(robot, a.q, frame) - tool_wrench(robot, b.q, frame)
                    for b, a in zip(wb, wa)])  # fmt: skip
    w_std = np.concatenate([np.hypot(b.tau_mean_std, a.tau_mean_std) for b, a in zip(wb, wa)])
    w_std = np.maximum(w_std, 1e-9)
    blocks = {WRENCH: (wrench_regressor(robot, q, frame)[0], np.diag(w_std**2))}
    torques = None
    if use_joint_torques and log.effort is not None:
        jlog = JointLog(log.time, log.joint_names, log.position, log.effort, log.source)
        tb, ta = read_pairs(jlog, before, after, max_speed)
        tau_b = np.array([b.tau + robot.gravity_torques(a.q) - robot.gravity_torques(b.q)
                          for b, a in zip(tb, ta)])  # fmt: skip
        t_std = np.concatenate([np.hypot(b.tau_mean_std, a.tau_mean_std) for b, a in zip(tb, ta)])
        cov_t = np.diag(np.maximum(t_std, 1e-6) ** 2)
        torques = (tau_b, np.array([a.tau for a in ta]), cov_t)
        blocks[JOINT_TORQUES] = (stacked_regressor(robot, q)[0], cov_t)
    est = estimate_com_wrench(robot, q, w_b, np.array([a.tau for a in wa]), frame,
                              wrench_std=w_std, method=method, torques=torques)  # fmt: skip
    shares = source_shares(blocks)
    return WrenchPairEstimate(est, tuple(blocks), shares, frame, q)


def pairs_result_dict(result: WrenchPairEstimate, frame: str) -> dict:
    """RESULT.json (DESIGN.md 4b's fields, plus the sources and their shares)."""
    est = result.estimate
    std = est.std
    return {
        **estimate_fields(est, frame),
        "std": None if std is None else {"mass_kg": float(std[0]), "com_m": std[1:].tolist()},
        "sensor_frame": result.sensor_frame,
        "sources": list(result.sources),
        "contributions": result.shares,
        "contributions_of": list(UNKNOWNS),
        "q_rad": result.q.tolist(),
    }
