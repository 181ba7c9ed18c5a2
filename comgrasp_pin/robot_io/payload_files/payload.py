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

import numpy as np
import pinocchio as pin

from comgrasp_pin import validate
from comgrasp_pin.errors import InvalidInputError
from comgrasp_pin.estimation.trust import IDENTIFIED, require_identified
from comgrasp_pin.robot import RobotModel
from comgrasp_pin.robot_io.results.estimate_result import PayloadEstimate

_AXES = {"x": 0, "y": 1, "z": 2}
INERTIA_HELP = (
    "point | cylinder:L,R,AXIS (L, R in m; AXIS x, y or z of the ee frame) | box:X,Y,Z (edge "
    "lengths in m along the ee frame's axes)"
)


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
        source: what it was estimated from, for the files' notes (``PayloadEstimate.mode``:
            "joint_torques at rest", "a motion's wrench and joint torques", ...).
        verdict: the estimate's verdict (``trust``), or None for a payload given by hand;
            reasons: its reasons. Every file's header states a verdict other than
            ``identified``.
        inertia_note: why an approximation stands for the inertia, where a motion was given.
    """

    mass: float
    com_flange: np.ndarray
    inertia_flange: np.ndarray
    flange_frame: str
    cov: np.ndarray | None
    inertia_model: str
    unobservable_flange: np.ndarray | None = None
    inertia_std_flange: np.ndarray | None = None
    source: str = "joint torques at rest"
    verdict: str | None = None
    reasons: tuple[str, ...] = ()
    inertia_note: str = ""

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


def header_lines(p: Payload) -> list[str]:
    """The notes every payload file starts with: what made it, its inertia, its std.

    A payload whose verdict is not ``identified`` (written on request, ``anyway``) says so
    first, with the verdict's reasons, and is never called identified.
    """
    trusted = p.verdict in (None, IDENTIFIED)
    if p.verdict is None:
        lines = [f"payload given to comgrasp_pin; frame {p.flange_frame}"]
    elif trusted:
        lines = [f"payload identified by comgrasp_pin from {p.source}; frame {p.flange_frame}"]
    else:
        lines = [
            f"NOT FOR USE WITHOUT CHECKING: comgrasp_pin's verdict on this payload is "
            f"{p.verdict!r}; written on request (--export-anyway)",
            *(f"reason: {r}" for r in p.reasons),
            f"payload estimated by comgrasp_pin from {p.source}; frame {p.flange_frame}",
        ]
    if p.inertia_std_flange is None:
        why = p.inertia_note or "readings at rest do not see inertia"
        lines.append(f"inertia: {p.inertia_model} approximation about the CoM, flange axes "
                     f"({why})")  # fmt: skip
    else:
        s = ", ".join(f"{v:.9g}" for v in six_components(p.inertia_std_flange))
        word = "identified" if trusted else "fitted to the motion"
        lines.append(f"inertia: {word}, about the CoM, flange axes; 1-sigma [Ixx, Iyy, Izz, Ixy, "
                     f"Ixz, Iyz] [{s}] kg m^2")  # fmt: skip
    std = p.std
    if std is not None:
        lines.append(
            f"1-sigma: mass {std[0]:.4g} kg, CoM {np.array2string(1e3 * std[1:], precision=3)} mm"
        )
    if p.unobservable_flange is not None:
        u = np.array2string(p.unobservable_flange, precision=4)
        lines.append(f"the CoM along {u} (gravity at the single pose) was not observed: 0")
    return lines


def six_components(I: np.ndarray) -> list[float]:
    """[Ixx, Iyy, Izz, Ixy, Ixz, Iyz] of a symmetric 3x3 inertia."""
    return [float(I[0, 0]), float(I[1, 1]), float(I[2, 2]),
            float(I[0, 1]), float(I[0, 2]), float(I[1, 2])]  # fmt: skip


def T_flange_ee(robot: RobotModel, flange_frame: str) -> np.ndarray:
    """(4, 4) the ee frame's pose in the flange frame, from the URDF (fixed joints only)."""
    return robot.T_frame_ee(flange_frame, "flange frame")


def _positive(parts: list[str], count: int, spec: str) -> list[float]:
    """``count`` lengths > 0 (m) of an inertia spec, or InvalidInputError naming it."""
    try:
        values = [float(v) for v in parts]
    except ValueError:
        raise InvalidInputError(f"inertia {spec!r}: lengths must be numbers (m)") from None
    if len(values) != count or not all(v > 0 and np.isfinite(v) for v in values):
        raise InvalidInputError(f"inertia {spec!r}: {count} lengths > 0 (m) expected; valid "
                                f"are {INERTIA_HELP}")  # fmt: skip
    return values


def inertia_about_com(mass: float, spec: str) -> tuple[np.ndarray, str, int | None]:
    """(3, 3) inertia about the CoM in the ee axes for ``spec``, the spec, the axis index."""
    spec = spec.strip()
    if spec == "point":
        return np.zeros((3, 3)), "point", None
    kind, _, rest = spec.partition(":")
    parts = rest.split(",")
    if kind == "box":
        sides = _positive(parts, 3, spec)
        I_box = pin.Inertia.FromBox(mass, *sides).inertia
        return I_box, f"box:{sides[0]:g},{sides[1]:g},{sides[2]:g}", None
    if kind != "cylinder" or len(parts) != 3 or parts[2].strip() not in _AXES:
        raise InvalidInputError(f"inertia {spec!r}: valid are {INERTIA_HELP}")
    length, radius = _positive(parts[:2], 2, spec)
    axis = _AXES[parts[2].strip()]
    I_z = pin.Inertia.FromCylinder(mass, radius, length).inertia  # cylinder along z
    perm = np.roll(np.arange(3), 2 - axis)  # the cylinder's z onto the chosen axis
    P = np.eye(3)[:, perm]
    return P @ I_z @ P.T, f"cylinder:{length:g},{radius:g},{parts[2].strip()}", axis


def payload_in_flange(
    robot: RobotModel,
    est: PayloadEstimate,
    flange_frame: str | None = None,
    inertia: str = "point",
    anyway: bool = False,
) -> Payload:
    """``est`` (CoM in the ee frame) for a controller, in ``flange_frame`` (default: ee).

    Args:
        robot: the arm the estimate was made with.
        est: any payload estimate.
        flange_frame: the frame the controller's payload refers to (module docstring).
        inertia: the inertia's approximation (``INERTIA_HELP``), used where no motion
            determined it (``est.inertia`` None or its verdict not ``identified``).
        anyway: make it although the verdict is not ``identified``; the payload then
            carries the verdict and its reasons, which every file's header states.

    Raises:
        NotIdentifiedError: the verdict is not ``identified`` and not ``anyway``.
    """
    require_identified(est.verdict, est.reasons, anyway)
    flange = flange_frame or robot.ee_frame
    T = T_flange_ee(robot, flange)
    R = T[:3, :3]
    G = np.eye(4)
    G[1:, 1:] = R
    cov = None if est.cov is None else G @ est.cov @ G.T
    u = None if est.unobservable_ee is None else R @ est.unobservable_ee
    std_flange = None
    if est.inertia is not None and est.inertia.verdict == IDENTIFIED:
        I_ee, model = est.inertia.inertia_com_ee, "identified from a motion"
        K = np.kron(R, R)  # vec(R I R^T) = (R x R) vec(I), row-major vec
        var = np.diag(K @ est.inertia.inertia_cov @ K.T)
        std_flange = np.sqrt(np.clip(var, 0, None)).reshape(3, 3)
    else:
        I_ee, model, _ = inertia_about_com(est.mass, inertia)
    note = ""
    if est.inertia is not None and std_flange is None:
        note = "the motion did not determine the inertia; this one was chosen (--inertia)"
    I_flange = R @ I_ee @ R.T
    return Payload(float(est.mass), R @ est.com_ee + T[:3, 3], 0.5 * (I_flange + I_flange.T),
                   flange, cov, model, u, std_flange, est.mode, est.verdict,
                   tuple(est.reasons), note)  # fmt: skip
