"""Files from elsewhere (issue 27, item 5): URDFs, MJCFs, bags, CSVs and run settings that
are truncated, malformed, entity bombs, endless (a FIFO, /dev/zero), huge (a 2 GB sparse
file), that name files outside their folder, or have non-UTF-8 names. Each is a real file in
tmp_path; each ends in a ComGraspError through the Python API, and in exit status 2 with a
message and no traceback through `comgrasp estimate`, within the subprocess' time limit,
writing nothing (the --out file does not exist afterwards)."""

import os
import signal
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from comgrasp_pin._paths import urdf_path
from comgrasp_pin.errors import ComGraspError, LogError, ResumeError
from comgrasp_pin.robot import RobotModel
from comgrasp_pin.robot_io import JointLog, write_bag
from comgrasp_pin.robot_io.front_door import load_robot
from comgrasp_pin.robot_io.log_files import read_bag, read_csv
from comgrasp_pin.simulation.mjcf_files import load_mjcf

UR5 = urdf_path("ur5_gripper.urdf").read_text()
JOINTS = ("shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint", "wrist_1_joint",
          "wrist_2_joint", "wrist_3_joint")  # fmt: skip
API_BOUND_S = 20  # every API call here ends long before; a FIFO read would block for ever
CLI_BOUND_S = 60  # a `comgrasp estimate` subprocess, start-up included (~1.5 s)
BOMB = (
    '<?xml version="1.0"?>\n<!DOCTYPE r [<!ENTITY a "aaaaaaaaaa">'
    + "".join(f'<!ENTITY {chr(98 + k)} "{("&" + chr(97 + k) + ";") * 10}">' for k in range(9))
    + ']>\n<robot name="&j;"/>\n'
)  # fmt: skip  (10^10 characters if expanded)
XXE = (
    '<?xml version="1.0"?><!DOCTYPE r [<!ENTITY x SYSTEM "file:///etc/passwd">]><robot name="&x;"/>'
)
NON_UTF8 = os.fsdecode(b"caf\xe9")  # a name in Latin-1: not UTF-8


@pytest.fixture(autouse=True)
def bounded():
    """An API call that blocks (a FIFO opened) fails the test instead of hanging it."""

    def stuck(*_):
        raise TimeoutError(f"still reading after {API_BOUND_S} s")

    before = signal.signal(signal.SIGALRM, stuck)
    signal.alarm(API_BOUND_S)
    yield
    signal.alarm(0)
    signal.signal(signal.SIGALRM, before)


def _sparse(path: Path, size: int = 2 << 30) -> Path:
    with path.open("wb") as f:
        f.truncate(size)  # 2 GB of zeros that take no disk
    return path


def _fifo(path: Path) -> Path:
    os.mkfifo(path)
    return path


def _dev_zero(path: Path) -> Path:
    path.symlink_to("/dev/zero")
    return path


def _mesh(filename: str):
    first = 'filename="package://example-robot-data/robots/ur_description/meshes/ur5/collision/base.stl"'
    assert first in UR5
    return lambda p: (p.write_text(UR5.replace(first, f'filename="{filename}"', 1)), p)[1]


def _linked_mesh(path: Path) -> Path:
    (path.parent / "meshes").mkdir()
    (path.parent / "meshes" / "base.stl").symlink_to("/etc/passwd")
    return _mesh("meshes/base.stl")(path)


URDFS = {  # attack -> (write the file at the path given, what the error says)
    "truncated": (lambda p: (p.write_text(UR5[: len(UR5) // 2]), p)[1], "not well-formed XML"),
    "malformed": (lambda p: (p.write_bytes(b"\x00\x01<robot"), p)[1], "not well-formed XML"),
    "not UTF-8": (
        lambda p: (p.write_bytes(UR5.encode().replace(b"ur5", b"ur\xe95")), p)[1],
        "not UTF-8",
    ),  # fmt: skip
    "entity bomb": (lambda p: (p.write_text(BOMB), p)[1], "DOCTYPE or entities"),
    "external entity": (lambda p: (p.write_text(XXE), p)[1], "DOCTYPE or entities"),
    "2 GB sparse": (_sparse, "at most 16777216 are read"),
    "FIFO": (_fifo, "is a FIFO"),
    "/dev/zero": (_dev_zero, "is a character device"),
    "mesh ../../etc/passwd": (_mesh("../../../../../../etc/passwd"), "not inside"),
    "mesh /etc/passwd": (_mesh("/etc/passwd"), "not inside"),
    "mesh file:///etc/passwd": (_mesh("file:///etc/passwd"), "not inside"),
    "mesh package:// climbing out": (_mesh("package://pkg/../../../../etc/passwd"), "not inside"),
    "mesh http://": (_mesh("http://example.com/base.stl"), "not inside"),
    "mesh link out of the folder": (_linked_mesh, "not inside"),
}


def _csv_text(rows: int = 5) -> str:
    cols = ["time"] + [f"{j}.{f}" for f in ("position", "effort") for j in JOINTS]
    lines = [",".join(cols)] + [",".join(["0.1"] * len(cols)) for _ in range(rows)]
    return "\n".join(lines) + "\n"


CSVS = {
    "truncated": (lambda p: (p.write_text(_csv_text()[:-9]), p)[1], "not a number"),
    "NUL in the header": (lambda p: (p.write_bytes(b"time,\x00x\n"), p)[1], "lacks the columns"),
    "a 500 kB header field": (
        lambda p: (p.write_text("time," + "x" * 500_000 + "\n"), p)[1],
        "no readable header",
    ),
    "not UTF-8": (lambda p: (p.write_bytes(b"time,caf\xe9\n1,2\n"), p)[1], "not UTF-8"),
    "endless first line": (
        lambda p: (p.write_bytes(b"x" * (2 << 20)), p)[1],
        "first line is longer",
    ),
    "2 GB sparse": (_sparse, "at most 1073741824 are read"),
    "FIFO": (_fifo, "is a FIFO"),
    "/dev/zero": (_dev_zero, "is a character device"),
}


def _bag(folder: Path) -> Path:
    log = JointLog(np.arange(4) * 0.1, JOINTS, np.zeros((4, 6)), np.ones((4, 6)))
    return write_bag(log, folder / "bag", "sqlite3")


def _metadata(edit):
    def make(p: Path) -> Path:
        bag = _bag(p.parent)
        meta = bag / "metadata.yaml"
        meta.write_text(edit(meta.read_text(), bag))
        return bag

    return make


def _storage_fifo(p: Path) -> Path:
    bag = _bag(p.parent)
    (db3,) = bag.glob("*.db3")
    db3.unlink()
    os.mkfifo(db3)
    return bag


def _truncated_db3(p: Path) -> Path:
    bag = _bag(p.parent)
    (db3,) = bag.glob("*.db3")
    db3.write_bytes(db3.read_bytes()[:700])
    return bag


def _sparse_metadata(p: Path) -> Path:
    bag = _bag(p.parent)
    (bag / "metadata.yaml").unlink()
    _sparse(bag / "metadata.yaml")
    return bag


def _compressed(text: str, bag: Path) -> str:
    return text.replace("compression_format: ''", "compression_format: zstd")


def _storage_climbs(text: str, bag: Path) -> str:
    return text.replace(next(bag.glob("*.db3")).name, "../../../../etc/passwd")


YAML_BOMB = "a: &a [x, x, x, x, x, x, x, x, x, x]\n" + "".join(
    f"{chr(98 + k)}: &{chr(98 + k)} [{', '.join(['*' + chr(97 + k)] * 10)}]\n" for k in range(9)
)
BAGS = {
    "truncated .db3": (_truncated_db3, "cannot read the bag"),
    "metadata not YAML": (_metadata(lambda t, b: "{{{ ]]"), "not a ROS 2 bag's metadata"),
    "metadata YAML bomb": (_metadata(lambda t, b: YAML_BOMB), "not a ROS 2 bag's metadata"),
    "metadata 2 GB sparse": (
        lambda p: (_sparse(_bag(p.parent) / "metadata.yaml"), p.parent / "bag")[1],
        "at most 16777216",
    ),  # fmt: skip
    "compressed": (
        _metadata(lambda t, b: t.replace("compression_format: ''", "compression_format: zstd")),
        "compressed",
    ),  # fmt: skip
    "storage ../../etc/passwd": (
        _metadata(lambda t, b: t.replace(next(b.glob("*.db3")).name, "../../../../etc/passwd")),
        "storage file not found",
    ),  # fmt: skip
    "storage file a FIFO": (_storage_fifo, "is a FIFO"),
    "bag a FIFO": (_fifo, "is a FIFO"),
    "bag /dev/zero": (_dev_zero, "is a character device"),
}


def _name(folder: Path, attack: str, suffix: str, non_utf8: bool) -> Path:
    stem = attack.replace("/", "_").replace(" ", "_").replace(":", "")
    return folder / (f"{stem}{NON_UTF8 if non_utf8 else ''}{suffix}")


def _cli(args: list[str]) -> subprocess.CompletedProcess:
    code = "import sys; from comgrasp_pin.cli import main; sys.exit(main(sys.argv[1:]))"
    return subprocess.run([sys.executable, "-c", code, *args], capture_output=True, text=True,
                          errors="replace", timeout=CLI_BOUND_S, check=False)  # fmt: skip


def _estimate(urdf: Path, log: list[str], out: Path) -> list[str]:
    return ["estimate", "--urdf", str(urdf), "--ee-frame", "eelink", *log, "--before", "0:0.1",
            "--after", "0.2:0.3", "--out", str(out)]  # fmt: skip


def _check_cli(result, message: str, out: Path) -> None:
    assert result.returncode == 2, result.stderr
    assert "Traceback" not in result.stderr and message in result.stderr, result.stderr
    assert not out.exists()


# --- URDF ---------------------------------------------------------------------------------


@pytest.mark.parametrize("attack", list(URDFS))
def test_hostile_urdf_is_refused_by_the_api(tmp_path, attack):
    make, message = URDFS[attack]
    (tmp_path / "robot").mkdir()
    path = make(_name(tmp_path / "robot", attack, ".urdf", non_utf8=attack == "FIFO"))
    for load in (RobotModel.from_urdf, load_robot):
        with pytest.raises(ComGraspError, match=message):
            load(path, "eelink")


@pytest.mark.parametrize("attack", ["entity bomb", "2 GB sparse", "FIFO", "mesh /etc/passwd"])
def test_hostile_urdf_exits_2_on_the_command_line(tmp_path, attack):
    make, message = URDFS[attack]
    (tmp_path / "robot").mkdir()
    path = make(_name(tmp_path / "robot", attack, ".urdf", non_utf8=True))
    (tmp_path / "log.csv").write_text(_csv_text())
    out = tmp_path / "result.json"
    _check_cli(_cli(_estimate(path, ["--csv", str(tmp_path / "log.csv")], out)), message, out)


def test_a_urdf_with_a_non_utf8_name_and_meshes_in_its_package_loads(tmp_path):
    path = tmp_path / f"robot{NON_UTF8}.urdf"
    path.write_text(UR5)
    assert RobotModel.from_urdf(path, "eelink").nq == 6
    assert load_robot(path, "eelink", package_dirs=[tmp_path]).nq == 6


# --- MJCF ---------------------------------------------------------------------------------

MJCF = """<mujoco><asset><mesh name="m" file="{file}"/></asset>
<worldbody><body><geom type="mesh" mesh="m"/></body></worldbody></mujoco>"""
CUBE_OBJ = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 1 2 4\nf 1 3 4\nf 2 3 4\n"


@pytest.mark.parametrize(
    ("attack", "text", "message"),
    [("truncated", MJCF.format(file="cube.obj")[:40], "not well-formed XML"),
     ("entity bomb", BOMB.replace("robot", "mujoco"), "DOCTYPE or entities"),
     ("mesh ../../etc/passwd", MJCF.format(file="../../../../../etc/passwd"), "not inside"),
     ("meshdir /etc", MJCF.format(file="passwd").replace("<asset>", '<compiler meshdir="/etc"/>'
                                                         "<asset>"), "not inside")],
)  # fmt: skip
def test_hostile_mjcf_is_refused(tmp_path, attack, text, message):
    path = tmp_path / "scene.xml"
    path.write_text(text)
    with pytest.raises(ComGraspError, match=message):
        load_mjcf(path)


def test_a_good_mjcf_loads_and_a_fifo_is_refused(tmp_path):
    (tmp_path / "cube.obj").write_text(CUBE_OBJ)
    (tmp_path / "scene.xml").write_text(MJCF.format(file="cube.obj"))
    assert load_mjcf(tmp_path / "scene.xml").nmesh == 1
    with pytest.raises(ComGraspError, match="is a FIFO"):
        load_mjcf(_fifo(tmp_path / "fifo.xml"))


# --- CSV logs -----------------------------------------------------------------------------


@pytest.mark.parametrize("attack", list(CSVS))
def test_hostile_csv_is_a_log_error(tmp_path, attack):
    make, message = CSVS[attack]
    path = make(_name(tmp_path, attack, ".csv", non_utf8=attack == "FIFO"))
    with pytest.raises(LogError, match=message):
        read_csv(path, JOINTS)


@pytest.mark.parametrize("attack", ["truncated", "2 GB sparse", "FIFO", "/dev/zero"])
def test_hostile_csv_exits_2_on_the_command_line(tmp_path, attack):
    make, message = CSVS[attack]
    path = make(_name(tmp_path, attack, ".csv", non_utf8=True))
    out = tmp_path / "result.json"
    _check_cli(_cli(_estimate(urdf_path("ur5_gripper.urdf"), ["--csv", str(path)], out)),
               message, out)  # fmt: skip


# --- bags ---------------------------------------------------------------------------------


@pytest.mark.parametrize("attack", list(BAGS))
def test_hostile_bag_is_a_log_error(tmp_path, attack):
    make, message = BAGS[attack]
    path = make(_name(tmp_path, attack, ".mcap", non_utf8=attack == "bag a FIFO"))
    with pytest.raises(LogError, match=message):
        read_bag(path, JOINTS)


@pytest.mark.parametrize("attack", ["storage file a FIFO", "compressed", "bag /dev/zero"])
def test_hostile_bag_exits_2_on_the_command_line(tmp_path, attack):
    make, message = BAGS[attack]
    path = make(_name(tmp_path, attack, ".mcap", non_utf8=False))
    out = tmp_path / "result.json"
    _check_cli(_cli(_estimate(urdf_path("ur5_gripper.urdf"), ["--bag", str(path)], out)),
               message, out)  # fmt: skip


# --- a run's settings and results, resumed ------------------------------------------------

SETTINGS = {
    "truncated": (lambda p: (p.write_text('{"seed": 0, "noi'), p)[1], "not JSON"),
    "nested past the parser": (
        lambda p: (p.write_text("[" * 200_000 + "]" * 200_000), p)[1],
        "nests too deep",
    ),  # fmt: skip
    "not UTF-8": (lambda p: (p.write_bytes(b'{"seed": "\xe9"}'), p)[1], "not UTF-8"),
    "2 GB sparse": (_sparse, "at most 16777216"),
    "FIFO": (_fifo, "is a FIFO"),
}


def _resumable(folder: Path) -> Path:
    from comgrasp_pin.experiments.runner import run_trials

    folder.mkdir(exist_ok=True)
    csv = folder / "accuracy.csv"
    run_trials(dict, [{"object": "obj1", "trial": 0, "method": "m"}], csv, ["object"],
               settings={"seed": 0})  # fmt: skip
    return csv


@pytest.mark.parametrize("attack", list(SETTINGS))
def test_hostile_settings_file_is_refused_on_resume(tmp_path, attack):
    from comgrasp_pin.experiments.runner import run_trials

    csv = _resumable(tmp_path)
    settings = csv.with_suffix(".settings.json")
    settings.unlink()
    SETTINGS[attack][0](settings)
    before = csv.read_bytes()
    with pytest.raises(ResumeError, match=SETTINGS[attack][1]):
        run_trials(dict, [{"object": "obj1", "trial": 1, "method": "m"}], csv, ["object"],
                   resume=True, settings={"seed": 0})  # fmt: skip
    assert csv.read_bytes() == before


def test_a_2gb_results_csv_is_refused_on_resume_and_on_the_command_line(tmp_path):
    from comgrasp_pin.experiments.runner import run_trials

    csv = _resumable(tmp_path / "run")
    _sparse(csv)
    with pytest.raises(ResumeError, match="at most 1073741824"):
        run_trials(dict, [{"object": "obj1", "trial": 1, "method": "m"}], csv, ["object"],
                   resume=True, settings={"seed": 0})  # fmt: skip
    settings = csv.with_suffix(".settings.json")
    settings.unlink()
    _fifo(settings)
    from comgrasp_pin.experiments.trials import ACCURACY_COLUMNS

    csv.write_text(",".join([*ACCURACY_COLUMNS, "error"]) + "\n")
    result = _cli(["accuracy", "--objects", "obj1", "--trials", "1", "--workers", "1",
                   "--out", str(tmp_path / "run"), "--resume"])  # fmt: skip
    assert result.returncode == 2 and "Traceback" not in result.stderr
    assert "is a FIFO" in result.stderr, result.stderr
    assert sorted(p.name for p in (tmp_path / "run").iterdir()) == [
        ".accuracy.csv.lock", "accuracy.csv", "accuracy.settings.json"]  # fmt: skip
