"""RobotModel against hand-derived statics: a planar two-link arm and the UR5's URDF by hand."""

import xml.etree.ElementTree as ET

import numpy as np
import pytest

import comgrasp_pin as cg
from comgrasp_pin._paths import example_robot_urdf, urdf_path
from comgrasp_pin.errors import ComGraspError

G = 9.81

TWO_LINK_URDF = """<?xml version="1.0"?>
<robot name="two_link">
  <link name="base"/>
  <link name="link1">
    <inertial><mass value="{m1}"/><origin xyz="{c1} 0 0"/>
      <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial>
  </link>
  <link name="link2">
    <inertial><mass value="{m2}"/><origin xyz="{c2} 0 0"/>
      <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial>
  </link>
  <link name="tip"/>
  <joint name="j1" type="revolute"><parent link="base"/><child link="link1"/>
    <origin xyz="0 0 0"/><axis xyz="0 -1 0"/><limit lower="-3" upper="3" effort="1" velocity="1"/>
  </joint>
  <joint name="j2" type="revolute"><parent link="link1"/><child link="link2"/>
    <origin xyz="{l1} 0 0"/><axis xyz="0 -1 0"/>
    <limit lower="-3" upper="3" effort="1" velocity="1"/>
  </joint>
  <joint name="tip_joint" type="fixed"><parent link="link2"/><child link="tip"/>
    <origin xyz="{l2} 0 0"/></joint>
</robot>
"""


def test_two_link_gravity_matches_hand_derivation(tmp_path):
    m1, m2, l1, l2, c1, c2 = 2.0, 1.5, 0.5, 0.4, 0.2, 0.25
    path = tmp_path / "two_link.urdf"
    path.write_text(TWO_LINK_URDF.format(m1=m1, m2=m2, l1=l1, l2=l2, c1=c1, c2=c2))
    robot = cg.RobotModel.from_urdf(path, "tip")
    assert robot.nq == 2
    rng = np.random.default_rng(0)
    for _ in range(20):
        q1, q2 = rng.uniform(-3, 3, 2)
        # Axis -y: positive q lifts the arm in the x-z plane; links lie along x.
        # Holding torque = moment of the weights below each joint about that joint.
        tau2 = m2 * G * c2 * np.cos(q1 + q2)
        tau1 = (m1 * c1 + m2 * l1) * G * np.cos(q1) + tau2
        np.testing.assert_allclose(robot.gravity_torques([q1, q2]), [tau1, tau2], atol=1e-10)
        # Tip position and lever arms by hand.
        tip = np.array(
            [l1 * np.cos(q1) + l2 * np.cos(q1 + q2), 0, l1 * np.sin(q1) + l2 * np.sin(q1 + q2)]
        )
        np.testing.assert_allclose(robot.ee_pose([q1, q2])[:3, 3], tip, atol=1e-12)
        elbow = np.array([l1 * np.cos(q1), 0, l1 * np.sin(q1)])
        np.testing.assert_allclose(robot.lever_arms([q1, q2]), [tip, tip - elbow], atol=1e-12)
        np.testing.assert_allclose(robot.joint_axes([q1, q2]), [[0, -1, 0], [0, -1, 0]], atol=1e-12)


def _rpy_matrix(rpy):
    r, p, y = rpy
    rx = np.array([[1, 0, 0], [0, np.cos(r), -np.sin(r)], [0, np.sin(r), np.cos(r)]])
    ry = np.array([[np.cos(p), 0, np.sin(p)], [0, 1, 0], [-np.sin(p), 0, np.cos(p)]])
    rz = np.array([[np.cos(y), -np.sin(y), 0], [np.sin(y), np.cos(y), 0], [0, 0, 1]])
    return rz @ ry @ rx


def _floats(text, default="0 0 0"):
    return np.array([float(v) for v in (text or default).split()])


def _urdf_statics_by_hand(path, q_by_joint):
    """World joint axes/origins and link (mass, CoM) from the URDF text, no Pinocchio."""
    root = ET.parse(path).getroot()
    links = {}
    for link in root.findall("link"):
        inertial = link.find("inertial")
        if inertial is None:
            links[link.get("name")] = (0.0, np.zeros(3))
            continue
        origin = inertial.find("origin")
        links[link.get("name")] = (
            float(inertial.find("mass").get("value")),
            _floats(None if origin is None else origin.get("xyz")),
        )
    children = {}
    for joint in root.findall("joint"):
        children.setdefault(joint.find("parent").get("link"), []).append(joint)
    poses, joints, parents_of = {"world": np.eye(4)}, {}, {"world": []}
    stack = ["world"]
    while stack:
        parent = stack.pop()
        for joint in children.get(parent, []):
            origin = joint.find("origin")
            T = np.eye(4)
            T[:3, :3] = _rpy_matrix(_floats(origin.get("rpy")))
            T[:3, 3] = _floats(origin.get("xyz"))
            T_joint = poses[parent] @ T
            child = joint.find("child").get("link")
            name, kind = joint.get("name"), joint.get("type")
            chain = list(parents_of[parent])
            if kind in ("revolute", "prismatic"):
                axis = T_joint[:3, :3] @ _floats(joint.find("axis").get("xyz"))
                joints[name] = (axis, T_joint[:3, 3].copy())
                motion = np.eye(4)
                qv = q_by_joint.get(name, 0.0)
                if kind == "revolute":
                    a = _floats(joint.find("axis").get("xyz"))
                    K = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
                    motion[:3, :3] = np.eye(3) + np.sin(qv) * K + (1 - np.cos(qv)) * K @ K
                else:
                    motion[:3, 3] = qv * _floats(joint.find("axis").get("xyz"))
                T_joint = T_joint @ motion
                chain.append(name)
            poses[child] = T_joint
            parents_of[child] = chain
            stack.append(child)
    bodies = []
    for name, (mass, com) in links.items():
        bodies.append((mass, poses[name][:3, :3] @ com + poses[name][:3, 3], parents_of[name]))
    return joints, bodies


def test_ur5_gravity_matches_sum_over_links_from_urdf():
    robot = cg.RobotModel.ur5()
    path = urdf_path("ur5_gripper.urdf")
    g = np.array([0.0, 0.0, -G])
    rng = np.random.default_rng(1)
    for _ in range(10):
        q = robot.random_configuration(rng)
        joints, bodies = _urdf_statics_by_hand(path, dict(zip(robot.joint_names, q)))
        tau = np.zeros(robot.nq)
        for i, name in enumerate(robot.joint_names):
            a_i, p_i = joints[name]
            for mass, c_k, chain in bodies:
                if name in chain:
                    tau[i] -= a_i @ np.cross(c_k - p_i, mass * g)
        np.testing.assert_allclose(robot.gravity_torques(q), tau, atol=1e-9)
        np.testing.assert_allclose(
            robot.joint_axes(q), [joints[n][0] for n in robot.joint_names], atol=1e-9
        )
        np.testing.assert_allclose(
            robot.joint_origins(q), [joints[n][1] for n in robot.joint_names], atol=1e-9
        )


def test_any_arm_from_example_robot_data():
    panda = cg.RobotModel.from_urdf(
        example_robot_urdf("panda_description/urdf/panda.urdf"), "panda_hand_tcp"
    )
    assert panda.nq == 7
    assert panda.joint_names[0] == "panda_joint1"
    q = 0.5 * (panda.q_lower + panda.q_upper)
    T = panda.ee_pose(q)
    np.testing.assert_allclose(T[:3, :3] @ T[:3, :3].T, np.eye(3), atol=1e-12)
    lever = panda.lever_arms(q)
    np.testing.assert_allclose(lever, T[:3, 3] - panda.joint_origins(q), atol=1e-12)
    ur10 = cg.RobotModel.from_urdf(
        example_robot_urdf("ur_description/urdf/ur10_robot.urdf"), "tool0"
    )
    assert ur10.nq == 6


def test_unknown_frame_lists_frames():
    with pytest.raises(ComGraspError, match="eelink"):
        cg.RobotModel.from_urdf(urdf_path("ur5_gripper.urdf"), "no_such_frame")


@pytest.mark.parametrize("q", [np.zeros(5), np.zeros((2, 6)), np.array([0, 0, np.nan, 0, 0, 0])])
def test_bad_configuration_raises(q):
    robot = cg.RobotModel.ur5()
    with pytest.raises(ComGraspError, match="q "):
        robot.gravity_torques(q)


def test_missing_urdf_raises(tmp_path):
    with pytest.raises(ComGraspError, match="not found"):
        cg.RobotModel.from_urdf(tmp_path / "nope.urdf", "tool0")
