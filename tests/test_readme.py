"""The README's "Use it on your robot" section runs: its python blocks, exec'd in order."""

import re
from pathlib import Path

import numpy as np

README = Path(__file__).resolve().parents[1] / "README.md"
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
    est, result = scope["est"], scope["result"]
    truth = np.r_[0.8, 0.02, -0.01, 0.05]
    for e in (est, result.estimate):
        assert np.all(np.abs(np.r_[e.mass, e.com_ee] - truth) < 4 * e.std)
    assert (tmp_path / "payload.yaml").is_file() and (tmp_path / "log.csv").is_file()
    assert "mass" in capsys.readouterr().out
