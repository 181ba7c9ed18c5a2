"""Where the trial grasp grasps and measures: pure geometry over the robot model.

``plan_trial`` places the grasp ``offset`` m along the perceived rod from its centre and the
measurement poses above it (the second, if any, rolled about ee-x); ``extra_pose`` chooses
one more rolled pose, the D-optimal reachable one, or None when no roll is reachable;
``modelled_tau_before`` gives that pose's empty-arm torques from the model. No ``Cell``
here: nothing moves, nothing is seen. Angles in rad unless named ``_deg``; lengths in m.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from comgrasp_pin.errors import IKError
from comgrasp_pin.geometry import GraspPose
from comgrasp_pin.motion.ik import grasp_frame, solve_ik, solve_top_down
from comgrasp_pin.perception import RodDetection
from comgrasp_pin.planning.wrist_poses import best_next_pose
from comgrasp_pin.robot import RobotModel


@dataclass(frozen=True)
class TrialPlan:
    """Where to grasp and where to measure.

    Attributes:
        grasp: the grasp on the table.
        poses: the measurement configurations, each (nq,) rad; the first unrolled.
        centre_hint: the rod's centre along ee-x from the jaws (m), a hint for the side view.
        T_world_ee_meas: (4, 4) the ee pose at the first measurement configuration.
        detection: the top view of the rod that the grasp was planned on.
    """

    grasp: GraspPose
    poses: list
    centre_hint: float
    T_world_ee_meas: np.ndarray
    detection: RodDetection

    @property
    def rod_length(self) -> float:
        """The rod's length as the top view measured it (m)."""
        return self.detection.length

    @property
    def grasp_z(self) -> float:
        """The ee frame's height at the grasp (m)."""
        return float(grasp_frame(self.grasp)[2, 3])


def rolled(T_world_ee: np.ndarray, roll_deg: float) -> np.ndarray:
    """(4, 4) the pose ``T_world_ee`` turned by ``roll_deg`` about its own x axis."""
    c, s = np.cos(np.radians(roll_deg)), np.sin(np.radians(roll_deg))
    T = T_world_ee.copy()
    T[:3, :3] = T_world_ee[:3, :3] @ np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])
    return T


def grasp_along_rod(rod: GraspPose, offset: float) -> GraspPose:
    """The grasp ``offset`` m along the rod (``rod``: its perceived centre) from its centre."""
    d = np.array([np.cos(rod.yaw), np.sin(rod.yaw)])
    return GraspPose(rod.x + offset * d[0], rod.y + offset * d[1], rod.z, rod.yaw)


def plan_trial(
    robot: RobotModel,
    q_seed: np.ndarray,
    detection: RodDetection,
    offset: float,
    approach: float,
    lift_height: float,
    roll_deg: float,
) -> TrialPlan:
    """The grasp ``offset`` m along the rod from its perceived centre (reached from
    ``approach`` m above, IK seeded at ``q_seed``), and the measurement poses: the jaws as
    they grasp, ``lift_height`` m above the world's origin, and the same rolled by
    ``roll_deg`` about ee-x when that is not 0. Raises IKError where a pose is out of reach."""
    rod = detection.grasp
    grasp = grasp_along_rod(rod, offset)
    q_pre, T_world_ee_pre = solve_top_down(robot, grasp, q_seed, dz=approach)
    along = np.array([np.cos(rod.yaw), np.sin(rod.yaw), 0.0])
    centre_hint = -offset * float(along @ T_world_ee_pre[:3, 0])  # rod centre along ee-x
    T_world_ee_meas = grasp_frame(grasp)
    T_world_ee_meas[:3, :3] = robot.ee_pose(q_pre)[:3, :3]
    T_world_ee_meas[2, 3] = lift_height
    T_world_ee_rolled = rolled(T_world_ee_meas, roll_deg) if roll_deg else None
    poses = [solve_ik(robot, T_world_ee_meas, q_pre)]
    if T_world_ee_rolled is not None:
        poses.append(solve_ik(robot, T_world_ee_rolled, poses[0]))
    return TrialPlan(grasp, poses, centre_hint, T_world_ee_meas, detection)


def extra_pose(
    robot: RobotModel, plan: TrialPlan, measured_q: np.ndarray, rolls_deg
) -> np.ndarray | None:
    """(nq,) rad: the first measurement pose rolled about ee-x by the one of ``rolls_deg``
    that adds most information to the poses ``measured_q`` ((k, nq) rad; D-optimal,
    ``best_next_pose``) among those within reach; None when none is."""
    candidates = []
    for roll_deg in rolls_deg:
        T = rolled(plan.T_world_ee_meas, roll_deg)
        try:
            candidates.append(solve_ik(robot, T, plan.poses[0]))
        except IKError:
            continue
    if not candidates:
        return None
    return candidates[best_next_pose(robot, measured_q, np.array(candidates))]


def modelled_tau_before(
    robot: RobotModel, q: np.ndarray, q_measured: list, tau_before: list
) -> np.ndarray:
    """(nq,) N m: the empty arm's torques at ``q`` from the model, carried over by the mean
    difference between ``tau_before`` and the model at the poses ``q_measured``."""
    bias = np.mean([tb - robot.gravity_torques(qm) for tb, qm in zip(tau_before, q_measured,
                    strict=True)], axis=0)  # fmt: skip
    return robot.gravity_torques(q) + bias
