"""Where the package's assets and example-robot-data's robot descriptions live on disk."""

from __future__ import annotations

from functools import cache
from importlib import metadata, resources
from pathlib import Path


def asset_path(*parts: str) -> Path:
    """Path of a file shipped in ``comgrasp_pin/assets`` (works for wheel and editable installs)."""
    path = Path(str(resources.files("comgrasp_pin").joinpath("assets", *parts)))
    if not path.exists():
        raise FileNotFoundError(f"package asset not found: {path}")
    return path


@cache
def example_robot_data_dir() -> Path:
    """The ``share`` folder of the installed example-robot-data package.

    It holds ``robots/<name>_description/...``; ``package://example-robot-data/`` mesh URIs
    resolve against it.
    """
    dist = metadata.distribution("example-robot-data")
    path = Path(str(dist.locate_file("cmeel.prefix/share/example-robot-data")))
    if not path.is_dir():
        raise FileNotFoundError(f"example-robot-data share folder not found at {path}")
    return path


def example_robot_urdf(relative: str) -> Path:
    """Path of a URDF of example-robot-data, e.g. ``"panda_description/urdf/panda.urdf"``."""
    path = example_robot_data_dir() / "robots" / relative
    if not path.exists():
        raise FileNotFoundError(f"no such example-robot-data file: {path}")
    return path
