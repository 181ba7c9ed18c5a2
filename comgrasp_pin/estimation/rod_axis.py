"""Where the CoM lies along a held rod, and the two-pose solve in the rod's own frame.

The first meets the CoM line with the rod's axis (paper eq. 8, made general). Both take the
rod's pose in the jaws, ``T_ee_obj`` (4, 4), from the side camera.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import cast

import numpy as np

from comgrasp_pin.errors import EmptyGripperError, InvalidInputError, UnobservableError
from comgrasp_pin.estimation.estimate import MIN_MASS_KG, ComEstimate, delta_method
from comgrasp_pin.estimation.inputs import validate_inputs
from comgrasp_pin.estimation.regressor import pose_regressor
from comgrasp_pin.geometry import check_transform, closest_point_on_line
from comgrasp_pin.robot import RobotModel

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
        InvalidInputError for a bad transform; UnobservableError when the rod axis is
        within ``min_angle`` of gravity (the vertical CoM line then does not fix a point).
    """
    T_ee_obj = check_transform(T_ee_obj, "T_ee_obj")
    origin_ee, axis_ee = T_ee_obj[:3, 3], T_ee_obj[:3, 0]
    com_ee = np.asarray(est.com_ee, dtype=float)
    if est.unobservable_ee is None:
        return float(axis_ee @ (com_ee - origin_ee))
    down_ee = np.asarray(est.unobservable_ee, dtype=float)
    sin_angle = cast(float, np.linalg.norm(np.cross(axis_ee, down_ee)))
    if sin_angle < np.sin(min_angle):
        angle = np.degrees(np.arcsin(min(sin_angle, 1.0)))
        raise UnobservableError(
            f"the rod axis is {angle:.2f} deg from gravity (minimum {np.degrees(min_angle):.2f}"
            " deg): the vertical CoM line does not fix a point along it; measure at a pose "
            "where the rod is not vertical"
        )
    return closest_point_on_line(origin_ee, axis_ee, com_ee, down_ee)


@dataclass(frozen=True)
class RodFrameEstimate:
    """Mass and CoM from poses at which the rod sat differently in the jaws.

    Attributes:
        com_obj: (3,) CoM in the rod's frame (m); com_obj[0] is x_CoM^O.
        mass: kg.
        condition_number: of the stacked problem (large: the poses do not separate the CoM).
        cov: (4, 4) covariance of (mass, com_obj) from the torque noise, or None.
    """

    com_obj: np.ndarray
    mass: float
    condition_number: float
    cov: np.ndarray | None = None


def com_in_rod_frame(
    robot: RobotModel,
    q: np.ndarray,
    tau_before: np.ndarray,
    tau_after: np.ndarray,
    T_ee_obj: np.ndarray,
    torque_std: float | np.ndarray | None = None,
) -> RodFrameEstimate:
    """CoM in the rod's frame from k >= 2 static poses with the rod's pose in the jaws at each.

    ``q``, ``tau_before`` and ``tau_after`` are (k, n); at pose i the rod sat in the jaws at
    ``T_ee_obj[i]`` ((k, 4, 4) in all), as the side camera saw it.

    The CoM is fixed in the rod, so with theta_ee = (m, m c_ee) and c_ee = R c_obj + p per
    pose, dtau = Y theta_ee becomes linear in (m, m c_obj): rows (Y_0 + Y_c p, Y_c R),
    stacked over the poses. Inputs are checked as in ``estimate_com``; a mass not above
    MIN_MASS_KG raises EmptyGripperError. With ``torque_std`` (N m, each reading) the result
    carries the covariance of (m, c_obj).
    """
    Q, dtau, sigma = validate_inputs(robot, q, tau_before, tau_after, torque_std)
    T_all = np.asarray(T_ee_obj, dtype=float)
    if len(Q) < 2 or T_all.shape != (len(Q), 4, 4):
        raise InvalidInputError(
            f"com_in_rod_frame needs k >= 2 poses and T_ee_obj of shape (k, 4, 4); got "
            f"{len(Q)} poses and T_ee_obj of shape {T_all.shape}"
        )
    rows = []
    for k, (qk, T) in enumerate(zip(Q, T_all, strict=True)):
        T = check_transform(T, f"T_ee_obj[{k}]")
        Y, _ = pose_regressor(robot, qk)
        rows.append(np.c_[Y[:, 0] + Y[:, 1:] @ T[:3, 3], Y[:, 1:] @ T[:3, :3]])
    A, b = np.vstack(rows), dtau.ravel()
    theta = np.linalg.lstsq(A, b, rcond=None)[0]
    singular = np.linalg.svd(A, compute_uv=False)
    if not theta[0] > MIN_MASS_KG:
        raise EmptyGripperError(
            f"the rod-frame estimate gives a payload of {theta[0]:.3g} kg: nothing held?"
        )
    cond = float(singular[0] / max(singular[-1], 1e-300))
    cov = None
    if sigma is not None:
        W = np.tile(1.0 / (2.0 * sigma**2), len(Q))  # 1 / variance of each difference
        cov = delta_method(theta, np.linalg.inv(A.T @ (A * W[:, None])))
    return RodFrameEstimate(theta[1:] / theta[0], float(theta[0]), cond, cov)
