"""The documentation site (mkdocs.yml at the top, pages in docs/): `mkdocs build --strict`
builds it without a single warning (a broken link or anchor, a page the nav leaves out, a
docstring griffe cannot parse), and the API pages document every name of their module's
``__all__``.

The docs tools are part of the ``test`` extra (CI installs ``.[test,ray,franka]``); locally
``pip install ".[docs]" && mkdocs serve`` serves the site.
"""

import importlib
import os
import re
import subprocess
import sys
import types
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
# module -> its page in the built site
API_PAGES = {
    "comgrasp_pin": "api/index.html",
    "comgrasp_pin.estimation": "api/estimation/index.html",
    "comgrasp_pin.perception": "api/perception/index.html",
    "comgrasp_pin.robot_io": "api/robot_io/index.html",
    "comgrasp_pin.planning": "api/planning/index.html",
}


@pytest.fixture(scope="module")
def site(tmp_path_factory) -> Path:
    """The site built by ``mkdocs build --strict`` into a temporary folder."""
    try:
        import mkdocs  # noqa: F401
    except ImportError:
        pytest.fail('mkdocs is not installed: pip install ".[test]" (or ".[docs]")')
    out = tmp_path_factory.mktemp("site")
    env = {**os.environ, "NO_MKDOCS_2_WARNING": "1"}  # Material's banner, not a build warning
    cmd = [sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir", str(out)]
    result = subprocess.run(cmd, cwd=ROOT, env=env, capture_output=True, text=True, timeout=300)
    log = result.stdout + result.stderr
    warnings = [line for line in log.splitlines() if re.match(r"\s*(WARNING|ERROR)\b", line)]
    assert result.returncode == 0 and not warnings, "mkdocs build --strict:\n" + (
        "\n".join(warnings) or log[-4000:]
    )
    return out


def _heading_ids(page: Path) -> set[str]:
    return set(re.findall(r'<h[1-6] id="([^"]+)"', page.read_text(encoding="utf-8")))


def test_every_docs_page_is_built(site):
    """Every Markdown page of docs/ outside the run outputs (docs/results/, of which only
    report.md is a page) is on the site."""
    pages = [p for p in DOCS.rglob("*.md") if p.relative_to(DOCS).parts[0] != "results"]
    pages.append(DOCS / "results" / "report.md")
    for page in pages:
        rel = page.relative_to(DOCS).with_suffix("")
        built = site / (rel.parent if rel.name == "index" else rel) / "index.html"
        assert built.is_file(), f"{page.relative_to(ROOT)} is not on the site"


def test_the_landing_page_shows_the_picture(site):
    html = (site / "index.html").read_text(encoding="utf-8")
    assert 'src="images/cameras.png"' in html
    assert (site / "images" / "cameras.png").is_file()


@pytest.mark.parametrize("module", sorted(API_PAGES))
def test_api_page_documents_the_public_names(site, module):
    """Each name of the module's ``__all__`` (or, without one, each public function and
    class of its submodules) has a heading of its own on the module's page."""
    mod = importlib.import_module(module)
    ids = _heading_ids(site / API_PAGES[module])
    names = getattr(mod, "__all__", None)
    if names is None:
        names = [
            f"{sub}.{name}"
            for sub in sorted(p.stem for p in Path(mod.__file__).parent.glob("[!_]*.py"))
            for name, obj in vars(importlib.import_module(f"{module}.{sub}")).items()
            if not name.startswith("_")
            and isinstance(obj, type | types.FunctionType)
            and obj.__module__ == f"{module}.{sub}"
        ]
    names = [n for n in names if not isinstance(getattr(mod, n, None), types.ModuleType)]
    assert names, f"{module}: nothing public to document"
    missing = [n for n in names if not any(i.endswith(f".{n}") for i in ids)]
    assert not missing, f"{API_PAGES[module]} lacks {missing}"
