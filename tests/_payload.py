"""Independent reference for the estimator tests: Pinocchio RNEA with a payload body."""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from comgrasp_pin._paths import example_robot_urdf
from comgrasp_pin.robot import RobotModel


def panda() -> RobotModel:
    return RobotModel.from_urdf(
        example_robot_urdf("panda_description/urdf/panda.urdf"), "panda_hand_tcp"
    )


def ur10() -> RobotModel:
    return RobotModel.from_urdf(example_robot_urdf("ur_description/urdf/ur10_robot.urdf"), "tool0")


def payload_model(robot: RobotModel, mass: float, com_ee: np.ndarray) -> pin.Model:
    """A copy of ``robot.model`` with a body (mass, CoM com_ee in the ee frame, some rotational
    inertia) appended to the ee frame's parent joint at the ee frame placement."""
    model = pin.Model(robot.model)
    frame = model.frames[robot.ee_frame_id]
    inertia = pin.Inertia(mass, np.asarray(com_ee, float), np.diag([2e-3, 3e-3, 4e-3]))
    model.appendBodyToJoint(frame.parentJoint, inertia, frame.placement)
    return model


def payload_torques(
    robot: RobotModel, Q: np.ndarray, mass: float, com_ee: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """(tau_before, tau_after), shape of Q ((n,) or (k, n)): RNEA at v = a = 0 (N m)."""
    Q = np.asarray(Q, float)
    Qk = Q.reshape(-1, robot.nq)
    loaded = payload_model(robot, mass, com_ee)
    d0, d1 = robot.model.createData(), loaded.createData()
    z = np.zeros(robot.nq)
    tb = np.array([pin.rnea(robot.model, d0, q, z, z) for q in Qk])
    ta = np.array([pin.rnea(loaded, d1, q, z, z) for q in Qk])
    return tb.reshape(Q.shape), ta.reshape(Q.shape)
