"""The payload regressor against Pinocchio RNEA with the payload appended as a body."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from comgrasp_pin.errors import InvalidInputError
from comgrasp_pin.estimation.payload_regressor import (
    condition_number,
    parameter_scale,
    payload_regressor,
)
from comgrasp_pin.estimation.regressor import stacked_regressor
from comgrasp_pin.robot import RobotModel
from comgrasp_pin.robot_io.front_door import load_robot
from tests._payload import panda


@pytest.fixture(scope="module", params=["ur5", "panda"])
def robot(request) -> RobotModel:
    return RobotModel.ur5() if request.param == "ur5" else panda()


def _random_inertia(rng: np.random.Generator) -> pin.Inertia:
    """A physically valid payload: mass 0.2-3 kg, CoM within 0.2 m, a random box's inertia
    about its CoM in random principal axes (triangle inequality holds)."""
    mass = rng.uniform(0.2, 3.0)
    sides = rng.uniform(0.02, 0.3, size=3)
    principal = mass / 12 * (np.sum(sides**2) - sides**2)
    R = pin.Quaternion(rng.normal(size=4)).normalized().toRotationMatrix()
    return pin.Inertia(mass, rng.uniform(-0.2, 0.2, size=3), R @ np.diag(principal) @ R.T)


def _rnea_difference(robot, inertia, q, qd, qdd) -> np.ndarray:
    """Independent reference: RNEA of the model with the payload appended as a body at the
    ee frame, minus RNEA without it (N m)."""
    loaded = pin.Model(robot.model)
    frame = loaded.frames[robot.ee_frame_id]
    loaded.appendBodyToJoint(frame.parentJoint, inertia, frame.placement)
    d0, d1 = robot.model.createData(), loaded.createData()
    return pin.rnea(loaded, d1, q, qd, qdd) - pin.rnea(robot.model, d0, q, qd, qdd)


def test_matches_rnea_with_the_payload_appended(robot):
    rng = np.random.default_rng(1)
    k = 8
    Q = np.array([robot.random_configuration(rng) for _ in range(k)])
    QD, QDD = rng.normal(0, 1.5, size=(2, k, robot.nq))
    Y = payload_regressor(robot, Q, QD, QDD)
    assert Y.shape == (k, robot.nq, 10)
    for i in range(k):
        inertia = _random_inertia(rng)
        expected = _rnea_difference(robot, inertia, Q[i], QD[i], QDD[i])
        got = Y[i] @ inertia.toDynamicParameters()
        np.testing.assert_allclose(got, expected, atol=1e-9, rtol=0)
        single = payload_regressor(robot, Q[i], QD[i], QDD[i])
        np.testing.assert_allclose(single, Y[i], atol=1e-12)


def test_static_case_is_the_static_regressor(robot):
    rng = np.random.default_rng(2)
    Q = np.array([robot.random_configuration(rng) for _ in range(5)])
    Y = payload_regressor(robot, Q, np.zeros_like(Q), np.zeros_like(Q))
    Y_static, _ = stacked_regressor(robot, Q)
    np.testing.assert_allclose(Y[..., :4].reshape(-1, 4), Y_static, atol=1e-9)
    np.testing.assert_allclose(Y[..., 4:], 0.0, atol=1e-12)


def test_uses_the_models_gravity_a_wall_mount():
    wall = load_robot(RobotModel.ur5().urdf_path, "eelink", gravity_base=(9.81, 0, 0))
    rng = np.random.default_rng(3)
    q, qd, qdd = wall.random_configuration(rng), rng.normal(size=6), rng.normal(size=6)
    inertia = _random_inertia(rng)
    expected = _rnea_difference(wall, inertia, q, qd, qdd)
    got = payload_regressor(wall, q, qd, qdd) @ inertia.toDynamicParameters()
    np.testing.assert_allclose(got, expected, atol=1e-9)


def test_condition_number_scaling():
    rng = np.random.default_rng(4)
    Y = rng.normal(size=(30, 10)) * np.array([1, 1, 1, 1, 9, 9, 9, 9, 9, 9.0])
    scale = np.array([1, 1, 1, 1, 1 / 9, 1 / 9, 1 / 9, 1 / 9, 1 / 9, 1 / 9])
    assert condition_number(Y, scale) == pytest.approx(np.linalg.cond(Y * scale))
    assert condition_number(np.zeros((5, 10))) == float("inf")
    np.testing.assert_allclose(parameter_scale(0.1, 2.0)[[0, 1, 4]], [2.0, 0.2, 0.02])


def test_bad_input():
    robot = RobotModel.ur5()
    z = np.zeros(6)
    with pytest.raises(InvalidInputError, match="same shape"):
        payload_regressor(robot, z, z, np.zeros(5))
    with pytest.raises(InvalidInputError, match="NaN"):
        payload_regressor(robot, z, np.full(6, np.nan), z)
    with pytest.raises(InvalidInputError):
        parameter_scale(0.0)
