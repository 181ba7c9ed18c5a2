"""Top-down IK: checked by forward kinematics, joint limits, branch, and arm clearance."""

import numpy as np
import pytest
from _clearance import link_points, scene_clearance

from comgrasp_pin.errors import IKError
from comgrasp_pin.geometry import GraspPose
from comgrasp_pin.motion.ik import (
    grasp_frame,
    grasp_height,
    solve_ik,
    solve_top_down,
    top_down_frame,
)
from comgrasp_pin.motion.trajectory import Quintic
from comgrasp_pin.workcell import Q_HOME


def _random_grasps(n, seed=0):
    rng = np.random.default_rng(seed)
    return [
        GraspPose(
            rng.uniform(0.35, 0.75),
            rng.uniform(-0.30, 0.30),
            rng.uniform(0.005, 0.03),
            rng.uniform(-np.pi, np.pi),
        )
        for _ in range(n)
    ]


def test_top_down_frame_is_a_rotation_with_z_down():
    T = top_down_frame(0.5, 0.1, 0.2, 0.7)
    R = T[:3, :3]
    np.testing.assert_allclose(R.T @ R, np.eye(3), atol=1e-12)
    assert np.linalg.det(R) == pytest.approx(1.0)
    np.testing.assert_allclose(R[:, 2], [0, 0, -1])
    np.testing.assert_allclose(R[:, 0], [np.cos(0.7), np.sin(0.7), 0], atol=1e-12)
    assert grasp_height(0.005) == pytest.approx(0.017)
    assert grasp_height(0.03) == pytest.approx(0.03)


def test_ik_reaches_random_top_down_grasps(ur5):
    for g in _random_grasps(25):
        for dz in (0.0, 0.15):
            q, T = solve_top_down(ur5, g, Q_HOME, dz=dz)
            T_fk = ur5.ee_pose(q)  # independent check: forward kinematics
            np.testing.assert_allclose(T_fk, T, atol=1e-7)
            assert np.all(q >= ur5.q_lower) and np.all(q <= ur5.q_upper)
            # same rod axis, either direction
            assert abs(T_fk[:3, 0] @ [np.cos(g.yaw), np.sin(g.yaw), 0]) == pytest.approx(1.0)
            assert T_fk[2, 3] == pytest.approx(grasp_height(g.z) + dz)
            # boom (ee -y) away from the robot base
            assert -T_fk[:2, 1] @ T_fk[:2, 3] >= -1e-9
            # elbow up and wrist down, close to the seed branch
            assert q[2] > 0.0 and abs(q[4] - Q_HOME[4]) < 0.5
            assert abs(q[5] - Q_HOME[5]) <= np.pi + 1e-9


def test_arm_clears_table_along_approach_moves(ur5):
    """Joint-space moves home -> above grasp, and the straight descent, keep every arm and
    gripper point above the table; only the fingertips go down to it (>= 2 mm)."""
    for g in _random_grasps(10, seed=1):
        q_pre, _ = solve_top_down(ur5, g, Q_HOME, dz=0.15)
        for t in np.linspace(0, 1, 21):
            q = Quintic(Q_HOME, q_pre, 1.0).sample(t)[0]
            pts = link_points(ur5, q)
            assert scene_clearance(pts["arm"]).min() > 0.08
            assert scene_clearance(pts["gripper"]).min() > 0.15
        q = q_pre
        for dz in np.linspace(0.15, 0.0, 16):
            q = solve_ik(ur5, grasp_frame(g, dz), q)
            pts = link_points(ur5, q)
            assert scene_clearance(pts["arm"]).min() > 0.08
            assert scene_clearance(pts["gripper"]).min() > 0.09 + dz
            assert scene_clearance(pts["fingertips"]).min() >= 0.002 - 1e-9


def test_unreachable_pose_raises(ur5):
    with pytest.raises(IKError):
        solve_ik(ur5, top_down_frame(2.0, 0.0, 0.1, 0.0), Q_HOME, max_iter=50)
