"""The repository's static checks, run by the test command.

- ``ruff check`` over the whole repository, including the docstring rules (D, Google
  convention) on the package's public API (configured in pyproject.toml);
- ``mypy`` on comgrasp_pin/estimation, perception, planning and robot_io
  ([tool.mypy]).

Both tools come with the ``test`` extra; a test is skipped only if its tool is missing.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
TYPED = [
    "comgrasp_pin/estimation",
    "comgrasp_pin/perception",
    "comgrasp_pin/planning",
    "comgrasp_pin/robot_io",
]
TIMEOUT_S = 600


def _run(tool: str, *args: str) -> subprocess.CompletedProcess[str]:
    pytest.importorskip(tool, reason=f"{tool} is not installed (pip install '.[test]')")
    return subprocess.run(
        [sys.executable, "-m", tool, *args],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=TIMEOUT_S,
        check=False,
    )


def _report(result: subprocess.CompletedProcess[str]) -> str:
    return (
        f"`python {' '.join(result.args[1:])}` exited with {result.returncode}:\n"
        f"{result.stdout}\n{result.stderr}"
    )


def test_ruff_check_passes():
    result = _run("ruff", "check", str(ROOT))
    assert result.returncode == 0, _report(result)


def test_mypy_passes_on_the_typed_packages():
    result = _run("mypy", *TYPED)
    assert result.returncode == 0, _report(result)
