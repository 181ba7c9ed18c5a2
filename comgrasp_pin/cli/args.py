"""The command line's argument types, and the options several commands share.

Each option is parsed and checked before anything runs: a bad value ends the command with
argparse's usage message and exit status 2 (no traceback, nothing written). The checks
themselves live in ``validate``.
"""

from __future__ import annotations

import argparse
import json
import os
from collections.abc import Callable
from pathlib import Path

from comgrasp_pin import validate
from comgrasp_pin._paths import sim_path
from comgrasp_pin.config import SENSOR_PRESETS
from comgrasp_pin.errors import InvalidInputError


def argument_type(parse: Callable[[str], object], label: str) -> Callable[[str], object]:
    """An argparse ``type=``: ``parse`` with InvalidInputError turned into argparse's error."""

    def convert(text: str) -> object:
        try:
            return parse(text)
        except InvalidInputError as exc:
            raise argparse.ArgumentTypeError(str(exc).strip()) from None

    convert.__name__ = label  # argparse names the type in "invalid <name> value"
    return convert


def _parse_int(text: str, low: int, high: int | None) -> int:
    try:
        value = int(text)
    except ValueError:
        raise InvalidInputError(f"must be an integer, got {text!r}") from None
    return validate.integer(value, "", low=low, high=high)


def _parse_float(text: str, low: float) -> float:
    try:
        value = float(text)
    except ValueError:
        raise InvalidInputError(f"must be a number, got {text!r}") from None
    return validate.number(value, "", low=low)


def int_at_least(low: int, high: int | None = None) -> Callable[[str], object]:
    """An integer option >= ``low`` (and <= ``high`` if given)."""
    return argument_type(lambda text: _parse_int(text, low, high), "integer")


def float_at_least(low: float) -> Callable[[str], object]:
    """A finite number option >= ``low``."""
    return argument_type(lambda text: _parse_float(text, low), "number")


def _parse_positive(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise InvalidInputError(f"must be a number of seconds, got {text!r}") from None
    return validate.number(value, "", low=0.0, low_open=True)


positive_seconds = argument_type(_parse_positive, "seconds")
"""A finite time in seconds, > 0."""


def _parse_names(text: str, valid: tuple[str, ...]) -> tuple[str, ...]:
    names = tuple(part.strip() for part in text.split(","))
    if not text.strip() or not all(names):
        raise InvalidInputError(f"needs comma-separated names from {', '.join(valid)}"
                                f", got {text!r}")  # fmt: skip
    unknown = [n for n in names if n not in valid]
    if unknown:
        raise InvalidInputError(f"unknown object(s) {unknown}; objects are {', '.join(valid)}")
    repeated = sorted({n for n in names if names.count(n) > 1})
    if repeated:
        raise InvalidInputError(f"object(s) {repeated} are listed more than once")
    return names


def object_list(valid: tuple[str, ...]) -> Callable[[str], object]:
    """A comma-separated list of distinct names from ``valid``."""
    return argument_type(lambda text: _parse_names(text, valid), "object list")


def _parse_out_dir(text: str) -> Path:
    path = Path(text)
    if not text.strip():
        raise InvalidInputError("must name a folder, got an empty path")
    for part in (path, *path.parents):
        if part.exists() and not part.is_dir():
            raise InvalidInputError(f"{part} exists and is not a folder")
        if part.exists():
            if not os.access(part, os.W_OK | os.X_OK):
                raise InvalidInputError(f"{part} is not a writable folder")
            break
    return path


out_dir = argument_type(_parse_out_dir, "folder")
"""An output folder: existing or creatable (no file in the way, its first existing
ancestor writable)."""


OBJECTS: tuple[str, ...] = tuple(json.loads(sim_path("objects.json").read_text())["objects"])
"""The rods a command may name (``--object``, ``--objects``): the names in ``sim/objects.json``,
in its order, as ``simulation.objects.OBJECTS`` has them; read here so that building the
parser imports no MuJoCo (the robot-side commands never load the simulator)."""


def sentence(text: str) -> str:
    """``text`` with a capital first letter: a subcommand's help as its help page's line."""
    return text[0].upper() + text[1:]


def add_sensors_arg(p: argparse.ArgumentParser) -> None:
    """``--sensors PRESET``, on the experiments and ``demo``."""
    p.add_argument("--sensors", default="ideal", choices=SENSOR_PRESETS,
                   help="sensor preset: ideal renders and torques, or realistic (RealSense-class "
                   "depth, link-side torque sensors, gripper model error; realistic_current: a "
                   "UR CB3's current-based torques); ideal+SOURCE adds one realistic error "
                   "source to the ideal sensors (%(default)s)")  # fmt: skip


SEED = int_at_least(0)
"""A seed: an integer >= 0."""
