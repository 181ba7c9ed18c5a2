"""Where an excitation motion may go: its joints' limits, its start, its final scaling.

``excitation_limits`` takes the URDF's position and velocity limits with the settings'
margins, range boxes and rate scales; ``check_start`` refuses a start outside them, in
collision or below the floor; ``within_limits`` scales a planned series down about its
start where a peak between the search's grid points exceeds a limit. Joint units (rad, or m
for a prismatic joint), s.
"""

from __future__ import annotations

import numpy as np

from comgrasp_pin.errors import CollisionError, InvalidInputError
from comgrasp_pin.motion.fourier import FourierMotion
from comgrasp_pin.robot import RobotModel
from comgrasp_pin.robot_io.collision import SelfCollision
from comgrasp_pin.robot_io.excitation_search import Limits
from comgrasp_pin.robot_io.excitation_settings import ExcitationSettings
from comgrasp_pin.robot_io.planning import feasible


def excitation_limits(robot: RobotModel, start: np.ndarray, s: ExcitationSettings) -> Limits:
    """The per-joint limits the motion keeps, from the URDF and the settings."""
    v_urdf = robot.model.velocityLimit
    bad = [n for n, v in zip(robot.joint_names, v_urdf) if not (0 < v < 1e10)]
    if bad:
        raise InvalidInputError(f"the URDF gives no velocity limit for the joints {bad}")
    n_wrist = min(s.wrist_joints, robot.nq)
    n_arm = robot.nq - n_wrist
    box = np.r_[np.full(n_arm, s.arm_range_rad), np.full(n_wrist, s.wrist_range_rad)]
    rate = np.r_[np.full(n_arm, s.arm_rate_scale), np.ones(n_wrist)]
    lower = np.maximum(robot.q_lower + s.position_margin_rad, start - box)
    upper = np.minimum(robot.q_upper - s.position_margin_rad, start + box)
    return Limits(lower, upper, rate * s.velocity_scale * v_urdf, rate * s.acceleration_limit)


def check_start(
    robot: RobotModel, checker: SelfCollision, start: np.ndarray, s: ExcitationSettings
) -> None:
    """Refuse a ``start`` (n,) that the motion cannot leave from.

    InvalidInputError: not ``position_margin_rad`` inside the joint limits. CollisionError:
    in self-collision, or with the wrist or ee below ``min_height_m``.
    """
    inside = robot.q_lower + s.position_margin_rad, robot.q_upper - s.position_margin_rad
    if np.any(start < inside[0]) or np.any(start > inside[1]):
        raise InvalidInputError(
            f"the start {np.round(start, 4).tolist()} is not {s.position_margin_rad} rad inside "
            f"the joint limits {robot.q_lower.tolist()} .. {robot.q_upper.tolist()}"
        )
    if not feasible(robot, checker, start, s.min_height_m):
        raise CollisionError(
            f"the start configuration collides ({checker.colliding_pairs(start)}) or puts the "
            f"wrist or ee below {s.min_height_m} m: give another --start"
        )


def within_limits(series: FourierMotion, t: np.ndarray, lim: Limits) -> FourierMotion:
    """``series`` scaled down about its start where a peak on ``t`` exceeds a limit.

    The search kept the limits on a coarser grid.
    """
    q, qd, qdd = series.evaluate(t)
    dq = q - series.q0
    with np.errstate(divide="ignore", invalid="ignore"):
        ratios = np.nan_to_num(
            np.vstack(
                [
                    dq / (lim.upper - series.q0),
                    dq / (lim.lower - series.q0),
                    np.abs(qd) / lim.velocity,
                    np.abs(qdd) / lim.acceleration,
                ]
            ),  # fmt: skip
            nan=0.0,
            posinf=np.inf,
        )
    worst = float(ratios.max())
    if worst <= 1.0:
        return series
    return FourierMotion(series.q0, series.a / worst, series.b / worst, series.period_s)
