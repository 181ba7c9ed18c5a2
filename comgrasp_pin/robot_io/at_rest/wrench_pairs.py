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

import numpy as np

from comgrasp_pin.estimation.regressor import stacked_regressor
from comgrasp_pin.estimation.wrench_com import (
    UNKNOWNS,
    estimate_com_wrench,
    source_shares,
    tool_wrench,
    wrench_regressor,
)
from comgrasp_pin.robot import RobotModel
from comgrasp_pin.robot_io.at_rest.joint_torques import judged_at_rest
from comgrasp_pin.robot_io.at_rest.windows import MAX_SPEED, read_pairs
from comgrasp_pin.robot_io.log_files.log_types import WrenchLog
from comgrasp_pin.robot_io.results.estimate_result import (
    JOINT_TORQUES,
    WRENCH,
    JointTorques,
    PayloadEstimate,
    Wrench,
)


def estimate_wrench_pairs(
    robot: RobotModel,
    log: WrenchLog,
    before: list[tuple[float, float]],
    after: list[tuple[float, float]],
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
