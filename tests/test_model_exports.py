"""robot_io.payload_files.model_exports: the URDF with the payload loaded back by Pinocchio and by
MuJoCo,
the MJCF body compiled by MuJoCo, against references written here: the payload's ten
parameters moved by the URDF's own joint origins (ElementTree + NumPy, tests/
test_robot_io_payload.urdf_T), gravity torques as m J^T g, MuJoCo's principal moments against
NumPy's eigenvalues."""

import xml.etree.ElementTree as ET

import mujoco
import numpy as np
import pinocchio as pin
import pytest
from test_robot_io_payload import urdf_T

from comgrasp_pin._paths import example_robot_urdf, urdf_path
from comgrasp_pin.errors import InvalidInputError
from comgrasp_pin.robot_io import Payload, load_robot
from comgrasp_pin.robot_io.payload_files import mjcf_payload_body, urdf_with_payload

G = 9.81


def physical_inertia(seed, mass=0.7):
    """A solid box's inertia about its CoM (random sides), turned by a random rotation."""
    rng = np.random.default_rng(seed)
    a, b, c = rng.uniform(0.02, 0.3, 3)
    moments = mass / 12 * np.array([b**2 + c**2, a**2 + c**2, a**2 + b**2])
    R = pin.Quaternion(*rng.normal(size=4)).normalized().toRotationMatrix()
    return R @ np.diag(moments) @ R.T


def _payload(flange, seed=0, inertia=None, mass=0.7):
    rng = np.random.default_rng(seed)
    I = physical_inertia(seed, mass) if inertia is None else inertia
    return Payload(mass, rng.uniform(-0.05, 0.05, 3) + [0, 0, 0.1], I, flange, None, "test")


def _params(mass, com, inertia_com):
    """Pinocchio's ten parameters (m, m c, Ixx Ixy Iyy Ixz Iyz Izz about the origin)."""
    c = np.asarray(com)
    I = inertia_com + mass * (c @ c * np.eye(3) - np.outer(c, c))  # parallel axes
    return np.r_[mass, mass * c, I[0, 0], I[0, 1], I[1, 1], I[0, 2], I[1, 2], I[2, 2]]


def _in_ee(text, p, ee):
    """The payload's CoM and inertia in the ee frame, through the URDF's joint origins."""
    T = urdf_T(text, p.flange_frame, ee)
    R = T[:3, :3]
    return R.T @ (p.com_flange - T[:3, 3]), R.T @ p.inertia_flange @ R


def _tilted_ur5(tmp_path):
    """The project's UR5 with a tool frame tilted off eelink (a rotated ee frame)."""
    text = urdf_path("ur5_gripper.urdf").read_text()
    extra = ('<link name="tcp_tilted"/><joint name="tcp_tilted_joint" type="fixed">'
             '<parent link="eelink"/><child link="tcp_tilted"/>'
             '<origin xyz="0.01 -0.02 0.05" rpy="0.4 -0.7 1.1"/></joint></robot>')  # fmt: skip
    path = tmp_path / "ur5_tilted.urdf"
    path.write_text(text.replace("</robot>", extra))
    return path


CASES = {  # urdf, ee frame (a link or a joint), flange, the URDF link the payload goes on
    "ur5 tilted tcp": ("tilted", "tcp_tilted", "tool0", "tcp_tilted"),
    "ur5 ee a joint": ("tilted", "tcp_tilted_joint", "tool0", "tcp_tilted"),
    "panda": ("panda", "panda_hand_tcp", "panda_link8", "panda_hand_tcp"),
}


def _case(name, tmp_path):
    which, ee, flange, link = CASES[name]
    path = _tilted_ur5(tmp_path) if which == "tilted" else example_robot_urdf(
        "panda_description/urdf/panda.urdf")  # fmt: skip
    return load_robot(path, ee), path, flange, link


@pytest.mark.parametrize("name", list(CASES))
def test_urdf_loads_in_pinocchio_with_the_payload(name, tmp_path):
    robot, path, flange, link = _case(name, tmp_path)
    p = _payload(flange, seed=len(name))
    out = tmp_path / "out" / "with_payload.urdf"
    out.parent.mkdir()
    out.write_text(urdf_with_payload(robot, p, out_dir=out.parent))
    text = path.read_text()
    root = ET.parse(out).getroot()
    joint = root.find("joint[@name='payload_joint']")
    assert joint.get("type") == "fixed" and joint.find("parent").get("link") == link
    inertial = root.find("link[@name='payload']/inertial")
    com_ee, I_ee = _in_ee(text, p, link)
    np.testing.assert_allclose([float(v) for v in inertial.find("origin").get("xyz").split()],
                               com_ee, atol=1e-12)  # fmt: skip
    assert float(inertial.find("mass").get("value")) == p.mass
    a = inertial.find("inertia").attrib
    I_read = np.array([[a["ixx"], a["ixy"], a["ixz"]], [a["ixy"], a["iyy"], a["iyz"]],
                       [a["ixz"], a["iyz"], a["izz"]]], float)  # fmt: skip
    np.testing.assert_allclose(I_read, I_ee, atol=1e-15)
    # Pinocchio: the payload is lumped into the body of the ee's joint; the difference is the
    # payload's ten parameters about that joint's frame (the URDF's own origins moved them)
    m0, m1 = pin.buildModelFromUrdf(str(path)), pin.buildModelFromUrdf(str(out))
    assert m1.existFrame("payload") and m0.nq == m1.nq
    j = m1.frames[m1.getFrameId("payload")].parentJoint
    joint_link = ET.fromstring(text).find(f"joint[@name='{m1.names[j]}']/child").get("link")
    T = urdf_T(text, joint_link, link)
    R, t = T[:3, :3], T[:3, 3]
    expected = _params(p.mass, R @ com_ee + t, R @ I_ee @ R.T)
    diff = m1.inertias[j].toDynamicParameters() - m0.inertias[j].toDynamicParameters()
    np.testing.assert_allclose(diff, expected, atol=1e-12)
    # gravity torques with minus without = m J_c^T (0, 0, g), J_c of the CoM on the old model
    d0, d1 = m0.createData(), m1.createData()
    f_id = m0.getFrameId(link)
    for _ in range(3):
        q = pin.randomConfiguration(m0, -np.ones(m0.nq), np.ones(m0.nq))
        pin.computeJointJacobians(m0, d0, q)
        pin.updateFramePlacements(m0, d0)
        J = pin.getFrameJacobian(m0, d0, f_id, pin.LOCAL_WORLD_ALIGNED)
        lever = d0.oMf[f_id].rotation @ com_ee
        J_c = J[:3] - pin.skew(lever) @ J[3:]
        tau = pin.computeGeneralizedGravity(m1, d1, q) - pin.computeGeneralizedGravity(m0, d0, q)
        np.testing.assert_allclose(tau, J_c.T @ (p.mass * np.array([0, 0, G])), atol=1e-10)


def _mujoco_urdf(path, fusestatic):
    """The URDF for MuJoCo's compiler: no geometry (meshes), static bodies kept or fused."""
    root = ET.parse(path).getroot()
    for link in root.findall("link"):
        for tag in ("visual", "collision"):
            for element in link.findall(tag):
                link.remove(element)
    for old in root.findall("mujoco"):
        root.remove(old)
    extension = ET.SubElement(root, "mujoco")
    ET.SubElement(extension, "compiler", fusestatic=fusestatic, discardvisual="false")
    return ET.tostring(root, encoding="unicode")


def _qfrc_gravity(model, qpos):
    data = mujoco.MjData(model)
    data.qpos[:] = qpos
    mujoco.mj_forward(model, data)
    return data.qfrc_bias.copy()


@pytest.mark.parametrize("inertia", ["full", "point"])
def test_urdf_loads_in_mujoco_with_the_payload(inertia, tmp_path):
    robot, path, flange, link = _case("ur5 tilted tcp", tmp_path)
    p = _payload(flange, seed=3, inertia=None if inertia == "full" else np.zeros((3, 3)))
    out = tmp_path / "with_payload.urdf"
    out.write_text(urdf_with_payload(robot, p))
    com_ee, I_ee = _in_ee(path.read_text(), p, link)
    kept = mujoco.MjModel.from_xml_string(_mujoco_urdf(out, "false"))
    body = kept.body("payload")
    assert body.mass[0] == pytest.approx(p.mass, rel=1e-12)
    assert kept.body(body.parentid[0]).name == link
    # MuJoCo stores the inertia in its principal frame: ipos the CoM, iquat the axes
    np.testing.assert_allclose(body.ipos, com_ee, atol=1e-9)
    np.testing.assert_allclose(np.sort(body.inertia), np.linalg.eigvalsh(I_ee), atol=1e-9)
    R = np.empty(9)
    mujoco.mju_quat2Mat(R, body.iquat)
    R = R.reshape(3, 3)
    np.testing.assert_allclose(R @ np.diag(body.inertia) @ R.T, I_ee, atol=1e-9)
    base = mujoco.MjModel.from_xml_string(_mujoco_urdf(path, "false"))
    assert kept.body_subtreemass[0] - base.body_subtreemass[0] == pytest.approx(p.mass)
    # fused (MuJoCo's default for URDF): the gravity torques grow by the payload's, as
    # Pinocchio computes them from the same file
    fused = mujoco.MjModel.from_xml_string(_mujoco_urdf(out, "true"))
    assert "payload" not in [fused.body(i).name for i in range(fused.nbody)]
    m0, m1 = pin.buildModelFromUrdf(str(path)), pin.buildModelFromUrdf(str(out))
    q = pin.neutral(m0)
    q[:6] = [0.4, -1.2, 1.2, -0.4, 0.8, 1.0]
    qpos = np.zeros(fused.nq)
    for name in robot.joint_names:
        qpos[fused.joint(name).qposadr[0]] = q[m0.joints[m0.getJointId(name)].idx_q]
    g1 = pin.computeGeneralizedGravity(m1, m1.createData(), q)
    pin_diff = g1 - pin.computeGeneralizedGravity(m0, m0.createData(), q)
    mj_diff = _qfrc_gravity(fused, qpos) - _qfrc_gravity(base, qpos)
    for name in robot.joint_names:
        assert mj_diff[fused.joint(name).dofadr[0]] == pytest.approx(
            pin_diff[m0.joints[m0.getJointId(name)].idx_v], abs=1e-6)  # fmt: skip


def _mjcf_in(body_name, snippet, base_xml):
    root = ET.fromstring(base_xml)
    parent = root.find(f".//body[@name='{body_name}']")
    parent.append(ET.fromstring(snippet.split("\n", 1)[1]))
    return mujoco.MjModel.from_xml_string(ET.tostring(root, encoding="unicode"))


@pytest.mark.parametrize("seed", [0, 1])
def test_mjcf_body_in_a_minimal_model(seed):
    p = _payload("flange", seed=seed)
    snippet = mjcf_payload_body(p)
    body = ET.fromstring(snippet.split("\n", 1)[1])
    inertial = body.find("inertial")
    six = [float(v) for v in inertial.get("fullinertia").split()]
    I = p.inertia_flange
    np.testing.assert_allclose(six, [I[0, 0], I[1, 1], I[2, 2], I[0, 1], I[0, 2], I[1, 2]])
    base = ('<mujoco><worldbody><body name="flange" pos="0 0 1"><joint type="hinge"/>'
            '<inertial pos="0 0 0" mass="1" diaginertia="0.01 0.01 0.01"/></body>'
            '</worldbody></mujoco>')  # fmt: skip
    model = _mjcf_in("flange", snippet, base)
    b = model.body("payload")
    assert b.mass[0] == pytest.approx(p.mass)
    np.testing.assert_allclose(b.ipos, p.com_flange, atol=1e-12)
    np.testing.assert_allclose(np.sort(b.inertia), np.linalg.eigvalsh(I), rtol=1e-9)


def test_mjcf_point_mass_compiles():
    p = _payload("flange", inertia=np.zeros((3, 3)))
    base = ('<mujoco><worldbody><body name="flange"><joint type="hinge"/>'
            '<inertial pos="0 0 0" mass="1" diaginertia="0.01 0.01 0.01"/></body>'
            '</worldbody></mujoco>')  # fmt: skip
    model = _mjcf_in("flange", mjcf_payload_body(p), base)
    assert model.body("payload").mass[0] == pytest.approx(p.mass)
    np.testing.assert_array_equal(model.body("payload").inertia, 0.0)


def test_mjcf_body_in_the_robot_puts_the_com_where_pinocchio_does(tmp_path):
    """Pasted in the body its comment names, in MuJoCo's own compile of the URDF: the
    payload's CoM in the world is the flange's pose (Pinocchio) applied to com_flange."""
    robot, path, flange, _ = _case("ur5 tilted tcp", tmp_path)
    p = _payload(flange, seed=5)
    snippet = mjcf_payload_body(p, robot)
    parent = snippet.split('<body name="')[1].split('"')[0]
    assert parent == "wrist_3_link"
    spec = mujoco.MjSpec.from_string(_mujoco_urdf(path, "true"))
    model = _mjcf_in(parent, snippet, spec.to_xml())
    q = np.array([0.4, -1.2, 1.2, -0.4, 0.8, 1.0])
    data = mujoco.MjData(model)
    for name, value in zip(robot.joint_names, q, strict=True):
        data.qpos[model.joint(name).qposadr[0]] = value
    mujoco.mj_forward(model, data)
    T_world_flange = robot.frame_pose(q, flange)  # the reduced model: fingers at neutral
    expected = T_world_flange[:3, :3] @ p.com_flange + T_world_flange[:3, 3]
    np.testing.assert_allclose(data.xipos[model.body("payload").id], expected, atol=1e-9)


def test_urdf_refuses_a_second_payload(tmp_path):
    robot, _, flange, _ = _case("ur5 tilted tcp", tmp_path)
    p = _payload(flange)
    first = tmp_path / "first.urdf"
    first.write_text(urdf_with_payload(robot, p))
    again = load_robot(first, robot.ee_frame)
    with pytest.raises(InvalidInputError, match="already has a link 'payload'"):
        urdf_with_payload(again, p)


def test_relative_mesh_paths_follow_the_file(tmp_path):
    """A mesh path relative to the URDF still names the same file from the output's folder."""
    src = tmp_path / "robot"
    src.mkdir()
    (src / "meshes").mkdir()
    (src / "meshes" / "box.stl").write_text("solid box\nendsolid box\n")
    mesh = '<visual><geometry><mesh filename="meshes/box.stl"/></geometry></visual>'
    text = _tilted_ur5(tmp_path).read_text()
    text = text.replace('<link name="tcp_tilted"/>', f'<link name="tcp_tilted">{mesh}</link>')
    path = src / "robot.urdf"
    path.write_text(text)
    robot = load_robot(path, "tcp_tilted")
    out_dir = tmp_path / "elsewhere" / "deep"
    out_dir.mkdir(parents=True)
    out = urdf_with_payload(robot, _payload("tool0"), out_dir=out_dir)
    mesh = ET.fromstring(out).find("link[@name='tcp_tilted']/visual/geometry/mesh")
    assert (out_dir / mesh.get("filename")).resolve() == (src / "meshes" / "box.stl").resolve()
    package = ET.fromstring(out).find("link[@name='base_link']/visual/geometry/mesh")
    assert package.get("filename").startswith("package://")
