"""Every controller's payload file, read back by a parser of its own: json for Franka Desk, a
regex for the KRL, Sunrise and RAPID lines, ruamel.yaml for MoveIt (the writer uses PyYAML),
ElementTree for the URDF and MJCF. The principal-axes formats are turned back into a 3x3
inertia with SciPy's rotations, in KUKA's (intrinsic Z, Y', X'') and ABB's (q1 the scalar)
conventions. End to end: `comgrasp estimate` with every --export-* option on a log of the
project's UR5 (MuJoCo torques), each file against RESULT.json moved to the flange frame by the
URDF's own joint origins; bad paths exit 2 with nothing written."""

import json
import re
import xml.etree.ElementTree as ET
from argparse import Namespace

import numpy as np
import pytest
from _logs import mujoco_torques, session
from ruamel.yaml import YAML
from scipy.spatial.transform import Rotation
from test_model_exports import _tilted_ur5, physical_inertia
from test_robot_io_cli import _bad
from test_robot_io_payload import urdf_T

from comgrasp_pin._paths import example_robot_urdf
from comgrasp_pin.cli import main
from comgrasp_pin.cli.exports import EXPORTS, write_exports
from comgrasp_pin.errors import InvalidInputError, OutputError
from comgrasp_pin.robot_io import Payload, load_robot, write_csv
from comgrasp_pin.robot_io.payload_files import (
    franka_desk,
    krl_load,
    moveit_yaml,
    principal_axes,
    rapid_loaddata,
    sunrise_load_data,
)

NUM = r"(-?\d+(?:\.\d+)?)"
KRL = re.compile(rf"\$LOAD=\{{M {NUM},CM \{{X {NUM},Y {NUM},Z {NUM},A {NUM},B {NUM},C {NUM}\}},"
                 rf"J \{{X {NUM},Y {NUM},Z {NUM}\}}\}}")  # fmt: skip
SUNRISE = re.compile(rf"LoadData loadData = new LoadData\({NUM}, XyzAbcTransformation\.ofDeg\("
                     rf"{NUM}, {NUM}, {NUM}, {NUM}, {NUM}, {NUM}\), new Inertia\({NUM}, {NUM}, "
                     rf"{NUM}\)\);")  # fmt: skip
RAPID = re.compile(rf"PERS loaddata (\w+) := \[{NUM}, \[{NUM}, {NUM}, {NUM}\], \[{NUM}, {NUM}, "
                   rf"{NUM}, {NUM}\], {NUM}, {NUM}, {NUM}\];")  # fmt: skip


def _payload(seed, flange="tool0", inertia=None):
    rng = np.random.default_rng(seed)
    I = physical_inertia(seed, 1.3) if inertia is None else inertia
    com = rng.uniform(-0.06, 0.06, 3) + [0, 0, 0.12]
    return Payload(1.3, com, I, flange, None, "identified from a motion", None, 1e-5 * I)


def _last_line(text, comment):
    lines = text.strip().splitlines()
    assert all(line.startswith(comment) for line in lines[:-1]), text
    return lines[-1]


def _kuka_inertia(abc_deg, moments):
    """KUKA: A about Z, B about the new Y, C about the new X (intrinsic Z-Y'-X'')."""
    R = Rotation.from_euler("ZYX", abc_deg, degrees=True).as_matrix()
    return R @ np.diag(moments) @ R.T


def _check_kuka(values, p):
    m, x, y, z, a, b, c, jx, jy, jz = values
    assert m == pytest.approx(p.mass, abs=1e-6)
    np.testing.assert_allclose(np.array([x, y, z]) / 1e3, p.com_flange, atol=1e-7)
    np.testing.assert_allclose(_kuka_inertia([a, b, c], [jx, jy, jz]), p.inertia_flange,
                               atol=1e-8)  # fmt: skip
    assert -180 <= a <= 180 and -90 <= b <= 90 and -180 <= c <= 180


def _check_abb(values, p):
    m, x, y, z, q1, q2, q3, q4, ix, iy, iz = values
    assert m == pytest.approx(p.mass, abs=1e-6)
    np.testing.assert_allclose(np.array([x, y, z]) / 1e3, p.com_flange, atol=1e-7)
    assert np.linalg.norm([q1, q2, q3, q4]) == pytest.approx(1, abs=1e-8) and q1 >= 0
    R = Rotation.from_quat([q2, q3, q4, q1]).as_matrix()  # SciPy: scalar last
    np.testing.assert_allclose(R @ np.diag([ix, iy, iz]) @ R.T, p.inertia_flange, atol=1e-8)


@pytest.mark.parametrize("seed", range(6))
def test_krl_sunrise_and_rapid_rebuild_the_inertia(seed):
    p = _payload(seed)
    krl = KRL.fullmatch(_last_line(krl_load(p), ";"))
    _check_kuka([float(v) for v in krl.groups()], p)
    java = SUNRISE.fullmatch(_last_line(sunrise_load_data(p), "//"))
    _check_kuka([float(v) for v in java.groups()], p)
    rapid = RAPID.fullmatch(_last_line(rapid_loaddata(p), "!"))
    assert rapid.group(1) == "comgrasp_load"
    _check_abb([float(v) for v in rapid.groups()[1:]], p)
    assert "identified" in krl_load(p) and "identified" in rapid_loaddata(p)


def test_a_diagonal_or_point_inertia_has_no_rotation():
    for I in (np.diag([1e-3, 2e-3, 2.5e-3]), np.zeros((3, 3))):
        p = _payload(0, inertia=I)
        values = [float(v) for v in KRL.fullmatch(_last_line(krl_load(p), ";")).groups()]
        assert values[4:7] == [0.0, 0.0, 0.0]
        np.testing.assert_allclose(values[7:], np.diag(I), atol=1e-12)
        abb = [float(v) for v in RAPID.fullmatch(_last_line(rapid_loaddata(p), "!")).groups()[1:]]
        assert abb[4:8] == [1.0, 0.0, 0.0, 0.0]


@pytest.mark.parametrize("seed", range(20))
def test_principal_axes_is_a_rotation_that_diagonalises(seed):
    I = physical_inertia(seed)
    moments, R = principal_axes(I)
    assert np.linalg.det(R) == pytest.approx(1.0)
    np.testing.assert_allclose(R.T @ R, np.eye(3), atol=1e-12)
    np.testing.assert_allclose(R @ np.diag(moments) @ R.T, I, atol=1e-15)


def test_franka_desk_json():
    robot = load_robot(example_robot_urdf("panda_description/urdf/panda.urdf"), "panda_hand_tcp")
    p = _payload(2, "panda_link8")
    from comgrasp_pin.robot_io.payload_files import T_flange_ee

    data = json.loads(json.dumps(franka_desk(p, T_flange_ee(robot, "panda_link8"))))
    assert set(data) == {"mass", "centerOfMass", "transformation", "inertia"}
    assert data["mass"] == p.mass
    np.testing.assert_allclose(data["centerOfMass"], p.com_flange)
    np.testing.assert_allclose(np.reshape(data["inertia"], (3, 3), order="F"), p.inertia_flange)
    T = np.reshape(data["transformation"], (4, 4), order="F")  # column-major, F_T_EE
    text = robot.urdf_path.read_text()
    np.testing.assert_allclose(T, urdf_T(text, "panda_link8", "panda_hand_tcp"), atol=1e-12)
    np.testing.assert_allclose(T[3], [0, 0, 0, 1])


def test_moveit_yaml_with_a_cylinder():
    L, R = 0.3, 0.02
    m = 1.3
    axis = np.array([0.6, 0.0, 0.8])  # the rod's axis in the flange frame
    I_axis = np.diag([m * R**2 / 2, m * (3 * R**2 + L**2) / 12, m * (3 * R**2 + L**2) / 12])
    Rot = Rotation.align_vectors([axis], [[1.0, 0, 0]])[0].as_matrix()
    p = Payload(m, np.array([0.01, 0.0, 0.1]), Rot @ I_axis @ Rot.T, "tool0", None,
                f"cylinder:{L},{R},x")  # fmt: skip
    T = np.eye(4)
    T[:3, :3] = Rotation.from_euler("x", -90, degrees=True).as_matrix()
    T[:3, 3] = [0, 0.0823, 0]
    doc = YAML(typ="safe").load(moveit_yaml(p, "wrist_3_link", T))
    assert doc["link_name"] == "wrist_3_link" and doc["touch_links"] == ["wrist_3_link"]
    assert doc["weight"] == m
    obj = doc["object"]
    assert obj["header"]["frame_id"] == "wrist_3_link" and obj["operation"] == 0
    pos, quat = obj["pose"]["position"], obj["pose"]["orientation"]
    np.testing.assert_allclose([pos["x"], pos["y"], pos["z"]], T[:3, :3] @ p.com_flange + T[:3, 3])
    R_obj = Rotation.from_quat([quat["x"], quat["y"], quat["z"], quat["w"]]).as_matrix()
    np.testing.assert_allclose(R_obj, T[:3, :3], atol=1e-12)
    (prim,), (prim_pose,) = obj["primitives"], obj["primitive_poses"]
    assert prim["type"] == 3 and prim["dimensions"] == [L, R]  # CYLINDER: height, radius
    q = prim_pose["orientation"]
    z = Rotation.from_quat([q["x"], q["y"], q["z"], q["w"]]).apply([0, 0, 1.0])
    assert abs(z @ axis) == pytest.approx(1.0)  # the cylinder's axis along the rod
    point = YAML(typ="safe").load(moveit_yaml(_payload(1)))
    assert "primitives" not in point["object"] and point["link_name"] == "tool0"


def test_a_transform_that_is_not_a_pose_is_refused():
    p = _payload(0)
    mirror = np.diag([1.0, 1.0, -1.0, 1.0])
    for T, words in ((np.eye(3), "shape"), (np.full((4, 4), np.nan), "finite"),
                     (mirror, "rigid transform")):  # fmt: skip
        with pytest.raises(InvalidInputError, match=words):
            franka_desk(p, T)
        with pytest.raises(InvalidInputError, match=words):
            moveit_yaml(p, "tool0", T)


# --- end to end: `comgrasp estimate` with every file ---------------------------------------

MASS, COM = 0.9, np.array([0.03, -0.015, 0.04])  # in eelink
UR_Q = np.array(
    [[0.0, -1.6, 1.6, -1.57, -1.57, 0.0], [0.4, -1.2, 1.2, -0.4, 0.8, 1.0],
     [-0.5, -1.9, 1.5, -2.5, -0.6, -1.2]]
)  # fmt: skip
CYL = (0.3, 0.02)


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    """The static estimate of a UR5 log, every export, a tilted TCP; flange tool0."""
    folder = tmp_path_factory.mktemp("exports")
    urdf = _tilted_ur5(folder)
    robot = load_robot(urdf, "tcp_tilted")
    log, before, after, _ = session(UR_Q, mujoco_torques(MASS, COM), robot.joint_names, 500.0,
                                    0.05, seed=4)  # fmt: skip
    csv = write_csv(log, folder / "log.csv")
    files = {option: folder / f"payload{option.removeprefix('--export')}" for option, _ in EXPORTS}
    base = ["estimate", "--urdf", str(urdf), "--ee-frame", "tcp_tilted", "--csv", str(csv),
            "--before", ",".join(f"{a}:{b}" for a, b in before),
            "--after", ",".join(f"{a}:{b}" for a, b in after)]  # fmt: skip
    args = [*base, "--out", str(folder / "R.json"), "--flange-frame", "tool0",
            "--inertia", f"cylinder:{CYL[0]},{CYL[1]},x"]  # fmt: skip
    for option, path in files.items():
        args += [option, str(path)]
    assert main(args) == 0
    result = json.loads((folder / "R.json").read_text())
    text = urdf.read_text()
    T = urdf_T(text, "tool0", "tcp_tilted")
    m, L, R = result["mass_kg"], *CYL
    I_tcp = np.diag([m * R**2 / 2, m * (3 * R**2 + L**2) / 12, m * (3 * R**2 + L**2) / 12])
    expected = Payload(m, T[:3, :3] @ np.array(result["com_m"]) + T[:3, 3],
                       T[:3, :3] @ I_tcp @ T[:3, :3].T, "tool0", None, "cylinder")  # fmt: skip
    return {"files": files, "result": result, "expected": expected, "T": T, "urdf": urdf,
            "base": base}  # fmt: skip


def test_every_file_is_written_with_the_result(run):
    files, p = run["files"], run["expected"]
    assert run["result"]["mass_kg"] == pytest.approx(MASS, rel=0.05)
    assert not np.allclose(p.inertia_flange, np.diag(np.diag(p.inertia_flange)), atol=1e-6)
    krl = KRL.fullmatch(_last_line(files["--export-kuka"].read_text(), ";"))
    _check_kuka([float(v) for v in krl.groups()], p)
    java = SUNRISE.fullmatch(_last_line(files["--export-kuka-sunrise"].read_text(), "//"))
    _check_kuka([float(v) for v in java.groups()], p)
    rapid = RAPID.fullmatch(_last_line(files["--export-abb"].read_text(), "!"))
    _check_abb([float(v) for v in rapid.groups()[1:]], p)
    desk = json.loads(files["--export-franka-desk"].read_text())
    np.testing.assert_allclose(desk["centerOfMass"], p.com_flange, atol=1e-12)
    np.testing.assert_allclose(np.reshape(desk["inertia"], (3, 3), order="F"), p.inertia_flange,
                               atol=1e-12)  # fmt: skip
    np.testing.assert_allclose(np.reshape(desk["transformation"], (4, 4), order="F"), run["T"],
                               atol=1e-12)  # fmt: skip
    franka = json.loads(files["--export-franka"].read_text())
    np.testing.assert_allclose(franka["F_x_Cload"], p.com_flange, atol=1e-12)
    moveit = YAML(typ="safe").load(files["--export-moveit"].read_text())
    assert moveit["weight"] == pytest.approx(p.mass) and moveit["link_name"] == "tool0"
    pos = moveit["object"]["pose"]["position"]
    np.testing.assert_allclose([pos["x"], pos["y"], pos["z"]], p.com_flange, atol=1e-12)
    assert moveit["object"]["primitives"][0]["dimensions"] == list(CYL)


def test_the_model_files_carry_the_result(run):
    files, result, p = run["files"], run["result"], run["expected"]
    urdf = ET.parse(files["--export-urdf"]).getroot()
    inertial = urdf.find("link[@name='payload']/inertial")
    assert float(inertial.find("mass").get("value")) == pytest.approx(result["mass_kg"])
    xyz = [float(v) for v in inertial.find("origin").get("xyz").split()]
    np.testing.assert_allclose(xyz, result["com_m"], atol=1e-12)  # the ee frame, as RESULT.json
    assert urdf.find("joint[@name='payload_joint']/parent").get("link") == "tcp_tilted"
    body = ET.fromstring(files["--export-mjcf"].read_text().split("\n", 1)[1])
    inertial = body.find("inertial")
    np.testing.assert_allclose([float(v) for v in inertial.get("pos").split()], p.com_flange,
                               atol=1e-12)  # fmt: skip
    six = [float(v) for v in inertial.get("fullinertia").split()]
    I = p.inertia_flange
    np.testing.assert_allclose(six, [I[0, 0], I[1, 1], I[2, 2], I[0, 1], I[0, 2], I[1, 2]],
                               atol=1e-12)  # fmt: skip
    assert load_robot(files["--export-urdf"], "payload").nq == 6  # the written file loads


def _estimate_args(run, tmp_path):
    return [*run["base"], "--out", str(tmp_path / "R.json")]


def test_unwritable_paths_exit_2_and_write_nothing(run, tmp_path, capsys):
    base = _estimate_args(run, tmp_path)
    ok = tmp_path / "load.krl"
    for bad, words in (
        (tmp_path / "missing" / "x.mod", ("--export-abb", "not a folder")),
        (tmp_path, ("--export-abb", "a folder")),
        (ok, ("same file",)),
    ):
        _bad([*base, "--export-kuka", str(ok), "--export-abb", str(bad)], capsys, *words)
        assert not ok.exists() and not (tmp_path / "R.json").exists()
    with pytest.raises(OutputError, match="not a folder"):
        args = Namespace(**{o.removeprefix("--").replace("-", "_"): None for o, _ in EXPORTS})
        args.export_moveit = str(tmp_path / "missing" / "attach.yaml")
        write_exports(args, load_robot(run["urdf"], "tcp_tilted"), run["expected"])


def test_a_urdf_that_has_a_payload_exits_2(run, tmp_path, capsys):
    with_payload = run["urdf"].parent / "already.urdf"
    with_payload.write_text(run["files"]["--export-urdf"].read_text())
    args = _estimate_args(run, tmp_path)
    args[2] = str(with_payload)
    out = tmp_path / "again.urdf"
    _bad([*args, "--export-urdf", str(out)], capsys, "already has a link 'payload'")
    assert not out.exists()


def test_dynamic_estimate_writes_through_the_same_exports(tmp_path):
    """`estimate --dynamic`: the identified inertia in the KRL line, as in RESULT.json."""
    from test_dynamic_estimate import PAYLOAD, fourier_motion, rnea_log

    from comgrasp_pin._paths import urdf_path
    from comgrasp_pin.robot import RobotModel

    robot = RobotModel.ur5()
    motion = fourier_motion(robot, duration=20.0, seed=5)  # the inertia determined (as below)
    logs = {option: str(write_csv(rnea_log(robot, held, motion, seed=seed), tmp_path / name))
            for option, held, seed, name in (("--csv", PAYLOAD, 6, "loaded.csv"),
                                             ("--empty-csv", None, 7, "empty.csv"))}  # fmt: skip
    krl, abb = tmp_path / "load.dat", tmp_path / "load.mod"
    args = ["estimate", "--dynamic", "--urdf", str(urdf_path("ur5_gripper.urdf")),
            "--ee-frame", "eelink", *[w for item in logs.items() for w in item],
            "--out", str(tmp_path / "R.json"), "--export-kuka", str(krl),
            "--export-abb", str(abb)]  # fmt: skip
    assert main(args) == 0
    result = json.loads((tmp_path / "R.json").read_text())
    inertia = np.array(result["inertia"]["inertia_kgm2"])
    p = Payload(result["mass_kg"], np.array(result["com_m"]), inertia, "eelink", None, "identified")
    _check_kuka([float(v) for v in KRL.fullmatch(_last_line(krl.read_text(), ";")).groups()], p)
    values = RAPID.fullmatch(_last_line(abb.read_text(), "!")).groups()[1:]
    _check_abb([float(v) for v in values], p)
    assert "identified" in krl.read_text()
