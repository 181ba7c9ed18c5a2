"""Frames and lines: the grasp pose type, transform checks, top-down frames, closest points.

Names follow docs/design.md section 2: ``T_a_b`` is the pose of frame b in frame a (4x4).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from comgrasp_pin import validate
from comgrasp_pin.errors import InvalidInputError, UnobservableError


@dataclass(frozen=True)
class GraspPose:
    """A top-down grasp in the world frame.

    Attributes:
        x, y: position of the grasp point (the rod's axis) in the world (m).
        z: height of the rod's axis (m).
        yaw: direction of the rod's axis about world z (rad); psi and psi + pi are the
            same grasp.
    """

    x: float
    y: float
    z: float
    yaw: float


_EYE3 = np.eye(3)
_LAST_ROW = np.array([0.0, 0.0, 0.0, 1.0])


def _allclose(a: np.ndarray, b: np.ndarray, atol: float) -> bool:
    """``np.allclose(a, b, atol=atol)`` for finite arrays, without its checks.

    A tenth of its time on a 3 x 3: perception checks thousands of transforms an episode.
    """
    return bool((np.abs(a - b) <= atol + 1e-5 * np.abs(b)).all())


def check_transform(T: np.ndarray, name: str = "T", atol: float = 1e-6) -> np.ndarray:
    """``T`` as a (4, 4) float rigid transform; InvalidInputError otherwise."""
    T = validate.real_array(T, name)
    if T.shape != (4, 4):
        raise InvalidInputError(f"{name} must be a (4, 4) homogeneous transform, got {T.shape}")
    if not np.isfinite(T).all():
        raise InvalidInputError(f"{name} contains NaN or inf")
    R = T[:3, :3]
    if np.abs(R).max() > 1.0 + atol:  # no entry of a rotation exceeds 1 (and R^T R overflows)
        raise InvalidInputError(f"{name}[:3, :3] is not a rotation matrix")
    if not _allclose(R.T @ R, _EYE3, atol) or np.linalg.det(R) < 0:
        raise InvalidInputError(f"{name}[:3, :3] is not a rotation matrix")
    if not _allclose(T[3], _LAST_ROW, atol):
        raise InvalidInputError(f"{name} last row must be (0, 0, 0, 1), got {T[3]}")
    return T


def invert_transform(T_a_b: np.ndarray) -> np.ndarray:
    """T_b_a (4, 4) from T_a_b (4, 4); InvalidInputError unless T_a_b is a rigid transform."""
    T_a_b = check_transform(T_a_b, "T_a_b")
    R, p = T_a_b[:3, :3], T_a_b[:3, 3]
    T_b_a = np.eye(4)
    T_b_a[:3, :3] = R.T
    T_b_a[:3, 3] = -R.T @ p
    return T_b_a


def transform_from_quaternion(translation: object, quaternion_xyzw: object) -> np.ndarray:
    """(4, 4) transform of a translation (3,) and a unit quaternion (x, y, z, w), ROS's order.

    The quaternion is normalised (a message's rounding); one of zero length is refused.
    """
    t = validate.finite_array(translation, "translation", (3,))
    x, y, z, w = validate.finite_array(quaternion_xyzw, "quaternion (x, y, z, w)", (4,))
    norm = float(np.sqrt(x * x + y * y + z * z + w * w))
    if norm < 1e-9:
        raise InvalidInputError("a quaternion of zero length is no rotation")
    x, y, z, w = x / norm, y / norm, z / norm, w / norm
    T = np.eye(4)
    T[:3, :3] = [[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                 [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                 [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]]  # fmt: skip
    T[:3, 3] = t
    return T


def rotation_angle(T: np.ndarray) -> float:
    """Angle (rad, in [0, pi]) of the rotation of the rigid transform ``T`` (4, 4)."""
    return float(np.arccos(np.clip(0.5 * (np.trace(T[:3, :3]) - 1.0), -1.0, 1.0)))


def closest_point_on_line(
    p_line: np.ndarray, d_line: np.ndarray, p_other: np.ndarray, d_other: np.ndarray
) -> float:
    """Parameter t of the point p_line + t d_line closest to the line p_other + s d_other.

    Points and directions are (3,) vectors, the directions of unit length.

    Raises:
        InvalidInputError: a vector of the wrong shape, not finite, or a direction that is
            not of unit length. UnobservableError: the lines are parallel (no single point).
    """
    p_line, p_other = (validate.finite_array(v, n, (3,)) for v, n in
                       ((p_line, "p_line"), (p_other, "p_other")))  # fmt: skip
    d_line, d_other = (_unit(v, n) for v, n in ((d_line, "d_line"), (d_other, "d_other")))
    w = p_line - p_other
    b = d_line @ d_other
    if not 1.0 - b * b > PARALLEL_TOL:
        raise UnobservableError("the two lines are parallel: no single closest point")
    return float((b * (d_other @ w) - d_line @ w) / (1.0 - b * b))


PARALLEL_TOL = 1e-12
"""Lines whose directions have 1 - cos^2 below this count as parallel."""


def tilt_from_level_deg(angle: float) -> float:
    """The tilt from level of a line at ``angle`` (rad) from the horizontal, in [0, 90] deg.

    A rod's axis is a line: ``angle`` and ``angle`` + 180 deg are the same tilt.
    """
    a = abs(np.degrees(angle)) % 180.0
    return float(min(a, 180.0 - a))


def tilt_difference_deg(a: float, b: float) -> float:
    """The angle between two lines at ``a`` and ``b`` (rad), in [0, 90] deg."""
    return tilt_from_level_deg(a - b)


def _unit(value: object, name: str) -> np.ndarray:
    v = validate.finite_array(value, name, (3,))
    if abs(float(np.linalg.norm(v)) - 1.0) > 1e-6:
        raise InvalidInputError(f"{name} must be a unit vector, got {v} (norm {np.linalg.norm(v)})")
    return v
