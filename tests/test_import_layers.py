"""The package's imports point one way: no circle, and each part imports only the layers below;
and the robot side stands alone: its commands load no simulator, camera or plotting library.

Every ``.py`` under ``comgrasp_pin/`` is read with ``ast`` (nothing is imported). Every import
of a ``comgrasp_pin`` module counts: at module level, inside a function, under
``if TYPE_CHECKING:``, and ``__import__`` / ``importlib.import_module`` with a literal name.
An import hidden in a function still ties the two modules together, so it can close a circle
like any other. ``from comgrasp_pin.a import b`` is an edge to ``a.b`` when ``b`` is a module,
else to ``a``; importing ``a.b`` is not counted as importing the package ``a``'s
``__init__`` (which re-exports its modules, as every package's may).

The robot side is checked by running it: each real-arm command (``estimate`` static and
``--dynamic``, ``plan-poses``, ``plan-motion``, ``identify-arm``, ``calibrate-gains``, and
``--help``) runs in a fresh Python on small logs made here, and afterwards none of MuJoCo,
OpenCV (cv2) and matplotlib is in its ``sys.modules`` (``--plot`` alone may load matplotlib).
"""

from __future__ import annotations

import argparse
import ast
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "comgrasp_pin"

LAYERS = [
    {"cli"},
    {"experiments", "live"},
    {"simulation", "__init__"},
    {"procedures", "robot_io"},
    {"planning"},
    {"perception", "motion"},
    {"estimation"},
    {
        "robot",
        "camera",
        "geometry",
        "workcell",
        "config",
        "validate",
        "file_checks",
        "_paths",
        "errors",
    },  # fmt: skip
]
"""Top to bottom, as docs/design.md draws them: a part imports only parts in lower layers
(``__init__`` is the package's public API, re-exported). The bottom layer's modules import
one another (``geometry`` checks with ``validate``), without a circle."""


def _module_name(path: Path) -> str:
    parts = list(path.relative_to(PACKAGE.parent).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


MODULES = {_module_name(p): p for p in sorted(PACKAGE.rglob("*.py"))}


def _existing(name: str) -> str:
    """``name``, or the closest package or module above it that exists."""
    while name not in MODULES:
        name = name.rpartition(".")[0]
    return name


def _imports(module: str) -> set[str]:
    """The package modules that ``module``'s source imports, anywhere in it."""
    path = MODULES[module]
    names = set()
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            names |= {alias.name for alias in node.names}
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:  # relative: from the module's own package upwards
                parent = module if path.name == "__init__.py" else module.rpartition(".")[0]
                for _ in range(node.level - 1):
                    parent = parent.rpartition(".")[0]
                base = f"{parent}.{base}".rstrip(".")
            for alias in node.names:  # a module by its name, else the one that holds the name
                names.add(f"{base}.{alias.name}" if f"{base}.{alias.name}" in MODULES else base)
        elif isinstance(node, ast.Call) and node.args:
            func = node.func
            called = func.id if isinstance(func, ast.Name) else getattr(func, "attr", "")
            first = node.args[0]
            if called in ("__import__", "import_module") and isinstance(first, ast.Constant):
                names.add(str(first.value))
    ours = {n for n in names if n == "comgrasp_pin" or n.startswith("comgrasp_pin.")}
    return {_existing(n) for n in ours} - {module}


def import_graph() -> dict[str, set[str]]:
    """Each package module and the package modules it imports."""
    return {module: _imports(module) for module in MODULES}


def circles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected groups of more than one module (Tarjan), each sorted."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    found = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        for w in sorted(graph[v]):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            group = []
            while not group or group[-1] != v:
                group.append(stack.pop())
            if len(group) > 1:
                found.append(sorted(group))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return found


def _part(module: str) -> str:
    """The top-level part a module belongs to: ``simulation``, ``errors``, ``__init__``."""
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else "__init__"


def test_the_reader_sees_every_kind_of_import():
    graph = import_graph()
    assert "comgrasp_pin.cli.experiments" in graph["comgrasp_pin.cli.sweep"]  # module level
    assert "comgrasp_pin.simulation.checks" in graph["comgrasp_pin.cli.world"]  # in a function
    assert "comgrasp_pin.cli.args" in graph["comgrasp_pin.cli.camera_files"]  # from cli import
    assert "comgrasp_pin.config.tree" in graph["comgrasp_pin.config"]  # a package's __init__


def test_no_import_circle():
    found = circles(import_graph())
    assert not found, "import circles (each a group of modules that import one another):\n" + (
        "\n".join(" <-> ".join(group) for group in found)
    )


def test_each_part_imports_only_the_layers_below():
    layer = {part: i for i, parts in enumerate(LAYERS) for part in parts}
    bottom = len(LAYERS) - 1
    wrong = []
    for module, imported in import_graph().items():
        for other in imported:
            a, b = _part(module), _part(other)
            if a != b and not (layer[a] < layer[b] or layer[a] == layer[b] == bottom):
                wrong.append(f"{module} -> {other}")
    assert not wrong, "imports against the layers (docs/design.md):\n" + "\n".join(wrong)


def test_every_part_has_a_layer():
    assert {_part(m) for m in MODULES} == set().union(*LAYERS)


# --- the robot side stands alone: its commands run without the simulation's libraries -------

SIMULATION_LIBRARIES = ("mujoco", "cv2", "matplotlib")
SIMULATION_PARTS = tuple(
    f"comgrasp_pin.{part}" for part in ("simulation", "experiments", "perception", "procedures")
)
"""The package's simulated world and what runs in it: the real-arm commands load none."""
_RUN = """
import json, sys
from comgrasp_pin.cli import main
try:
    code = main(json.loads(sys.argv[1]))
except SystemExit as exc:  # --help
    code = exc.code
loaded = [m for m in json.loads(sys.argv[2]) if m in sys.modules]
print(json.dumps({"code": code, "loaded": loaded}), file=sys.stderr)
"""


def _run_alone(argv: list[str]) -> list[str]:
    """Which of SIMULATION_LIBRARIES and SIMULATION_PARTS ``comgrasp argv`` has loaded when
    it ends, run in a fresh Python (it must succeed)."""
    watched = [*SIMULATION_LIBRARIES, *SIMULATION_PARTS]
    res = subprocess.run(
        [sys.executable, "-c", _RUN, json.dumps(argv), json.dumps(watched)],
        capture_output=True, text=True, timeout=300, cwd=PACKAGE.parent,
    )  # fmt: skip
    assert res.returncode == 0, res.stderr
    last = json.loads(res.stderr.strip().splitlines()[-1])
    assert last["code"] == 0, res.stderr
    return last["loaded"]


def _motion_csv(robot, q0: np.ndarray, mass: float, path: Path) -> str:
    """A 10 s motion about ``q0`` at 200 Hz, its efforts Pinocchio's RNEA with a payload of
    ``mass`` (kg) at the ee frame, plus friction and noise, as a CSV."""
    import pinocchio as pin

    from comgrasp_pin.robot_io import JointLog, write_csv

    t = np.arange(0.0, 10.0, 1 / 200)
    waves = np.sin(np.outer(2 * np.pi * t / 5, [1, 2, 3, 1, 2, 3]) + np.arange(6))
    q = q0 + 0.5 * np.sin(np.pi * t / 10)[:, None] ** 2 * waves
    qd = np.gradient(q, t, axis=0)
    qdd = np.gradient(qd, t, axis=0)
    model = pin.Model(robot.model)
    frame = model.frames[robot.ee_frame_id]
    body = pin.Inertia(mass, np.array([0.02, -0.01, 0.08]), np.diag([4e-3, 5e-3, 1e-3]))
    model.appendBodyToJoint(frame.parentJoint, body, frame.placement)
    data = model.createData()
    tau = np.array([pin.rnea(model, data, *row) for row in zip(q, qd, qdd, strict=True)])
    noise = np.random.default_rng(int(10 * mass)).standard_normal(tau.shape)
    tau += 0.2 * np.tanh(qd / 0.01) + 0.02 * noise
    return str(write_csv(JointLog(t, tuple(robot.joint_names), q, tau), path))


@pytest.fixture(scope="module")
def robot_logs(tmp_path_factory):
    """The project's UR5 (URDF, ee frame), and logs made with Pinocchio (no MuJoCo): a
    static session at three poses empty then loaded (CSV and bag, its windows), and one
    motion played empty and loaded (CSVs)."""
    from _logs import rnea_torques, session

    from comgrasp_pin._paths import urdf_path
    from comgrasp_pin.robot_io import load_robot, write_bag, write_csv

    folder = tmp_path_factory.mktemp("robot_logs")
    urdf = str(urdf_path("ur5_gripper.urdf"))
    robot = load_robot(urdf, "eelink")
    Q = np.array([[0.0, -1.6, 1.6, -1.57, -1.57, 0.0], [0.4, -1.2, 1.2, -0.4, 0.8, 1.0],
                  [-0.5, -1.9, 1.5, -2.5, -0.6, -1.2]])  # fmt: skip
    torques = rnea_torques(robot, 0.6, np.array([0.03, 0.0, 0.04]))
    log, before, after, grasp = session(Q, torques, robot.joint_names, seed=3)
    return {
        "folder": folder, "robot": ["--urdf", urdf, "--ee-frame", "eelink"],
        "csv": str(write_csv(log, folder / "static.csv")),
        "bag": str(write_bag(log, folder / "static_bag")),
        "windows": ["--before", ",".join(f"{a}:{b}" for a, b in before),
                    "--after", ",".join(f"{a}:{b}" for a, b in after)],
        "grasp_time": str(grasp),
        "empty": _motion_csv(robot, Q[0], 0.0, folder / "empty.csv"),
        "loaded": _motion_csv(robot, Q[0], 0.8, folder / "loaded.csv"),
    }  # fmt: skip


ARM_RUNS = {
    "estimate --help": lambda L: ["estimate", "--help"],
    "estimate, CSV, payload files": lambda L: [
        "estimate", *L["robot"], "--csv", L["csv"], *L["windows"],
        "--out", str(L["folder"] / "R1.json"), "--export-ur", str(L["folder"] / "p.script"),
        "--export-franka", str(L["folder"] / "p.json"),
        "--export-ros2", str(L["folder"] / "p.yaml"),
    ],
    "estimate, bag, --auto": lambda L: [
        "estimate", *L["robot"], "--bag", L["bag"], "--auto", "--grasp-time", L["grasp_time"],
        "--out", str(L["folder"] / "R2.json"),
    ],
    "estimate --dynamic": lambda L: [
        "estimate", "--dynamic", *L["robot"], "--csv", L["loaded"], "--empty-csv", L["empty"],
        "--out", str(L["folder"] / "R3.json"), "--export-franka", str(L["folder"] / "d.json"),
    ],
    "identify-arm": lambda L: [
        "identify-arm", *L["robot"], "--csv", L["empty"], "--out", str(L["folder"] / "ARM.json"),
    ],
    "calibrate-gains": lambda L: [
        "calibrate-gains", *L["robot"], "--csv", L["loaded"], "--empty-csv", L["empty"],
        "--known-mass", "0.8", "--out", str(L["folder"] / "GAINS.json"),
    ],
    "plan-poses": lambda L: [
        "plan-poses", *L["robot"], "--k", "2", "--candidates", "200",
        "--out", str(L["folder"] / "poses.json"), "--urscript", str(L["folder"] / "p.urscript"),
    ],
    "plan-motion": lambda L: [
        "plan-motion", *L["robot"], "--duration", "4", "--candidates", "20", "--starts", "1",
        "--iterations", "2", "--out", str(L["folder"] / "motion.json"),
        "--urscript", str(L["folder"] / "m.script"), "--ros2", str(L["folder"] / "m.yaml"),
    ],
}  # fmt: skip


@pytest.mark.parametrize("name", ARM_RUNS)
def test_robot_commands_load_no_simulator_camera_or_plot_library(robot_logs, name):
    """Not MuJoCo, cv2, matplotlib, nor the package's simulation, experiments, perception or
    procedures."""
    loaded = _run_alone(ARM_RUNS[name](robot_logs))
    assert loaded == [], f"comgrasp {name} loaded {loaded}"


def test_the_dynamic_estimates_plot_alone_loads_matplotlib(robot_logs):
    """--plot draws with matplotlib, and the check above would see it."""
    L = robot_logs
    loaded = _run_alone(["estimate", "--dynamic", *L["robot"], "--csv", L["loaded"],
                            "--empty-csv", L["empty"], "--out", str(L["folder"] / "R4.json"),
                            "--plot", str(L["folder"] / "fit.png")])  # fmt: skip
    assert loaded == ["matplotlib"]


def test_the_robot_sides_modules_load_no_simulator_camera_or_plot_library():
    """The package's face and the parts below the simulation that a real arm uses: the
    bottom layer's file checks (MuJoCo's loader lives in simulation.mjcf_files), robot_io,
    estimation, motion, planning, the command line's parser."""
    parts = ["", ".file_checks", ".robot_io", ".estimation", ".motion.ik", ".motion.fourier",
             ".motion.trajectory", ".planning", ".cli"]  # fmt: skip
    modules = [f"comgrasp_pin{part}" for part in parts]
    code = (
        f"import importlib, json, sys\nfor m in {modules!r}: importlib.import_module(m)\n"
        "import comgrasp_pin.cli as cli\ncli.build_parser()\n"
        f"print(json.dumps([m for m in {SIMULATION_LIBRARIES!r} if m in sys.modules]))"
    )
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         timeout=120, cwd=PACKAGE.parent)  # fmt: skip
    assert res.returncode == 0, res.stderr
    assert json.loads(res.stdout.splitlines()[-1]) == []


def test_the_robot_only_parser_has_the_robot_commands():
    """``main`` builds only the real-arm part of the parser for ROBOT_COMMANDS: they are the
    commands ``robot`` and ``arm`` register, and the full parser has them too."""
    from comgrasp_pin.cli import ROBOT_COMMANDS, build_parser

    def commands(parser):
        (sub,) = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
        return list(sub.choices)

    assert commands(build_parser(robot_only=True)) == list(ROBOT_COMMANDS)
    assert commands(build_parser())[-len(ROBOT_COMMANDS) :] == list(ROBOT_COMMANDS)


def test_a_top_option_before_a_robot_command_sees_every_command(capsys):
    from comgrasp_pin.cli import main

    with pytest.raises(SystemExit):
        main(["-h", "estimate"])
    assert "reproduce" in capsys.readouterr().out


def test_the_parsers_rods_are_the_simulations():
    """``cli.args.OBJECTS`` reads sim/objects.json itself (no MuJoCo): the same names, order."""
    from comgrasp_pin.cli.args import OBJECTS
    from comgrasp_pin.simulation.objects import OBJECTS as SIMULATED

    assert OBJECTS == tuple(SIMULATED)
