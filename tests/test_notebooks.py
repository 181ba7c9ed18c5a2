"""The notebooks: committed with their figures, and re-executing them at their small size
(COMGRASP_QUICK=1) reproduces what is committed.

"Reproduces" means, cell by cell: no errors; the same number of PNG figures; the same text
outputs (printouts, Markdown tables) word for word once the numbers are taken out, and every
number within two units of its last printed digit plus 1 % of its value. That allows for the
last digit of a rounding and for a simulation that runs a hair differently on another CPU,
and still catches a changed table, a lost figure, a cell that prints something else, or an
estimate that moved. Timings and paths are not printed by the notebooks, so nothing else is
excluded.
"""

import os
import re
from pathlib import Path

import pytest

NOTEBOOKS = sorted((Path(__file__).parent.parent / "notebooks").glob("*.ipynb"))
PLOTS = re.compile(r"\bplt\.(figure|subplots)\(")
NUMBER = re.compile(r"[-+−]?\d+(?:\.\d+)?(?:e[-+]?\d+)?")
MAX_NOTEBOOK_BYTES = 300_000  # figures at 80 dpi, cropped renders: the repository stays small


def _code_cells(notebook) -> list:
    return [cell for cell in notebook.cells if cell.cell_type == "code"]


def _pngs(cell) -> int:
    return sum("image/png" in out.get("data", {}) for out in cell.get("outputs", []))


def _text(cell) -> str:
    """The cell's printed and displayed text (a figure's own text/plain repr left out)."""
    parts = []
    for out in cell.get("outputs", []):
        if out.get("output_type") == "stream":
            parts.append(out["text"])
        data = out.get("data", {})
        if "text/markdown" in data:
            parts.append(data["text/markdown"])
        elif "text/plain" in data and "image/png" not in data:
            parts.append(data["text/plain"])
    return "\n".join(parts)


def _numbers_agree(committed: str, fresh: str) -> bool:
    value, new = float(committed.replace("−", "-")), float(fresh.replace("−", "-"))
    decimals = len(committed.split(".")[1].split("e")[0]) if "." in committed else 0
    return abs(value - new) <= 2 * 10.0**-decimals + 0.01 * abs(value)


def test_there_are_notebooks():
    assert len(NOTEBOOKS) >= 5, NOTEBOOKS


@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.stem for p in NOTEBOOKS])
def test_the_committed_notebook_has_its_figures(path):
    nbformat = pytest.importorskip("nbformat")
    assert path.stat().st_size < MAX_NOTEBOOK_BYTES
    cells = _code_cells(nbformat.read(path, as_version=4))
    for k, cell in enumerate(cells):
        assert cell.execution_count is not None, f"code cell {k} was never run"
        assert not any(out.get("output_type") == "error" for out in cell.outputs), k
        if PLOTS.search(cell.source):
            assert _pngs(cell) >= 1, f"code cell {k} plots but has no figure"
    assert sum(_pngs(cell) for cell in cells) >= 1


def test_numbers_agree_within_their_last_digit():
    assert _numbers_agree("97.4", "97.5") and not _numbers_agree("97.4", "99.5")
    assert _numbers_agree("0", "1") and not _numbers_agree("1", "4")
    assert _numbers_agree("1.0e-3", "1.1e-3")


@pytest.mark.slow
@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.stem for p in NOTEBOOKS])
def test_the_notebook_reproduces_its_committed_outputs(path, tmp_path, monkeypatch):
    nbformat = pytest.importorskip("nbformat")
    nbclient = pytest.importorskip("nbclient")
    monkeypatch.setenv("COMGRASP_QUICK", "1")
    monkeypatch.setenv("COMGRASP_OUT", str(tmp_path))
    # the committed runs the notebooks analyse (CI installs the package, not in place)
    monkeypatch.setenv("COMGRASP_RESULTS", str(Path(__file__).parents[1] / "docs" / "results"))
    monkeypatch.setenv("MUJOCO_GL", os.environ.get("MUJOCO_GL", "egl"))
    committed = nbformat.read(path, as_version=4)
    fresh = nbformat.read(path, as_version=4)
    client = nbclient.NotebookClient(
        fresh, timeout=600, kernel_name="python3", resources={"metadata": {"path": str(tmp_path)}}
    )
    client.execute()
    for k, (old, new) in enumerate(zip(_code_cells(committed), _code_cells(fresh))):
        errors = [out for out in new.outputs if out.get("output_type") == "error"]
        assert not errors, (k, errors)
        assert _pngs(new) == _pngs(old), (
            f"code cell {k}: {_pngs(new)} figures, {_pngs(old)} committed"
        )
        old_text, new_text = _text(old), _text(new)
        assert NUMBER.sub("#", new_text) == NUMBER.sub("#", old_text), f"code cell {k}"
        for a, b in zip(NUMBER.findall(old_text), NUMBER.findall(new_text)):
            assert _numbers_agree(a, b), f"code cell {k}: {b}, committed {a}"
