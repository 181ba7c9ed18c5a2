"""Where the robot description (``urdf/``), the world description (``sim/``) and
example-robot-data's meshes live on disk.

``urdf/`` and ``sim/`` sit at the top of the repository, the only copies. A wheel carries
them inside the package (``comgrasp_pin/urdf``, ``comgrasp_pin/sim``; pyproject maps them
there), so a non-editable ``pip install .`` finds them from any folder; a source checkout or
an editable install finds them beside the package.
"""

from __future__ import annotations

from functools import cache
from importlib import metadata
from pathlib import Path

from comgrasp_pin.errors import InvalidInputError, MissingAssetError, MissingExtraError

_PACKAGE = Path(__file__).resolve().parent
DATA_FOLDERS = ("urdf", "sim")


def data_path(folder: str, name: str) -> Path:
    """Path of ``name`` in the top-level ``folder`` ("urdf" or "sim")."""
    if folder not in DATA_FOLDERS:
        raise InvalidInputError(f"folder must be one of {DATA_FOLDERS}, got {folder!r}")
    for root in (_PACKAGE, _PACKAGE.parent):  # installed wheel, then source checkout
        path = root / folder / name
        if path.exists():
            return path
    raise MissingAssetError(
        f"{folder}/{name} not found beside the package ({_PACKAGE}) nor in the repository "
        f"({_PACKAGE.parent}); reinstall comgrasp_pin"
    )


def urdf_path(name: str = "ur5_gripper.urdf") -> Path:
    """Path of a robot description in ``urdf/``."""
    return data_path("urdf", name)


def sim_path(name: str = "scene.xml") -> Path:
    """Path of a world description in ``sim/``."""
    return data_path("sim", name)


@cache
def example_robot_data_dir() -> Path:
    """The ``share`` folder of the installed example-robot-data package.

    It holds ``robots/<name>_description/...``; ``package://example-robot-data/`` mesh URIs
    resolve against it.
    """
    dist = metadata.distribution("example-robot-data")
    path = Path(str(dist.locate_file("cmeel.prefix/share/example-robot-data")))
    if not path.is_dir():
        raise MissingAssetError(f"example-robot-data share folder not found at {path}")
    return path


def example_robot_urdf(relative: str) -> Path:
    """Path of a URDF of example-robot-data, e.g. ``"panda_description/urdf/panda.urdf"``."""
    path = example_robot_data_dir() / "robots" / relative
    if not path.exists():
        raise MissingAssetError(f"no such example-robot-data file: {path}")
    return path


def fr3_urdf() -> Path:
    """The FR3's URDF that franky-sim ships (franka_description's), found without importing
    franky-sim (whose import loads MuJoCo); MissingExtraError where the extra is missing."""
    import importlib.util

    spec = importlib.util.find_spec("franky_sim")
    if spec is None or not spec.submodule_search_locations:
        raise MissingExtraError('the FR3 needs franky-sim: pip install ".[franka]"')
    return Path(spec.submodule_search_locations[0]) / "assets" / "fr3.urdf"


def results_dir() -> Path:
    """The paper-size runs committed with the repository (``docs/results``), for the notebooks.

    ``COMGRASP_RESULTS`` when set; else ``docs/results`` beside the package (a source checkout
    or an editable install), or above or in the current folder (a notebook opened in the
    repository's ``notebooks/``, the package installed from it). A wheel does not carry them.
    """
    import os

    if os.environ.get("COMGRASP_RESULTS"):
        return Path(os.environ["COMGRASP_RESULTS"])
    for root in (_PACKAGE.parent, Path.cwd().parent, Path.cwd()):
        if (root / "docs" / "results" / "accuracy.csv").exists():
            return root / "docs" / "results"
    raise MissingAssetError(
        "docs/results (the committed paper-size runs) not found beside the package nor from "
        f"the current folder {Path.cwd()}; set COMGRASP_RESULTS to its path"
    )
