"""A robot read from its URDF and mounted under any gravity: floor, wall, ceiling or a tilt.

Every model of the package takes gravity from ``model.gravity`` (Pinocchio), in any direction
and of any magnitude. The planners measure heights along world z (``planning.floor_heights``),
so for a base mounted otherwise than on a floor, ``gravity_base`` being gravity in the URDF's
base (root) frame, the model's world frame is turned by the smallest rotation R_world_base
that takes gravity to -z, and the model's gravity is (0, 0, -|g|) in it. Joint torques,
ee-frame quantities and the CoM in the ee or flange frame do not depend on that choice of
world frame; only ``T_world_ee`` is in the turned frame.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin

from comgrasp_pin import validate
from comgrasp_pin.errors import InvalidInputError
from comgrasp_pin.robot import RobotModel, urdf_model

GRAVITY_FLOOR = (0.0, 0.0, -9.81)
"""Gravity in the base frame of a floor-mounted arm (m/s^2)."""


def load_robot(
    urdf_path: str | Path,
    ee_frame: str,
    package_dirs: list[str | Path] | None = None,
    gravity_base: tuple[float, float, float] | np.ndarray = GRAVITY_FLOOR,
) -> RobotModel:
    """The arm of ``urdf_path`` up to ``ee_frame``, with gravity ``gravity_base`` (m/s^2)."""
    g = validate.real_array(gravity_base, "gravity_base")
    if g.shape != (3,) or not np.all(np.isfinite(g)) or not np.linalg.norm(g) > 0.1:
        raise InvalidInputError(
            f"gravity must be 3 finite numbers GX,GY,GZ in the robot's base frame (m/s^2) with "
            f"a magnitude above 0.1, e.g. 0,0,-9.81 on a floor or 9.81,0,0 on a wall; got {g}"
        )
    path = Path(urdf_path)
    full = urdf_model(path, package_dirs)
    R_world_base = rotation_to_down(g)
    if not np.allclose(R_world_base, np.eye(3)):
        _turn_root(full, pin.SE3(R_world_base, np.zeros(3)))
    robot = RobotModel(full, ee_frame, path)
    robot.package_dirs = [str(p) for p in package_dirs or []]  # as from_urdf
    robot.model.gravity = pin.Motion(np.array([0.0, 0.0, -np.linalg.norm(g), 0.0, 0.0, 0.0]))
    return robot


def rotation_to_down(gravity_base: np.ndarray) -> np.ndarray:
    """(3, 3) R_world_base, the smallest rotation taking ``gravity_base`` to (0, 0, -|g|)."""
    quat = pin.Quaternion.FromTwoVectors(np.asarray(gravity_base, float), np.array([0, 0, -1.0]))
    return quat.toRotationMatrix()


def _turn_root(model: pin.Model, M_world_base: pin.SE3) -> None:
    """Place the root of ``model`` at ``M_world_base``: every joint and frame on the universe."""
    for j in range(1, model.njoints):
        if model.parents[j] == 0:
            model.jointPlacements[j] = M_world_base * model.jointPlacements[j]
    for i, frame in enumerate(model.frames):
        if frame.parentJoint == 0 and i > 0:
            frame.placement = M_world_base * frame.placement
            model.frames[i] = frame
