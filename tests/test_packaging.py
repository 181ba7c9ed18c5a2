"""Packaging: pyproject.toml lists the packages by hand (urdf/ and sim/ sit at the top of the
repository and are mapped into the wheel as ``comgrasp_pin.urdf`` and ``comgrasp_pin.sim``),
so these tests check the list against the source tree, that the robot and scene descriptions
exist once, and (slow) that a built wheel carries them byte for byte.

The wheel is built from a copy of the repository's files (tracked and untracked, not ignored)
in pytest's tmp_path: setuptools writes ``build/`` and ``*.egg-info`` beside the sources, and
a stale ``build/lib`` in the checkout would both litter it and carry removed files into the
next wheel. ``--no-build-isolation`` is used when the running interpreter has what
pyproject's ``[build-system] requires`` asks for (setuptools >= 68 and wheel); otherwise (a
fresh venv ships an older setuptools and no wheel) pip builds in an isolated environment,
fetching those two from its configured index, as ``pip install .`` in CI does.
"""

import email
import email.message
import re
import shutil
import subprocess
import sys
import zipfile
from fnmatch import fnmatch
from importlib import metadata
from pathlib import Path

import pytest

if sys.version_info >= (3, 11):
    import tomllib
else:  # Python 3.10, which the project declares: tomli, the same parser (the test extra)
    import tomli as tomllib

ROOT = Path(__file__).resolve().parents[1]
PYPROJECT = tomllib.loads((ROOT / "pyproject.toml").read_text())
SETUPTOOLS = PYPROJECT["tool"]["setuptools"]
DATA = {"comgrasp_pin.urdf": "urdf", "comgrasp_pin.sim": "sim"}
URDF, SCENE = "urdf/ur5_gripper.urdf", "sim/scene.xml"


def _repo_files() -> list[str]:
    """Files of the repository: tracked, and untracked but not ignored (a file about to be
    committed counts), that exist in the work tree."""
    out = subprocess.run(
        ["git", "ls-files", "--cached", "--others", "--exclude-standard", "-z"],
        cwd=ROOT,
        check=True,
        capture_output=True,
        text=True,
    ).stdout
    return sorted({f for f in out.split("\0") if f and (ROOT / f).is_file()})


def _source_packages() -> set[str]:
    """Dotted names of every folder under comgrasp_pin/ (itself included) with an
    ``__init__.py``."""
    return {
        ".".join(init.parent.relative_to(ROOT).parts)
        for init in (ROOT / "comgrasp_pin").rglob("__init__.py")
        if "__pycache__" not in init.parts
    }


def test_every_subpackage_is_listed():
    missing = _source_packages() - set(SETUPTOOLS["packages"])
    assert not missing, f"add to [tool.setuptools] packages in pyproject.toml: {sorted(missing)}"


def test_every_listed_package_exists():
    packages = set(SETUPTOOLS["packages"])
    assert len(packages) == len(SETUPTOOLS["packages"]), "a package is listed twice"
    mapped = set(SETUPTOOLS["package-dir"])
    for name in packages - mapped:
        assert (ROOT.joinpath(*name.split(".")) / "__init__.py").is_file(), name
    for name in packages & mapped:
        assert (ROOT / SETUPTOOLS["package-dir"][name]).is_dir(), name


def test_data_packages_map_to_the_top_level_folders():
    assert SETUPTOOLS["package-dir"] == DATA
    assert set(DATA) <= set(SETUPTOOLS["packages"])


@pytest.mark.parametrize(("package", "folder"), sorted(DATA.items()))
def test_package_data_globs_match_every_file_of_the_folder(package, folder):
    globs = PYPROJECT["tool"]["setuptools"]["package-data"][package]
    files = [
        Path(f).relative_to(folder).as_posix() for f in _repo_files() if f.startswith(folder + "/")
    ]
    assert files, f"{folder}/ is empty"
    unmatched = [f for f in files if not any(fnmatch(f, g) and "/" not in f for g in globs)]
    assert not unmatched, f"{folder}/ files no package-data glob of {package} carries: {unmatched}"


def test_the_descriptions_exist_once():
    """No second URDF or scene anywhere in the repository, by name or by content."""
    files = _repo_files()
    assert URDF in files and SCENE in files
    by_name = [f for f in files if f.endswith(".urdf") or fnmatch(Path(f).name, "scene*.xml")]
    assert sorted(by_name) == sorted([URDF, SCENE]), by_name
    originals = {(ROOT / URDF).read_bytes(), (ROOT / SCENE).read_bytes()}
    copies = [f for f in files if f not in (URDF, SCENE) and (ROOT / f).read_bytes() in originals]
    assert not copies, copies


def test_no_data_folder_inside_the_package_shadows_the_top_level_one():
    """comgrasp_pin/_paths.py looks beside the package first (an installed wheel's layout):
    a comgrasp_pin/urdf or comgrasp_pin/sim in a checkout would win over urdf/ and sim/."""
    for folder in DATA.values():
        assert not (ROOT / "comgrasp_pin" / folder).exists(), f"comgrasp_pin/{folder}"


# --- the wheel (slow) ----------------------------------------------------------------------------


def _version_tuple(version: str) -> tuple[int, ...]:
    return tuple(int(part) for part in re.findall(r"\d+", version)[:3])


def _build_requirements_installed() -> bool:
    """Whether the running interpreter has pyproject's ``[build-system] requires``:
    setuptools at the version it asks for (``setuptools>=X``) and wheel."""
    (wanted,) = [r for r in PYPROJECT["build-system"]["requires"] if r.startswith("setuptools")]
    try:
        installed = metadata.version("setuptools")
        metadata.version("wheel")
    except metadata.PackageNotFoundError:
        return False
    return _version_tuple(installed) >= _version_tuple(wanted.split(">=")[1])


@pytest.fixture(scope="module")
def wheel(tmp_path_factory):
    """The wheel pip builds from a copy of the repository, opened."""
    src, out = tmp_path_factory.mktemp("src"), tmp_path_factory.mktemp("wheel")
    for f in _repo_files():
        (src / f).parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(ROOT / f, src / f)
    flags = ["--no-build-isolation"] if _build_requirements_installed() else []
    cmd = [sys.executable, "-m", "pip", "wheel", "--no-deps", *flags, "-w", str(out), str(src)]
    result = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stdout[-3000:] + result.stderr[-3000:]
    (path,) = out.glob("comgrasp_pin-*.whl")
    with zipfile.ZipFile(path) as zf:
        yield zf


def _wheel_metadata(wheel: zipfile.ZipFile) -> email.message.Message:
    (name,) = [n for n in wheel.namelist() if re.fullmatch(r"[^/]+\.dist-info/METADATA", n)]
    return email.message_from_bytes(wheel.read(name))


@pytest.mark.slow
@pytest.mark.parametrize("name", [URDF, SCENE])
def test_wheel_carries_the_description_byte_identical(wheel, name):
    inside = f"comgrasp_pin/{name}"
    assert inside in wheel.namelist()
    assert wheel.read(inside) == (ROOT / name).read_bytes()


@pytest.mark.slow
def test_wheel_carries_every_module(wheel):
    modules = {f for f in _repo_files() if f.startswith("comgrasp_pin/") and f.endswith(".py")}
    missing = modules - set(wheel.namelist())
    assert not missing, sorted(missing)


def test_the_notebooks_find_the_committed_results(monkeypatch, tmp_path):
    """results_dir: COMGRASP_RESULTS when set; from the repository's notebooks/ folder
    otherwise, installed in place or not (CI installs the package into site-packages)."""
    from comgrasp_pin._paths import results_dir

    repo = Path(__file__).resolve().parents[1]
    monkeypatch.setenv("COMGRASP_RESULTS", str(tmp_path))
    assert results_dir() == tmp_path
    monkeypatch.delenv("COMGRASP_RESULTS")
    monkeypatch.chdir(repo / "notebooks")
    assert results_dir().resolve() == (repo / "docs" / "results").resolve()


# --- the metadata a package index shows ----------------------------------------------------------

VERSION = "0.3.0"  # the release this tree is (CHANGELOG.md)
URLS = {"Homepage", "Documentation", "Repository", "Issues", "Changelog"}
PYTHONS = ("3.10", "3.11", "3.12")


def _check_metadata(meta) -> None:
    """The fields an index shows, in a distribution's METADATA (an email.message.Message or
    importlib.metadata's PackageMetadata)."""
    assert meta["Name"] == "comgrasp_pin"
    assert meta["Version"] == VERSION
    assert meta["Requires-Python"] == ">=3.10"
    assert meta["Summary"]
    assert meta["License-Expression"] == "BSD-3-Clause"
    assert "LICENSE" in (meta.get_all("License-File") or [])
    urls = dict(u.split(", ", 1) for u in meta.get_all("Project-URL") or [])
    assert set(urls) >= URLS, f"Project-URL lacks {URLS - set(urls)}"
    assert all(u.startswith("https://") for u in urls.values()), urls
    classifiers = meta.get_all("Classifier") or []
    for wanted in [
        "Intended Audience :: Science/Research",
        "Topic :: Scientific/Engineering",
        *(f"Programming Language :: Python :: {v}" for v in PYTHONS),
    ]:
        assert wanted in classifiers, wanted
    assert any(c.startswith("Development Status :: ") for c in classifiers), classifiers
    assert any(c.startswith("Operating System :: ") for c in classifiers), classifiers
    # PEP 639: the licence is the SPDX expression above; a "License ::" classifier beside it
    # is refused by setuptools >= 77 and deprecated by the packaging guide.
    assert not any(c.startswith("License :: ") for c in classifiers), classifiers
    assert meta["Keywords"] and "robotics" in meta["Keywords"]
    assert meta["Description-Content-Type"] == "text/markdown"
    assert "comgrasp_pin" in meta.get_payload(), "the README is the long description"


def test_one_version():
    """comgrasp_pin.__version__ is the one source; pyproject reads it (no second literal)."""
    import comgrasp_pin

    assert comgrasp_pin.__version__ == VERSION
    assert "version" in PYPROJECT["project"]["dynamic"] and "version" not in PYPROJECT["project"]
    assert PYPROJECT["tool"]["setuptools"]["dynamic"]["version"] == {
        "attr": "comgrasp_pin.__version__"
    }


def test_installed_distribution_metadata():
    """What importlib.metadata reads of the installed package (an editable install included:
    reinstall after a version or metadata change)."""
    import comgrasp_pin

    meta = metadata.metadata("comgrasp_pin")
    assert meta["Version"] == comgrasp_pin.__version__, "installed metadata is stale: pip install"
    _check_metadata(meta)


@pytest.mark.slow
def test_wheel_metadata(wheel):
    meta = _wheel_metadata(wheel)
    _check_metadata(meta)
    (license_file,) = [n for n in wheel.namelist() if n.endswith(".dist-info/licenses/LICENSE")]
    assert wheel.read(license_file) == (ROOT / "LICENSE").read_bytes()
