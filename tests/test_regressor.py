"""The regression matrix: Jacobian form == eq. 5 cross products == Pinocchio's regressors."""

import numpy as np
import pinocchio as pin
import pytest
from _payload import panda, payload_torques, ur10

from comgrasp_pin.estimation.regressor import (
    G0,
    GRAVITY_WORLD,
    gravity_in_ee,
    perpendicular_basis,
    pose_regressor,
    regressor_from_jacobian,
    stacked_regressor,
)
from comgrasp_pin.robot import RobotModel

ROBOTS = {"ur5": RobotModel.ur5, "panda": panda, "ur10": ur10}


@pytest.fixture(scope="module", params=list(ROBOTS))
def robot(request) -> RobotModel:
    return ROBOTS[request.param]()


def eq5_regressor(axes: np.ndarray, levers: np.ndarray, R_world_ee: np.ndarray) -> np.ndarray:
    """Paper eq. 5 written out for revolute joints: dtau_i = -a_i . ((r_i + R c) x m g)."""
    n = len(axes)
    Y = np.zeros((n, 4))
    for i in range(n):
        Y[i, 0] = -axes[i] @ np.cross(levers[i], GRAVITY_WORLD)
        for j in range(3):  # unit m*c_ee along ee axis j
            Y[i, 1 + j] = -axes[i] @ np.cross(R_world_ee[:, j], GRAVITY_WORLD)
    return Y


def pinocchio_frame_regressor(robot: RobotModel, q: np.ndarray) -> np.ndarray:
    """First four inertial parameters of a body at the ee frame: J_local^T frameBodyRegressor."""
    model, data = robot.model, robot.model.createData()
    zero = np.zeros(model.nv)
    pin.rnea(model, data, q, zero, zero)
    pin.updateFramePlacements(model, data)
    body = pin.frameBodyRegressor(model, data, robot.ee_frame_id)
    J_local = pin.computeFrameJacobian(model, data, q, robot.ee_frame_id, pin.LOCAL)
    return J_local.T @ body[:, :4]


def pinocchio_joint_torque_regressor(robot: RobotModel, q: np.ndarray) -> np.ndarray:
    """computeJointTorqueRegressor at v = a = 0: the ee parent joint's body columns (params in
    the joint frame), moved to the ee frame: m c_joint = m p_joint_ee + R_joint_ee m c_ee."""
    model, data = robot.model, robot.model.createData()
    zero = np.zeros(model.nv)
    full = pin.computeJointTorqueRegressor(model, data, q, zero, zero)
    frame = model.frames[robot.ee_frame_id]
    cols = full[:, 10 * (frame.parentJoint - 1) : 10 * (frame.parentJoint - 1) + 4]
    placement = frame.placement
    return np.column_stack(
        [cols[:, 0] + cols[:, 1:4] @ placement.translation, cols[:, 1:4] @ placement.rotation]
    )


def test_three_paths_agree(robot):
    rng = np.random.default_rng(3)
    assert robot.is_revolute.all()
    for _ in range(5):
        q = robot.random_configuration(rng)
        Y, T = pose_regressor(robot, q)
        Y_eq5 = eq5_regressor(robot.joint_axes(q), robot.lever_arms(q), T[:3, :3])
        np.testing.assert_allclose(Y, Y_eq5, atol=1e-12)
        np.testing.assert_allclose(pinocchio_frame_regressor(robot, q), Y_eq5, atol=1e-12)
        np.testing.assert_allclose(pinocchio_joint_torque_regressor(robot, q), Y_eq5, atol=1e-12)


def test_regressor_predicts_rnea_payload_torques(robot):
    rng = np.random.default_rng(4)
    Q = np.array([robot.random_configuration(rng) for _ in range(3)])
    mass, com_ee = 0.8, np.array([0.03, -0.05, 0.12])
    tau_before, tau_after = payload_torques(robot, Q, mass, com_ee)
    Y, T = stacked_regressor(robot, Q)
    theta = np.r_[mass, mass * com_ee]
    np.testing.assert_allclose(Y @ theta, (tau_after - tau_before).ravel(), atol=1e-12)
    assert T.shape == (3, 4, 4)
    np.testing.assert_allclose(T[1], robot.ee_pose(Q[1]), atol=1e-14)


def test_gravity_direction_is_the_null_space(robot):
    q = robot.random_configuration(np.random.default_rng(5))
    Y, T = pose_regressor(robot, q)
    u = gravity_in_ee(T[:3, :3])
    np.testing.assert_allclose(T[:3, :3] @ u, [0, 0, -1], atol=1e-14)
    np.testing.assert_allclose(Y[:, 1:] @ u, 0.0, atol=1e-12)
    assert np.linalg.matrix_rank(Y, tol=1e-9 * G0) == 3


def test_prismatic_joint_column_is_the_weight():
    """For a prismatic joint along a, dtau = -a . m g (no moment)."""
    J = np.zeros((6, 1))
    J[:3, 0] = [0.0, 0.6, 0.8]
    Y = regressor_from_jacobian(J, np.eye(3))
    np.testing.assert_allclose(Y, [[0.8 * G0, 0, 0, 0]], atol=1e-14)


@pytest.mark.parametrize("u", [[0, 0, 1.0], [1.0, 0, 0], [0.3, -0.4, 0.866]])
def test_perpendicular_basis(u):
    u = np.array(u) / np.linalg.norm(u)
    E = perpendicular_basis(u)
    np.testing.assert_allclose(E.T @ E, np.eye(2), atol=1e-14)
    np.testing.assert_allclose(E.T @ u, 0.0, atol=1e-14)
