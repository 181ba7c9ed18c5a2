"""plan_wrist_poses: wrist-only variations that make the full 3-D CoM observable."""

import numpy as np
import pytest
from _payload import panda, payload_torques

import comgrasp_pin as cg
from comgrasp_pin.errors import ComGraspError
from comgrasp_pin.estimation.regressor import stacked_regressor

MASS, COM_EE, SIGMA = 0.6, np.array([0.02, 0.03, 0.12]), 0.05


@pytest.fixture(scope="module")
def ur5() -> cg.RobotModel:
    return cg.RobotModel.ur5()


def logdet_information(robot, Q) -> float:
    Y = stacked_regressor(robot, Q)[0]
    sign, value = np.linalg.slogdet(Y.T @ Y)
    return value if sign > 0 else -np.inf


@pytest.mark.parametrize("make_robot", [cg.RobotModel.ur5, panda])
def test_shape_wrist_only_and_limits(make_robot):
    robot = make_robot()
    q = robot.random_configuration(np.random.default_rng(40))
    Q = cg.plan_wrist_poses(robot, 4, q).q
    assert Q.shape == (4, robot.nq)
    np.testing.assert_array_equal(Q[0], q)
    np.testing.assert_array_equal(Q[:, :-3], np.tile(q[:-3], (4, 1)))
    assert np.all(Q >= robot.q_lower) and np.all(Q <= robot.q_upper)
    assert np.all(np.abs(Q - q) <= 0.6 + 1e-12)
    assert len(np.unique(Q, axis=0)) == 4
    np.testing.assert_array_equal(cg.plan_wrist_poses(robot, 1, q).q, q[None])


def test_full_3d_com_observable_and_tighter(ur5):
    q = ur5.random_configuration(np.random.default_rng(41))
    Q = cg.plan_wrist_poses(ur5, 4, q).q
    tau_before, tau_after = payload_torques(ur5, Q, MASS, COM_EE)
    full = cg.estimate_com(ur5, Q, tau_before, tau_after, torque_std=SIGMA)
    assert full.unobservable_ee is None
    np.testing.assert_allclose(full.com_ee, COM_EE, atol=1e-9)
    one = cg.estimate_com(ur5, q, tau_before[0], tau_after[0], torque_std=SIGMA)
    u = one.unobservable_ee
    assert np.all(np.isfinite(full.cov)) and np.linalg.eigvalsh(full.cov).min() > 0
    assert abs(u @ one.cov[1:, 1:] @ u) < 1e-15  # one pose: nothing known along gravity
    assert u @ full.cov[1:, 1:] @ u < (0.02) ** 2  # four poses: known to about a cm
    # across gravity the planned set beats even four repeats of the single pose
    P = np.eye(3) - np.outer(u, u)
    assert np.trace(P @ full.cov[1:, 1:] @ P) < np.trace(one.cov[1:, 1:]) / 4
    assert full.std[0] < one.std[0] / 2


def test_planned_beats_random_wrist_poses(ur5):
    rng = np.random.default_rng(42)
    q = ur5.random_configuration(rng)
    planned = logdet_information(ur5, cg.plan_wrist_poses(ur5, 3, q).q)
    random_scores = []
    for _ in range(20):
        Q = np.tile(q, (3, 1))
        Q[1:, -3:] += rng.uniform(-0.6, 0.6, size=(2, 3))
        Q = np.clip(Q, ur5.q_lower, ur5.q_upper)
        random_scores.append(logdet_information(ur5, Q))
    assert planned >= max(random_scores) - 0.2
    assert planned > np.median(random_scores)


def test_bad_input(ur5):
    q = np.zeros(6)
    for k in (0, -1, 1.5, True, "2"):
        with pytest.raises(cg.InvalidInputError, match="k must be an integer"):
            cg.plan_wrist_poses(ur5, k, q)
    with pytest.raises(ComGraspError, match="shape"):
        cg.plan_wrist_poses(ur5, 3, np.zeros(5))
    with pytest.raises(ComGraspError, match="NaN"):
        cg.plan_wrist_poses(ur5, 3, np.full(6, np.nan))
    with pytest.raises(cg.InvalidInputError, match="max_offset"):
        cg.plan_wrist_poses(ur5, 3, q, max_offset=0.0)


def test_the_two_planners_take_the_same_arguments_and_give_the_same_plan(ur5):
    """robot, k, start, torque_std, mass: the same names in the same order, one PosePlan."""
    import inspect

    from comgrasp_pin.robot_io import plan_measurement_poses

    shared = ["robot", "k", "start", "torque_std", "mass"]
    for planner in (cg.plan_wrist_poses, plan_measurement_poses):
        assert list(inspect.signature(planner).parameters)[:5] == shared
    q = np.array([0.0, -1.2, 1.4, -1.8, -1.5, 0.3])
    wrist = cg.plan_wrist_poses(ur5, 3, q, torque_std=0.01, mass=0.5)
    anywhere = plan_measurement_poses(ur5, 3, q, torque_std=0.01, mass=0.5, n_candidates=200)
    for plan in (wrist, anywhere):
        assert isinstance(plan, cg.PosePlan) and plan.q.shape == (3, 6)
        np.testing.assert_array_equal(plan.q[0], q)
        assert (plan.torque_std, plan.mass, plan.ee_frame) == (0.01, 0.5, ur5.ee_frame)
        assert np.all(np.isfinite(plan.predicted_std))
