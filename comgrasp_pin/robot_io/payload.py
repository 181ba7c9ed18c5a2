"""The payload as a robot controller wants it: mass, CoM and inertia in the flange frame.

The flange frame is the tool mounting frame the controller's payload refers to: ``tool0`` on
a UR arm (the URDF's tool flange), ``panda_link8`` (F, the flange) on a Franka arm. It must be
on the same rigid body as the ee frame, so that T_flange_ee is fixed by the URDF.

Inertia: static torques do not see it (they depend on the mass and the CoM only). It is an
approximation, always symmetric and positive semi-definite, about the CoM in flange axes:
- ``"point"``: a point mass, zero inertia;
- ``"cylinder:L,R,AXIS"``: a solid cylinder of length L and radius R (m) with its axis along
  the ee frame's AXIS (x, y or z; x is the rod's axis in a top-down grasp), centred on the
  estimated CoM (Pinocchio's ``Inertia.FromCylinder``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import pinocchio as pin

from comgrasp_pin import validate
from comgrasp_pin.errors import InvalidInputError
from comgrasp_pin.estimation import ComEstimate
from comgrasp_pin.robot import RobotModel

if TYPE_CHECKING:
    from comgrasp_pin.robot_io.wrench_static import WrenchStaticEstimate

_AXES = {"x": 0, "y": 1, "z": 2}
WRENCH_AT_REST = "a wrist sensor's wrench at rest"
INERTIA_HELP = "point | cylinder:L,R,AXIS (L, R in m; AXIS x, y or z of the ee frame)"


@dataclass(frozen=True)
class Payload:
    """A payload for a controller, in the flange frame (SI units).

    Attributes:
        mass: kg.
        com_flange: (3,) CoM in the flange frame (m).
        inertia_flange: (3, 3) inertia about the CoM, flange axes (kg m^2); an approximation.
        flange_frame: name of the flange frame.
        cov: (4, 4) covariance of (mass, com_flange) (kg, m), or None.
        inertia_model: how the inertia was made (``"point"`` or the cylinder spec).
        unobservable_flange: (3,) the direction (flange frame) the CoM was not seen along
            (its component there is 0 in the ee frame), or None.
        inertia_std_flange: (3, 3) std of each entry of ``inertia_flange`` where the inertia
            was identified from a motion, or None where it is an approximation.
        source: what it was estimated from, for the files' notes ("static joint torques",
            "a wrist sensor's wrench at rest", "a motion's joint torques", "a motion's
            wrench").
    """

    mass: float
    com_flange: np.ndarray
    inertia_flange: np.ndarray
    flange_frame: str
    cov: np.ndarray | None
    inertia_model: str
    unobservable_flange: np.ndarray | None = None
    inertia_std_flange: np.ndarray | None = None
    source: str = "static joint torques"

    def __post_init__(self) -> None:
        """Refuse complex, boolean, string and object arrays (validate.real_array)."""
        for name in ("com_flange", "inertia_flange", "cov", "unobservable_flange",
                     "inertia_std_flange"):  # fmt: skip
            value = getattr(self, name)
            if value is not None:
                object.__setattr__(self, name, validate.real_array(value, f"Payload.{name}"))

    @property
    def std(self) -> np.ndarray | None:
        """(4,) standard deviations of (mass, com_flange) (kg, m), or None."""
        return None if self.cov is None else np.sqrt(np.clip(np.diag(self.cov), 0, None))


def T_flange_ee(robot: RobotModel, flange_frame: str) -> np.ndarray:
    """(4, 4) the ee frame's pose in the flange frame, from the URDF (fixed joints only)."""
    return robot.T_frame_ee(flange_frame, "flange frame")


def inertia_about_com(mass: float, spec: str) -> tuple[np.ndarray, str, int | None]:
    """(3, 3) inertia about the CoM in the ee axes for ``spec``, the spec, the axis index."""
    spec = spec.strip()
    if spec == "point":
        return np.zeros((3, 3)), "point", None
    kind, _, rest = spec.partition(":")
    parts = rest.split(",")
    if kind != "cylinder" or len(parts) != 3 or parts[2].strip() not in _AXES:
        raise InvalidInputError(f"inertia {spec!r}: valid are {INERTIA_HELP}")
    try:
        length, radius = float(parts[0]), float(parts[1])
    except ValueError:
        raise InvalidInputError(f"inertia {spec!r}: L and R must be numbers (m)") from None
    if not (length > 0 and radius > 0 and np.isfinite(length + radius)):
        raise InvalidInputError(f"inertia {spec!r}: L and R must be > 0 (m)")
    axis = _AXES[parts[2].strip()]
    I_z = pin.Inertia.FromCylinder(mass, radius, length).inertia  # cylinder along z
    perm = np.roll(np.arange(3), 2 - axis)  # the cylinder's z onto the chosen axis
    P = np.eye(3)[:, perm]
    return P @ I_z @ P.T, f"cylinder:{length:g},{radius:g},{parts[2].strip()}", axis


def payload_in_flange(
    robot: RobotModel,
    est: ComEstimate | WrenchStaticEstimate,
    flange_frame: str | None = None,
    inertia: str = "point",
) -> Payload:
    """``est`` (CoM in the ee frame) expressed in ``flange_frame`` (default: the ee frame).

    ``est``: a joint-torque estimate, or a wrist sensor's static one.
    """
    flange = flange_frame or robot.ee_frame
    T = T_flange_ee(robot, flange)
    R = T[:3, :3]
    com_flange = R @ est.com_ee + T[:3, 3]
    I_ee, model, _ = inertia_about_com(est.mass, inertia)
    I_flange = R @ I_ee @ R.T
    I_flange = 0.5 * (I_flange + I_flange.T)
    cov = None
    if est.cov is not None:
        G = np.eye(4)
        G[1:, 1:] = R
        cov = G @ est.cov @ G.T
    u = None if est.unobservable_ee is None else R @ est.unobservable_ee
    source = "static joint torques" if isinstance(est, ComEstimate) else WRENCH_AT_REST
    return Payload(float(est.mass), com_flange, I_flange, flange, cov, model, u, None, source)


def dynamic_payload_in_flange(robot: RobotModel, est, flange_frame: str | None = None) -> Payload:
    """A ``DynamicEstimate`` (ee frame) in ``flange_frame``, the identified inertia too.

    The inertia's std is rotated to the flange axes through its covariance (R x R).
    """
    flange = flange_frame or robot.ee_frame
    T = T_flange_ee(robot, flange)
    R = T[:3, :3]
    I_flange = R @ est.inertia_com_ee @ R.T
    K = np.kron(R, R)  # vec(R I R^T) = (R x R) vec(I), row-major vec
    std = np.sqrt(np.clip(np.diag(K @ est.inertia_cov @ K.T), 0, None)).reshape(3, 3)
    G = np.eye(4)
    G[1:, 1:] = R
    source = "a motion's wrench" if hasattr(est, "sensor_bias") else "a motion's joint torques"
    return Payload(float(est.mass), R @ est.com_ee + T[:3, 3], 0.5 * (I_flange + I_flange.T),
                   flange, G @ est.cov @ G.T, "identified from a motion", None, std,
                   source)  # fmt: skip
