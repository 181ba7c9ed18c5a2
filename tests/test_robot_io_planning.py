"""planning.measurement_poses: planned poses within the limits and free of self-collision
(checked here with a collision model built independently: pin.buildGeomFromUrdf +
pin.computeCollisions),
and a predicted CoM std at least 2x better than four random wrist poses near the start."""

import numpy as np
import pinocchio as pin
import pytest
from _payload import panda

from comgrasp_pin import RobotModel
from comgrasp_pin._paths import example_robot_data_dir, example_robot_urdf
from comgrasp_pin.errors import CollisionError, InvalidInputError
from comgrasp_pin.planning.measurement_poses import plan_measurement_poses, urscript_program
from comgrasp_pin.planning.wrist_poses import predicted_std

STARTS = {
    "panda": np.array([0.0, -0.3, 0.0, -2.2, 0.0, 2.0, 0.8]),
    "ur5": np.array([0.0, -1.6, 1.6, -1.57, -1.57, 0.0]),
}
SIGMA = 0.05 / np.sqrt(200)  # 0.05 N m per sample, 1 s at 200 Hz


def _robot(name):
    return panda() if name == "panda" else RobotModel.ur5()


def _independent_collision_check(robot, srdf):
    """Collision test at an arm configuration, built from scratch here."""
    model = pin.buildModelFromUrdf(str(robot.urdf_path))
    geom = pin.buildGeomFromUrdf(model, str(robot.urdf_path), pin.COLLISION,
                                 package_dirs=[str(example_robot_data_dir().parent)])  # fmt: skip
    geom.addAllCollisionPairs()
    if srdf is not None:
        pin.removeCollisionPairs(model, geom, str(srdf))
    else:  # the same links only: each geometry against every other body's
        for k in reversed(range(len(geom.collisionPairs))):
            p = geom.collisionPairs[k]
            a, b = (geom.geometryObjects[i].parentJoint for i in (p.first, p.second))
            if a == b or model.parents[a] == b or model.parents[b] == a:
                geom.removeCollisionPair(pin.CollisionPair(p.first, p.second))
    data, gdata = model.createData(), geom.createData()
    idx = [model.idx_qs[model.getJointId(n)] for n in robot.joint_names]

    def collides(q):
        qf = pin.neutral(model)
        qf[idx] = q
        return pin.computeCollisions(model, data, geom, gdata, qf, True)

    return collides


@pytest.fixture(scope="module", params=["panda", "ur5"])
def case(request):
    robot = _robot(request.param)
    plan = plan_measurement_poses(robot, 4, start=STARTS[request.param], torque_std=SIGMA)
    return request.param, robot, plan


def test_poses_within_limits_and_collision_free(case):
    name, robot, plan = case
    assert plan.q.shape == (4, robot.nq)
    assert np.all(plan.q >= robot.q_lower) and np.all(plan.q <= robot.q_upper)
    srdf = (example_robot_urdf("panda_description/srdf/panda.srdf") if name == "panda"
            else None)  # fmt: skip
    collides = _independent_collision_check(robot, srdf)
    assert not any(collides(q) for q in plan.q)
    # the check can fail: a folded arm collides
    folded = {"panda": [0, 0, 0, -3.0, 0, 0, 0], "ur5": [0, -1.6, 3.1, 0, 0, 0]}[name]
    assert collides(np.clip(folded, robot.q_lower, robot.q_upper))


def test_predicted_std_beats_random_wrist_poses(case):
    """Four random wrist offsets (+-0.6 rad, plan_wrist_poses' range) around the same start,
    20 draws: the planned poses' worst CoM std is at least 2x smaller than their median."""
    name, robot, plan = case
    rng = np.random.default_rng(2)
    worst = []
    for _ in range(20):
        Q = np.tile(STARTS[name], (4, 1))
        Q[1:, -3:] += rng.uniform(-0.6, 0.6, (3, 3))
        worst.append(predicted_std(robot, Q, SIGMA, 1.0)[1:].max())
    ratio = np.median(worst) / plan.predicted_std[1:].max()
    print(f"{name}: median worst CoM std of random wrist poses / planned = {ratio:.2f}")
    assert ratio >= 2.0


def test_predicted_std_matches_the_estimator_covariance(case):
    """The prediction is the covariance estimate_com reports for the same poses and noise."""
    from _payload import payload_torques

    import comgrasp_pin as cg

    _, robot, plan = case
    tb, ta = payload_torques(robot, plan.q, 1.0, np.zeros(3))
    est = cg.estimate_com(robot, plan.q, tb, ta, torque_std=SIGMA)
    np.testing.assert_allclose(plan.predicted_std, est.std, rtol=1e-6)


def test_urscript_program_only_for_six_joints(case):
    name, _, plan = case
    if name == "ur5":
        text = urscript_program(plan)
        assert text.count("movej(") == 4 and text.startswith("#")
    else:
        with pytest.raises(InvalidInputError, match="6-joint"):
            urscript_program(plan)


def test_colliding_start_is_refused():
    robot = RobotModel.ur5()
    with pytest.raises(CollisionError, match="collides"):
        plan_measurement_poses(robot, 3, start=np.array([0, -1.6, 3.1, 0, 0, 0]))
