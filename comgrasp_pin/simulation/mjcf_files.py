"""An MJCF file from elsewhere, checked before MuJoCo compiles it.

``file_checks`` (the shared, MuJoCo-free checks: a regular file of bounded size, XML without
a DOCTYPE, every referenced asset inside its folder) reads it first; only then does MuJoCo
see the path. Here, on the simulation side, because it imports MuJoCo.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import mujoco

from comgrasp_pin import file_checks
from comgrasp_pin.errors import InvalidInputError


def load_mjcf(path: str | Path, package_dirs: Sequence[str | Path] = ()) -> mujoco.MjModel:
    """A ``mujoco.MjModel`` from an MJCF file checked by ``file_checks.read_description``.

    Raises:
        InvalidInputError: the file fails a check, or MuJoCo cannot compile it.
    """
    file_checks.read_description(path, "MJCF", package_dirs)
    try:
        return mujoco.MjModel.from_xml_path(str(path))
    except (ValueError, UnicodeError) as exc:
        raise InvalidInputError(f"MuJoCo cannot load the MJCF file {path}: {exc}") from None
