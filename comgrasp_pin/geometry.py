"""Frames and lines: transform checks and the CoM position along a rod's axis.

Names follow DESIGN section 3: ``T_a_b`` is the pose of frame b in frame a (4x4).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from comgrasp_pin.errors import InvalidInputError, UnobservableError

MIN_AXIS_GRAVITY_ANGLE = 0.05
"""Smallest angle (rad, about 2.9 deg) between the rod axis and the CoM line (gravity) for
which ``com_along_axis`` intersects them; the error of x_CoM^O grows as 1 / sin(angle)."""


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


def check_transform(T: np.ndarray, name: str = "T", atol: float = 1e-6) -> np.ndarray:
    """``T`` as a (4, 4) float rigid transform; InvalidInputError otherwise."""
    T = np.asarray(T, dtype=float)
    if T.shape != (4, 4):
        raise InvalidInputError(f"{name} must be a (4, 4) homogeneous transform, got {T.shape}")
    if not np.all(np.isfinite(T)):
        raise InvalidInputError(f"{name} contains NaN or inf")
    R = T[:3, :3]
    if not np.allclose(R.T @ R, np.eye(3), atol=atol) or np.linalg.det(R) < 0:
        raise InvalidInputError(f"{name}[:3, :3] is not a rotation matrix")
    if not np.allclose(T[3], [0.0, 0.0, 0.0, 1.0], atol=atol):
        raise InvalidInputError(f"{name} last row must be (0, 0, 0, 1), got {T[3]}")
    return T


def invert_transform(T_a_b: np.ndarray) -> np.ndarray:
    """T_b_a (4, 4) from T_a_b (4, 4)."""
    R, p = T_a_b[:3, :3], T_a_b[:3, 3]
    T_b_a = np.eye(4)
    T_b_a[:3, :3] = R.T
    T_b_a[:3, 3] = -R.T @ p
    return T_b_a


def closest_point_on_line(
    p_line: np.ndarray, d_line: np.ndarray, p_other: np.ndarray, d_other: np.ndarray
) -> float:
    """Parameter t of the point p_line + t d_line closest to the line p_other + s d_other.

    Directions are unit (3,) vectors and must not be parallel (the caller checks).
    """
    w = p_line - p_other
    b = d_line @ d_other
    return float((b * (d_other @ w) - d_line @ w) / (1.0 - b * b))


def com_along_axis(est, T_ee_obj: np.ndarray, min_angle: float = MIN_AXIS_GRAVITY_ANGLE) -> float:
    """x_CoM^O (m): where the payload's CoM lies along the rod axis, from the rod's centre.

    The rod axis is the obj x-axis through the obj origin, given in the ee frame by
    ``T_ee_obj`` (4, 4). With one pose (``est.unobservable_ee`` set) the CoM is only known to
    lie on the vertical line com_ee + s * unobservable_ee; the answer is the point of the rod
    axis closest to that line (their intersection when they meet). With a full 3-D CoM it is
    the projection of com_ee on the axis. Paper eq. 8 is the one-pose case with gravity along
    ee-z, intersecting the CoM line with the plane z^O = 0 instead of with the axis: the two
    agree whenever obj-y is horizontal (a rod tilted only about the jaw axis).

    Args:
        est: a ``ComEstimate`` (uses ``com_ee`` and ``unobservable_ee``).
        T_ee_obj: (4, 4) pose of the object frame in the ee frame.
        min_angle: smallest accepted angle (rad) between rod axis and gravity (one pose).
    Raises:
        InvalidInputError for a bad transform; UnobservableError when the rod axis is
        within ``min_angle`` of gravity (the vertical CoM line then does not fix a point).
    """
    T_ee_obj = check_transform(T_ee_obj, "T_ee_obj")
    origin_ee, axis_ee = T_ee_obj[:3, 3], T_ee_obj[:3, 0]
    com_ee = np.asarray(est.com_ee, dtype=float)
    if est.unobservable_ee is None:
        return float(axis_ee @ (com_ee - origin_ee))
    down_ee = np.asarray(est.unobservable_ee, dtype=float)
    sin_angle = np.linalg.norm(np.cross(axis_ee, down_ee))
    if sin_angle < np.sin(min_angle):
        angle = np.degrees(np.arcsin(min(sin_angle, 1.0)))
        raise UnobservableError(
            f"the rod axis is {angle:.2f} deg from gravity (minimum {np.degrees(min_angle):.2f}"
            " deg): the vertical CoM line does not fix a point along it; measure at a pose "
            "where the rod is not vertical"
        )
    return closest_point_on_line(origin_ee, axis_ee, com_ee, down_ee)
