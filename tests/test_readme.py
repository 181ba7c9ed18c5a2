"""The README: its "Use it on your robot" section runs (its python blocks, exec'd in order);
docs/experiments.md's tables agree with the code (the objects) and with docs/results (the
accuracy)."""

import csv
import inspect
import json
import re
from pathlib import Path

import numpy as np
import pytest

from comgrasp_pin._paths import sim_path
from comgrasp_pin.experiments.trials import ACCURACY_COM_RANGE
from comgrasp_pin.simulation.objects import OBJECTS, PAPER_OBJECTS, get_object
from comgrasp_pin.simulation.scene import Scene

README = Path(__file__).resolve().parents[1] / "README.md"
RESULTS = README.parent / "docs" / "results"
EXPERIMENTS = README.parent / "docs" / "experiments.md"
HEADING = "## Use it on your robot"


def _section_blocks() -> list[str]:
    text = README.read_text()
    start = text.index(HEADING)
    end = text.find("\n## ", start + len(HEADING))
    section = text[start : end if end > 0 else None]
    return re.findall(r"```python\n(.*?)```", section, flags=re.S)


def test_the_section_is_at_the_top():
    text = README.read_text()
    assert text.index(HEADING) < text.index("## The two commands")


def test_python_blocks_run(tmp_path, monkeypatch, capsys):
    blocks = _section_blocks()
    assert blocks
    monkeypatch.chdir(tmp_path)
    scope: dict = {"__name__": "readme"}
    for code in blocks:
        exec(compile(code, str(README), "exec"), scope)
    est = scope["est"]  # the front door's PayloadEstimate
    truth = np.r_[0.8, 0.02, -0.01, 0.05]
    assert np.all(np.abs(np.r_[est.mass, est.com_ee] - truth) < 4 * est.std)
    assert est.verdict == "identified" and est.at_rest.fit is not None
    assert (tmp_path / "payload.yaml").is_file() and (tmp_path / "log.csv").is_file()
    assert json.loads((tmp_path / "RESULT.json").read_text())["schema_version"] == 3
    assert "mass" in capsys.readouterr().out


def _table(heading: str, first_cell: str) -> list[list[str]]:
    """The Markdown table of docs/experiments.md under ``heading`` whose header row starts
    with ``first_cell``, as rows of stripped cells (header and separator dropped)."""
    text = EXPERIMENTS.read_text()
    start = text.index(heading)
    lines = text[start:].splitlines()
    top = next(i for i, line in enumerate(lines) if line.startswith(f"| {first_cell} |"))
    rows = []
    for line in lines[top + 2 :]:
        if not line.startswith("|"):
            break
        rows.append([c.strip() for c in line.strip().strip("|").split("|")])
    return rows


def _holds_level_mm(name: str) -> float:
    """From sim/tilt_calibration.json: the largest grasp-to-CoM distance (mm) the
    calibration tried below the first that tilted the rod by more than 1 deg, the lower side."""
    cal = json.loads(sim_path("tilt_calibration.json").read_text())["objects"][name]
    levers = []
    for side in ("+x", "-x"):
        ratio, tilt = np.array(cal[side]["lever_ratio"]), np.array(cal[side]["tilt_deg"])
        first = int(np.argmax(tilt > 1.0))
        assert first > 0 and tilt[first] > 1.0, (name, side)
        levers.append(ratio[first - 1] * cal["holding_lever_m"])
    return 1e3 * min(levers)


def test_the_objects_table_matches_the_code():
    rows = _table("## The objects", "object")
    assert [r[0].split()[0] for r in rows] == list(OBJECTS)
    com_regrasp = inspect.signature(Scene.sample).parameters["com_range"].default
    for cells in rows:
        name = cells[0].split()[0]
        o = get_object(name)
        assert ("(extra)" in cells[0]) == (not o.paper)
        assert cells[1] == o.description
        length, mass, handle_mm = float(cells[2]), float(cells[3]), float(cells[4])
        assert abs(length - o.length) <= 0.005 and abs(mass - o.mass) <= 0.005
        assert abs(handle_mm - 1e3 * o.thickness) <= 0.5
        for cell, (lo, hi) in ((cells[5], ACCURACY_COM_RANGE), (cells[6], com_regrasp)):
            shown = [float(v) for v in cell.split("–")]
            assert np.allclose(shown, [1e3 * lo * o.length, 1e3 * hi * o.length], atol=0.5)
        holds = _holds_level_mm(name)
        assert abs(float(cells[7]) - holds) <= 0.5, (name, holds)
        assert abs(float(cells[8]) - 100 * (1 - 5 * holds / (1e3 * o.length))) <= 0.5


@pytest.mark.parametrize(
    "heading, run",
    [("## Results at the paper's size, realistic sensors", "."),
     ("## The same with ideal sensors", "ideal")],
)  # fmt: skip
def test_the_accuracy_table_matches_docs_results(heading, run):
    """docs/experiments.md's per-bin numbers against docs/results[/ideal]/accuracy.csv,
    recomputed here."""
    rows = _table(heading, "tilt in the jaws, 0–90° from level")
    by_name = {r[0]: r[1:] for r in rows}
    with open(RESULTS / run / "accuracy.csv", newline="") as f:
        csv_rows = [r for r in csv.DictReader(f) if r["object"] in PAPER_OBJECTS]
    good = [r for r in csv_rows if not r["error"]]
    tilt = np.abs([float(r["theta_deg"]) for r in good])
    ours = 100 * np.array([float(r["accuracy"]) for r in good])
    line = 100 * np.array([float(r["accuracy_line"]) for r in good])
    edges = [0, 5, 10, 15, 20, 25, 30, 60, 90]
    for k, (lo, hi) in enumerate(zip(edges[:-1], edges[1:])):
        sel = (tilt >= lo) & (tilt < hi)
        assert int(by_name["grasps"][k]) == sel.sum()
        assert float(by_name["ours (%)"][k]) == pytest.approx(ours[sel].mean(), abs=0.05)
        assert float(by_name["paper's method, our world (%)"][k]) == pytest.approx(
            line[sel].mean(), abs=0.05
        )
        assert float(by_name["worst grasp, ours (%)"][k]) == pytest.approx(
            ours[sel].min(), abs=0.05
        )


def test_the_notebooks_extra_and_the_license_are_stated():
    tomllib = pytest.importorskip("tomllib", reason="Python >= 3.11 reads TOML")
    text = README.read_text()
    assert 'pip install ".[notebooks]" && jupyter lab notebooks/' in text
    pyproject = tomllib.loads((README.parent / "pyproject.toml").read_text())
    assert "notebooks" in pyproject["project"]["optional-dependencies"]
    assert pyproject["project"]["license"] == "BSD-3-Clause"  # SPDX (PEP 639)
    assert (README.parent / "LICENSE").read_text().startswith("BSD 3-Clause License")
    assert "BSD 3-Clause" in text.split("## License", 1)[1]
    assert "https://arxiv.org/abs/2205.01048" in text.split("## Citation", 1)[1]


def test_the_readme_is_short_and_every_link_resolves():
    import re

    text = README.read_text()
    assert len(text.splitlines()) <= 300
    links = re.findall(r"\]\(([^)\s]+)\)", text)
    assert links
    headings = {re.sub(r"[^a-z0-9 -]", "", h.lower()).strip().replace(" ", "-")
                for h in re.findall(r"^#+ (.+)$", text, flags=re.M)}  # fmt: skip
    for target in links:
        if target.startswith("#"):
            assert target[1:] in headings, f"README links to {target}, no such heading"
            continue
        if target.startswith(("http://", "https://", "mailto:")):
            continue
        path = (README.parent / target.split("#")[0]).resolve()
        assert path.exists(), f"README links to {target}, which is not in the repository"


REALDATA = Path(__file__).resolve().parents[2] / "shared" / "realdata"
UR_FILES = {"ur10e.urdf": "ur10e.urdf", "loaded.csv": "excitation_loaded_2805g.csv",
            "empty.csv": "excitation_empty.csv"}  # fmt: skip


@pytest.mark.skipif(not (REALDATA / "ur10e_rtde").is_dir(),
                    reason=f"the real UR10e recording is not in {REALDATA}")  # fmt: skip
def test_the_ur_commands_run_as_written_on_the_real_recording(tmp_path, monkeypatch, capsys):
    """The README's UR block, command by command, on the real files it names (issue 32)."""
    import shlex

    from comgrasp_pin.cli import main

    text = README.read_text()
    start = text.index("**An arm that logs motor currents")
    block = re.search(r"```bash\n(.*?)```", text[start:], flags=re.S).group(1)
    commands = [shlex.split(c) for c in block.replace("\\\n", " ").splitlines() if c.strip()]
    assert [c[1] for c in commands] == ["calibrate-gains", "identify-arm", "estimate"]
    for name, real in UR_FILES.items():  # the README's names, the real files
        (tmp_path / name).symlink_to(REALDATA / "ur10e_rtde" / real)
    monkeypatch.chdir(tmp_path)
    for argv in commands:
        assert argv[0] == "comgrasp"
        assert main(argv[1:]) == 0, argv
    out = capsys.readouterr().out
    assert "VERDICT:" in out
    result = json.loads((tmp_path / "RESULT.json").read_text())
    lo, hi = result["interval95_mass_kg"]
    assert lo < 2.805 < hi  # the gains were weighed with this load: it must hold it
    assert (tmp_path / "fit.png").stat().st_size > 0
    assert "set_target_payload" in (tmp_path / "payload.script").read_text()


@pytest.mark.skipif(not (REALDATA / "rgbd" / "overhead_primesense_flashlight").is_dir(),
                    reason=f"the real PrimeSense frame is not in {REALDATA}")  # fmt: skip
def test_the_views_command_runs_as_written_on_the_real_frame(tmp_path, monkeypatch):
    """The README's depth-only `comgrasp views` on the real flashlight frame it names: it
    measures the length the README states (0.206 m) and writes the view and the JSON."""
    import shlex

    from comgrasp_pin.cli import main

    text = README.read_text()
    start = text.index("**Perception on your own camera's frames.**")
    block = re.search(r"```bash\n(.*?)```", text[start:], flags=re.S).group(1)
    argv = shlex.split(block.strip())
    assert argv[:2] == ["comgrasp", "views"] and "--rgb" not in argv
    folder = REALDATA / "rgbd" / "overhead_primesense_flashlight"
    for name in ("depth_0_mm.png", "primesense_camera_info.yaml"):
        (tmp_path / name).symlink_to(folder / name)
    monkeypatch.chdir(tmp_path)
    assert main(argv[1:]) == 0
    measured = json.loads((tmp_path / "views" / "depth_0_mm_top_view.json").read_text())
    stated = float(re.search(r"measures the flashlight at (\d\.\d+) m", text).group(1))
    assert abs(measured["length_m"] - stated) < 0.0005
    assert (tmp_path / "views" / "depth_0_mm_top_view.png").stat().st_size > 0
