"""The package's imports point one way: no circle, and each part imports only the layers below.

Every ``.py`` under ``comgrasp_pin/`` is read with ``ast`` (nothing is imported). Every import
of a ``comgrasp_pin`` module counts: at module level, inside a function, under
``if TYPE_CHECKING:``, and ``__import__`` / ``importlib.import_module`` with a literal name.
An import hidden in a function still ties the two modules together, so it can close a circle
like any other. ``from comgrasp_pin.a import b`` is an edge to ``a.b`` when ``b`` is a module,
else to ``a``; importing ``a.b`` is not counted as importing the package ``a``'s
``__init__`` (which re-exports its modules, as every package's may).
"""

from __future__ import annotations

import ast
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / "comgrasp_pin"

LAYERS = [
    {"cli"},
    {"experiments"},
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
