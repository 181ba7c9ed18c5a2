"""A prior on where the CoM can be: near the rod's axis, as the side camera sees it.

The CoM of a rod lies on or near its axis: on it for a rod of revolution, a little off it
for a hammer whose head sits to one side. The side camera gives the axis in the ee frame;
``AxisPrior`` turns that into a Gaussian on the CoM's distance from the axis line, with a
standard deviation that says how far off the axis the CoM may sit and how well the axis was
seen. With one static pose it settles the CoM's component along gravity that the torques
cannot see (the paper's eq. 8, made general); with several it pulls only where the torques
are weak.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from comgrasp_pin import validate
from comgrasp_pin.errors import InvalidInputError

MAX_DISTANCE_M = 1e3
"""Largest accepted distance (m) of the prior's point from the ee, and largest std."""


@dataclass(frozen=True)
class AxisPrior:
    """Gaussian prior on the CoM's distance from the line ``point_ee + t direction_ee``.

    Attributes:
        point_ee: (3,) a point of the rod's axis in the ee frame (m).
        direction_ee: (3,) the axis direction in the ee frame; any non-zero length (stored
            as a unit vector).
        std: standard deviation of the CoM's distance from the line in each of the two
            directions across it (m), > 0 and <= MAX_DISTANCE_M.

    Raises:
        InvalidInputError: a point or direction of the wrong shape or not finite, a zero
            direction, a std that is not finite and positive.
    """

    point_ee: np.ndarray
    direction_ee: np.ndarray
    std: float

    def __post_init__(self) -> None:
        point = _vector3(self.point_ee, "point_ee")
        direction = _vector3(self.direction_ee, "direction_ee")
        with np.errstate(over="ignore"):
            norm = float(np.linalg.norm(direction))
        if not np.isfinite(norm):  # entries near the float range: scale first
            direction = direction / np.max(np.abs(direction))
            norm = float(np.linalg.norm(direction))
        if not norm > 1e-12:
            raise InvalidInputError(
                f"AxisPrior direction_ee must be a non-zero vector, got {direction}"
            )
        try:
            std = float(self.std)
        except (TypeError, ValueError):
            raise InvalidInputError(f"AxisPrior std must be a number, got {self.std!r}") from None
        if not (np.isfinite(std) and 0.0 < std <= MAX_DISTANCE_M):
            raise InvalidInputError(
                f"AxisPrior std must be > 0 and <= {MAX_DISTANCE_M:g} (m), got {std}"
            )
        point.flags.writeable = False
        unit = direction / norm
        unit.flags.writeable = False
        object.__setattr__(self, "point_ee", point)
        object.__setattr__(self, "direction_ee", unit)
        object.__setattr__(self, "std", std)

    @classmethod
    def from_rod(cls, T_ee_obj: np.ndarray, std: float) -> AxisPrior:
        """The prior of a rod whose frame is ``T_ee_obj`` (4, 4): its axis is obj-x."""
        T = np.asarray(T_ee_obj, dtype=float)
        if T.shape != (4, 4):
            raise InvalidInputError(f"T_ee_obj must be (4, 4), got shape {T.shape}")
        return cls(T[:3, 3], T[:3, 0], std)

    def across(self) -> np.ndarray:
        """(3, 3) projector onto the plane across the axis: I - d d^T."""
        d = self.direction_ee
        return np.eye(3) - np.outer(d, d)

    def distance(self, com_ee: np.ndarray) -> float:
        """Distance (m) of the point ``com_ee`` (3,) from the axis line."""
        return float(np.linalg.norm(self.across() @ (np.asarray(com_ee) - self.point_ee)))


def _vector3(value, name: str) -> np.ndarray:
    v = np.array(validate.real_array(value, f"AxisPrior {name}"), dtype=float)  # a copy
    if v.shape != (3,):
        raise InvalidInputError(f"AxisPrior {name} must have shape (3,), got {v.shape}")
    if not np.all(np.isfinite(v)):
        raise InvalidInputError(f"AxisPrior {name} must be finite, got {v}")
    if name == "point_ee" and np.abs(v).max() > MAX_DISTANCE_M:
        raise InvalidInputError(
            f"AxisPrior point_ee must lie within {MAX_DISTANCE_M:g} m of the ee, got {v}"
        )
    return v
