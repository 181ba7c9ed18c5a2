"""robot_io.payload_files.payload / exports: the CoM in the flange frame against a conversion
written here
from the URDF's joint origins (ElementTree + NumPy, not Pinocchio); inertia approximations;
the exported files parsed back (json, ruamel.yaml, a regex for URScript)."""

import json
import re
import xml.etree.ElementTree as ET

import numpy as np
import pytest
from _logs import rnea_torques, session
from _payload import panda

from comgrasp_pin._paths import example_robot_urdf, urdf_path
from comgrasp_pin.errors import InvalidInputError
from comgrasp_pin.robot_io import estimate_from_log, load_robot, payload_in_flange
from comgrasp_pin.robot_io.payload_files import franka_load, ros2_yaml, urscript

MASS, COM = 0.7, np.array([0.015, 0.02, 0.045])


def _rpy(r, p, y):
    cr, sr, cp, sp, cy, sy = np.cos(r), np.sin(r), np.cos(p), np.sin(p), np.cos(y), np.sin(y)
    Rx = np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
    Ry = np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
    Rz = np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
    return Rz @ Ry @ Rx  # URDF: fixed-axis roll, pitch, yaw


def urdf_T(urdf_text, parent_link, child_link):
    """T_parent_child through the URDF's fixed joints, from their <origin> elements."""
    joints = {j.find("child").get("link"): j for j in ET.fromstring(urdf_text).findall("joint")}
    T = np.eye(4)
    link = child_link
    while link != parent_link:
        j = joints[link]
        assert j.get("type") == "fixed", f"{j.get('name')} is not fixed"
        o = j.find("origin")
        step = np.eye(4)
        if o is not None:
            step[:3, :3] = _rpy(*map(float, o.get("rpy", "0 0 0").split()))
            step[:3, 3] = list(map(float, o.get("xyz", "0 0 0").split()))
        T = step @ T
        link = j.find("parent").get("link")
    return T


def _estimate(robot, Q, seed=0):
    log, before, after, _ = session(Q, rnea_torques(robot, MASS, COM), robot.joint_names,
                                    200.0, 0.05, seed=seed)  # fmt: skip
    return estimate_from_log(robot, log, before, after)


PANDA_Q = np.array(
    [[0.0, -0.3, 0.0, -2.2, 0.0, 2.0, 0.8], [0.5, -0.6, 0.3, -1.8, 1.2, 1.2, -0.6],
     [-0.4, 0.2, -0.2, -2.4, -1.0, 2.6, 1.5]]
)  # fmt: skip
UR_Q = np.array(
    [[0.0, -1.6, 1.6, -1.57, -1.57, 0.0], [0.4, -1.2, 1.2, -0.4, 0.8, 1.0],
     [-0.5, -1.9, 1.5, -2.5, -0.6, -1.2]]
)  # fmt: skip


def _check_flange(robot, est, urdf_text, flange):
    T = urdf_T(urdf_text, flange, robot.ee_frame)
    p = payload_in_flange(robot, est, flange)
    np.testing.assert_allclose(p.com_flange, T[:3, :3] @ est.com_ee + T[:3, 3], atol=1e-12)
    truth_flange = T[:3, :3] @ COM + T[:3, 3]
    assert np.all(np.abs(p.com_flange - truth_flange) < 3 * p.std[1:])
    assert p.mass == est.mass and p.flange_frame == flange
    return p


def test_panda_com_in_link8():
    robot = panda()  # ee panda_hand_tcp: rotated by -45 deg about z and 0.1034 m out
    est = _estimate(robot, PANDA_Q)
    _check_flange(robot, est, robot.urdf_path.read_text(), "panda_link8")


def test_ur5_com_in_tool0_from_a_rotated_ee_frame(tmp_path):
    text = example_robot_urdf("ur_description/urdf/ur5_robot.urdf").read_text()
    extra = ('<link name="tcp_tilted"/><joint name="tcp_tilted_joint" type="fixed">'
             '<parent link="tool0"/><child link="tcp_tilted"/>'
             '<origin xyz="0.01 -0.02 0.15" rpy="0.4 -0.7 1.1"/></joint></robot>')  # fmt: skip
    text = text.replace("</robot>", extra)
    path = tmp_path / "ur5_tilted.urdf"
    path.write_text(text)
    robot = load_robot(path, "tcp_tilted")
    _check_flange(robot, _estimate(robot, UR_Q), text, "tool0")


def test_project_ur5_eelink_in_tool0():
    robot = load_robot(urdf_path("ur5_gripper.urdf"), "eelink")
    _check_flange(robot, _estimate(robot, UR_Q), urdf_path("ur5_gripper.urdf").read_text(), "tool0")


def test_flange_on_another_link_is_refused():
    robot = panda()
    with pytest.raises(InvalidInputError, match="same link chain"):
        payload_in_flange(robot, _estimate(robot, PANDA_Q), "panda_link3")


def test_cylinder_inertia_against_the_formula():
    robot = panda()
    est = _estimate(robot, PANDA_Q)
    L, R = 0.3, 0.02
    p = payload_in_flange(robot, est, "panda_link8", f"cylinder:{L},{R},x")
    m = est.mass
    I_ee = np.diag([m * R**2 / 2, m * (3 * R**2 + L**2) / 12, m * (3 * R**2 + L**2) / 12])
    Rf = urdf_T(robot.urdf_path.read_text(), "panda_link8", robot.ee_frame)[:3, :3]
    np.testing.assert_allclose(p.inertia_flange, Rf @ I_ee @ Rf.T, atol=1e-12)
    np.testing.assert_array_equal(p.inertia_flange, p.inertia_flange.T)
    assert np.linalg.eigvalsh(p.inertia_flange).min() >= 0
    point = payload_in_flange(robot, est, "panda_link8", "point")
    np.testing.assert_array_equal(point.inertia_flange, np.zeros((3, 3)))
    for bad in ("sphere:1", "cylinder:0.3,0.02", "cylinder:-1,0.02,x", "cylinder:1,2,w"):
        with pytest.raises(InvalidInputError, match="valid are|must be"):
            payload_in_flange(robot, est, "panda_link8", bad)


@pytest.fixture(scope="module")
def payload():
    robot = panda()
    return payload_in_flange(robot, _estimate(robot, PANDA_Q), "panda_link8", "cylinder:0.3,0.02,x")


def test_urscript_line(payload):
    text = urscript(payload)
    assert all(line.startswith("#") for line in text.splitlines()[:-1])
    assert "approximation" in text
    num = r"(-?[\d.eE+-]+)"
    vec3, vec6 = r",\s*".join([num] * 3), r",\s*".join([num] * 6)
    m = re.fullmatch(rf"set_target_payload\({num}, \[{vec3}\], \[{vec6}\]\)",
                     text.splitlines()[-1])  # fmt: skip
    assert m, text
    values = np.array([float(v) for v in m.groups()])
    I = payload.inertia_flange
    np.testing.assert_allclose(values[0], payload.mass, rtol=1e-8)
    np.testing.assert_allclose(values[1:4], payload.com_flange, rtol=1e-8, atol=1e-12)
    six = [I[0, 0], I[1, 1], I[2, 2], I[0, 1], I[0, 2], I[1, 2]]
    np.testing.assert_allclose(values[4:], six, rtol=1e-8, atol=1e-12)


def test_franka_json(payload):
    data = json.loads(json.dumps(franka_load(payload)))
    assert {"mass", "F_x_Cload", "load_inertia"} <= set(data)
    np.testing.assert_allclose(data["F_x_Cload"], payload.com_flange)
    I = np.array(data["load_inertia"]).reshape(3, 3, order="F")  # column-major
    np.testing.assert_allclose(I, payload.inertia_flange)
    assert "approximation" in data["comment"]


def test_ros2_yaml_parses_with_the_request_fields(payload):
    from ruamel.yaml import YAML

    text = ros2_yaml(payload)
    assert "approximation" in text
    doc = YAML(typ="safe").load(text)
    ur, fr = doc["ur_msgs/srv/SetPayload"], doc["franka_msgs/srv/SetLoad"]
    assert {"mass", "center_of_gravity"} <= set(ur)
    c = ur["center_of_gravity"]
    np.testing.assert_allclose([c["x"], c["y"], c["z"]], payload.com_flange, rtol=1e-8)
    np.testing.assert_allclose(ur["ixy"], payload.inertia_flange[0, 1], rtol=1e-8)
    assert set(fr) == {"mass", "center_of_mass", "load_inertia"}
    np.testing.assert_allclose(fr["center_of_mass"], payload.com_flange, rtol=1e-8)
    I = np.array(fr["load_inertia"]).reshape(3, 3, order="F")
    np.testing.assert_allclose(I, payload.inertia_flange, rtol=1e-8, atol=1e-15)
