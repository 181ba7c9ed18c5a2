"""Config values by their dotted path in the ``EpisodeConfig`` tree, for sweeps.

``motion.grip_force``, ``sensors.torque.noise_std``, ``world.pad_friction.0`` (an element of
a tuple by its index; a tuple's path alone means its first element): every number of the
tree has one. Short aliases (``ALIASES``) name the common ones. ``with_values`` returns a
new tree with some values replaced; the tree's own checks apply to them.
"""

from __future__ import annotations

from dataclasses import fields, is_dataclass, replace

from comgrasp_pin.config.tree import EpisodeConfig
from comgrasp_pin.errors import InvalidInputError

ALIASES = {
    "grip_force": "motion.grip_force",
    "noise": "sensors.torque.noise_std",
    "bias": "sensors.torque.bias",
    "drift": "sensors.torque.drift_std",
    "friction": "world.pad_friction.0",
    "torsional_friction": "world.pad_friction.1",
    "kp": "world.kp",
    "sim_dt": "world.sim_dt",
    "roll_deg": "trial.roll_deg",
    "window": "trial.window",
    "settle": "trial.settle",
    "lift_height": "trial.lift_height",
    "slip_tilt_deg": "regrasp.slip_tilt_deg",
}
"""Short names of common config values: alias -> dotted path."""


def _is_number(value: object) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def numeric_paths(tree: object = None, prefix: str = "") -> dict[str, type]:
    """Every numeric value of the tree (default: ``EpisodeConfig()``) and its type.

    Returns:
        dotted path -> int or float; a tuple's elements as ``path.i``.
    """
    tree = EpisodeConfig() if tree is None else tree
    out: dict[str, type] = {}
    for f in fields(tree):
        value, path = getattr(tree, f.name), f"{prefix}{f.name}"
        if is_dataclass(value):
            out.update(numeric_paths(value, f"{path}."))
        elif _is_number(value):
            out[path] = type(value)
        elif isinstance(value, tuple) and value and all(_is_number(v) for v in value):
            out.update({f"{path}.{i}": type(v) for i, v in enumerate(value)})
    return out


def valid_names() -> str:
    """The aliases and paths a sweep accepts, as text for an error message."""
    aliases = ", ".join(f"{a} ({p})" for a, p in ALIASES.items())
    return f"aliases: {aliases}; paths: {', '.join(numeric_paths())}"


def resolve(name: str) -> str:
    """The dotted path ``name`` (an alias or a path) stands for.

    Raises:
        InvalidInputError: no number of the config tree has that name (the valid ones are
            listed).
    """
    paths = numeric_paths()
    path = ALIASES.get(name, name)
    if path not in paths and f"{path}.0" in paths:
        path = f"{path}.0"  # a tuple's path alone: its first element
    if path not in paths:
        raise InvalidInputError(f"unknown config value {name!r}; {valid_names()}")
    return path


def with_values(config: EpisodeConfig, values: dict[str, float]) -> EpisodeConfig:
    """``config`` with the values at the given dotted paths (``resolve``d) replaced.

    Raises:
        InvalidInputError: an unknown path, a non-integer for an integer value, or a value
            the config tree refuses.
    """
    kinds = numeric_paths()
    for name, value in values.items():
        path = resolve(name)
        number: float | int = float(value)
        if kinds[path] is int:
            if not float(number).is_integer():
                raise InvalidInputError(f"{path} takes an integer, got {value!r}")
            number = int(number)
        config = _replace_at(config, path.split("."), number)
    return config


def _replace_at(node, parts: list[str], value):
    head, rest = parts[0], parts[1:]
    current = getattr(node, head)
    if not rest:
        return replace(node, **{head: value})
    if isinstance(current, tuple):
        items = list(current)
        items[int(rest[0])] = value
        return replace(node, **{head: tuple(items)})
    return replace(node, **{head: _replace_at(current, rest, value)})
