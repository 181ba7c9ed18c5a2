"""Where the CoM lies along a held rod: the CoM line met with the rod's axis.

Paper eq. 8, made general, from the rod's pose in the jaws, ``T_ee_obj`` (4, 4), seen by the
side camera.
"""

from __future__ import annotations

from typing import cast

import numpy as np

from comgrasp_pin import validate
from comgrasp_pin.errors import InvalidInputError, UnobservableError
from comgrasp_pin.estimation.estimate import ComEstimate
from comgrasp_pin.geometry import check_transform, closest_point_on_line

MIN_AXIS_GRAVITY_ANGLE = 0.05
"""Smallest angle (rad, about 2.9 deg) between the rod axis and the CoM line (gravity) for
which ``com_along_axis`` intersects them; the error of x_CoM^O grows as 1 / sin(angle)."""


def com_along_axis(
    est: ComEstimate, T_ee_obj: np.ndarray, min_angle: float = MIN_AXIS_GRAVITY_ANGLE
) -> float:
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
        InvalidInputError: a bad transform, an ``est`` that is not a ComEstimate or a
            ``min_angle`` outside (0, pi/2].
        UnobservableError: the rod axis is within ``min_angle`` of gravity (the vertical
            CoM line then does not fix a point).
    """
    if not (hasattr(est, "com_ee") and hasattr(est, "unobservable_ee")):
        raise InvalidInputError(f"est must be a ComEstimate, got {type(est).__name__}")
    com_ee = validate.finite_array(est.com_ee, "est.com_ee (m)", (3,))
    min_angle = validate.number(min_angle, "min_angle (rad)", low=0.0, high=np.pi / 2,
                                low_open=True)  # fmt: skip
    T_ee_obj = check_transform(T_ee_obj, "T_ee_obj")
    origin_ee, axis_ee = T_ee_obj[:3, 3], T_ee_obj[:3, 0]
    if est.unobservable_ee is None:
        return float(axis_ee @ (com_ee - origin_ee))
    down_ee = validate.finite_array(est.unobservable_ee, "est.unobservable_ee", (3,))
    sin_angle = cast(float, np.linalg.norm(np.cross(axis_ee, down_ee)))
    if sin_angle < np.sin(min_angle):
        angle = np.degrees(np.arcsin(min(sin_angle, 1.0)))
        raise UnobservableError(
            f"the rod axis is {angle:.2f} deg from gravity (minimum {np.degrees(min_angle):.2f}"
            " deg): the vertical CoM line does not fix a point along it; measure at a pose "
            "where the rod is not vertical"
        )
    return closest_point_on_line(origin_ee, axis_ee, com_ee, down_ee)
