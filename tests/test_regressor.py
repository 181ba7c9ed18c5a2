"""The regression matrix: Jacobian form == eq. 5 cross products == Pinocchio's regressors."""

import numpy as np
import pinocchio as pin
import pytest
from _payload import panda, payload_torques, ur10

from comgrasp_pin.estimation.regressor import (
    pose_regressor,
    stacked_regressor,
)
from comgrasp_pin.robot import RobotModel


def gravity_in_ee(robot: RobotModel, R_world_ee: np.ndarray) -> np.ndarray:
    """(3,) the model's unit gravity direction in the ee frame."""
    g = robot.model.gravity.linear
    return R_world_ee.T @ g / np.linalg.norm(g)


ROBOTS = {"ur5": RobotModel.ur5, "panda": panda, "ur10": ur10}


@pytest.fixture(scope="module", params=list(ROBOTS))
def robot(request) -> RobotModel:
    return ROBOTS[request.param]()


GRAVITY_WORLD = np.array([0.0, 0.0, -9.81])  # the URDFs' models' (Pinocchio's default)


def eq5_regressor(
    axes: np.ndarray, levers: np.ndarray, R_world_ee: np.ndarray, g=GRAVITY_WORLD
) -> np.ndarray:
    """Paper eq. 5 written out for revolute joints: dtau_i = -a_i . ((r_i + R c) x m g)."""
    n = len(axes)
    Y = np.zeros((n, 4))
    for i in range(n):
        Y[i, 0] = -axes[i] @ np.cross(levers[i], g)
        for j in range(3):  # unit m*c_ee along ee axis j
            Y[i, 1 + j] = -axes[i] @ np.cross(R_world_ee[:, j], g)
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
    u = gravity_in_ee(robot, T[:3, :3])
    np.testing.assert_allclose(T[:3, :3] @ u, [0, 0, -1], atol=1e-14)
    np.testing.assert_allclose(Y[:, 1:] @ u, 0.0, atol=1e-12)
    assert np.linalg.matrix_rank(Y, tol=1e-9 * 9.81) == 3


@pytest.mark.parametrize("g", [[0, 0, -9.80665], [0, 0, -1.62], [9.81, 0, 0], [2.0, -3.0, -8.0]])
def test_the_regressor_takes_the_models_gravity(robot, g):
    """Any magnitude and direction: eq. 5 with that g, and RNEA under it with a payload."""
    model_gravity = robot.model.gravity
    robot.model.gravity = pin.Motion(np.array([*g, 0.0, 0.0, 0.0]))
    try:
        rng = np.random.default_rng(7)
        Q = np.array([robot.random_configuration(rng) for _ in range(2)])
        Y, T = stacked_regressor(robot, Q)
        n = robot.nq
        for i, q in enumerate(Q):
            expected = eq5_regressor(robot.joint_axes(q), robot.lever_arms(q), T[i, :3, :3], g)
            np.testing.assert_allclose(Y[i * n : (i + 1) * n], expected, atol=1e-12)
        mass, com_ee = 0.7, np.array([0.02, -0.01, 0.09])
        tau_before, tau_after = payload_torques(robot, Q, mass, com_ee)
        theta = np.r_[mass, mass * com_ee]
        np.testing.assert_allclose(Y @ theta, (tau_after - tau_before).ravel(), atol=1e-12)
        u = gravity_in_ee(robot, T[0, :3, :3])
        np.testing.assert_allclose(T[0, :3, :3] @ u, np.array(g) / np.linalg.norm(g), atol=1e-14)
    finally:
        robot.model.gravity = model_gravity


def test_prismatic_joint_column_is_the_weight():
    """For a prismatic joint along a, dtau = -a . m g (no moment): a one-joint slider."""
    model = pin.Model()
    joint = model.addJoint(0, pin.JointModelPrismaticUnaligned(np.array([0.0, 0.6, 0.8])),
                           pin.SE3.Identity(), "slider")  # fmt: skip
    model.appendBodyToJoint(joint, pin.Inertia.Random(), pin.SE3.Identity())
    model.addFrame(pin.Frame("ee", joint, 0, pin.SE3.Identity(), pin.FrameType.OP_FRAME))
    robot = RobotModel(model, "ee")
    Y, _ = pose_regressor(robot, np.zeros(1))
    np.testing.assert_allclose(Y, [[0.8 * 9.81, 0, 0, 0]], atol=1e-14)
