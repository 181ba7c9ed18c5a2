"""Payloads of known inertia, held rigidly in the ee frame: the ground truth of a motion test.

A ``Payload`` is a mass, its centre of mass ``p_com_ee`` and its inertia about the CoM
``I_com_ee``, all in the ee frame (the tool centre point of DESIGN section 3: ``eelink`` on
the UR5, ``panda_hand_tcp`` on the Panda). ``dynamic_parameters`` gives the same body as the
ten numbers a payload estimator returns, in Pinocchio's order.

The three test payloads are built from homogeneous solids (``Solid``) whose inertias are
textbook formulas; Pinocchio's ``Inertia`` sums them (the parallel-axis theorem). Pure
maths: nothing here imports MuJoCo (``tests/test_payload_motion.py`` compares these numbers
with the inertia MuJoCo compiles from the same solids).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from comgrasp_pin.errors import InvalidInputError

SHAPES = ("cylinder", "box", "sphere")
AXES = "xyz"
STEEL_DENSITY = 7850.0  # kg/m^3
ALUMINIUM_DENSITY = 2700.0  # kg/m^3


@dataclass(frozen=True)
class Solid:
    """A homogeneous solid, its axes parallel to the ee frame's.

    Attributes:
        shape: "cylinder", "box" or "sphere".
        size: cylinder (radius, length) (m); box (x, y, z) full side lengths along the ee
            axes (m); sphere (radius,) (m).
        mass: kg, > 0.
        p_centre_ee: (3,) its centre in the ee frame (m).
        axis: a cylinder's axis, "x", "y" or "z" of the ee frame (ignored for the others).
    """

    shape: str
    size: tuple[float, ...]
    mass: float
    p_centre_ee: tuple[float, float, float]
    axis: str = "z"

    def __post_init__(self) -> None:
        sizes = {"cylinder": 2, "box": 3, "sphere": 1}
        if self.shape not in SHAPES or len(self.size) != sizes[self.shape]:
            raise InvalidInputError(
                f"a Solid is one of {SHAPES} with {sizes} sizes; got {self.shape!r} "
                f"with size {self.size}"
            )
        if not (self.mass > 0 and min(self.size) > 0) or self.axis not in AXES:
            raise InvalidInputError(
                f"a Solid needs mass > 0, sizes > 0 and an axis in {tuple(AXES)}; got mass "
                f"{self.mass}, size {self.size}, axis {self.axis!r}"
            )

    def I_centre(self) -> np.ndarray:
        """(3, 3) inertia about its own centre, ee axes (kg m^2)."""
        m = self.mass
        if self.shape == "sphere":  # solid ball: 2/5 m r^2 about every axis
            return np.eye(3) * 0.4 * m * self.size[0] ** 2
        if self.shape == "box":  # I_xx = m (y^2 + z^2) / 12, and cyclically
            x2, y2, z2 = np.square(self.size)
            return np.diag([y2 + z2, x2 + z2, x2 + y2]) * m / 12.0
        # Solid cylinder: m r^2 / 2 about its axis, m (3 r^2 + L^2) / 12 across it.
        r, length = self.size
        diag = np.full(3, m * (3 * r**2 + length**2) / 12.0)
        diag[AXES.index(self.axis)] = m * r**2 / 2.0
        return np.diag(diag)


@dataclass(frozen=True, eq=False)
class Payload:
    """A rigid body held in the ee frame.

    Attributes:
        name: what it is ("rod", "box", "off_axis_weight", ...).
        mass: kg.
        p_com_ee: (3,) its centre of mass in the ee frame (m).
        I_com_ee: (3, 3) its inertia about the CoM, ee axes (kg m^2), symmetric positive
            definite.
        parts: the solids it was built from, or () for a body given by its numbers only.
    """

    name: str
    mass: float
    p_com_ee: np.ndarray
    I_com_ee: np.ndarray
    parts: tuple[Solid, ...] = ()

    def __post_init__(self) -> None:
        com = np.asarray(self.p_com_ee, dtype=float)
        inertia = np.asarray(self.I_com_ee, dtype=float)
        if not (self.mass > 0 and com.shape == (3,) and inertia.shape == (3, 3)):
            raise InvalidInputError(
                f"a Payload needs mass > 0 (kg), p_com_ee (3,) and I_com_ee (3, 3); got "
                f"{self.mass}, shapes {com.shape} and {inertia.shape}"
            )
        if not np.allclose(inertia, inertia.T) or np.linalg.eigvalsh(inertia)[0] <= 0:
            raise InvalidInputError(f"I_com_ee must be symmetric positive definite: {inertia}")
        object.__setattr__(self, "p_com_ee", com)
        object.__setattr__(self, "I_com_ee", inertia)

    @classmethod
    def from_parts(cls, name: str, parts: tuple[Solid, ...]) -> Payload:
        """The rigid union of ``parts`` (Pinocchio's Inertia sum: parallel-axis theorem)."""
        body = pin.Inertia.Zero()
        for part in parts:
            body += pin.Inertia(part.mass, np.asarray(part.p_centre_ee, float), part.I_centre())
        return cls(name, body.mass, body.lever.copy(), body.inertia.copy(), tuple(parts))

    def inertia(self) -> pin.Inertia:
        """The body as Pinocchio's spatial inertia, expressed at the ee frame's origin."""
        return pin.Inertia(self.mass, self.p_com_ee, self.I_com_ee)

    def dynamic_parameters(self) -> np.ndarray:
        """(10,) (m, m c_x, m c_y, m c_z, Ixx, Ixy, Iyy, Ixz, Iyz, Izz): mass (kg), first
        moments (kg m) and the inertia about the ee frame's origin (kg m^2), ee axes; the
        order of ``pin.Inertia.toDynamicParameters`` and of the payload regressor."""
        return self.inertia().toDynamicParameters()


def rod() -> Payload:
    """A steel rod of 0.6 kg and 0.3 m along ee x (a top-down grasp of a lying rod), held
    6 cm off its middle; radius 9 mm from the steel's density."""
    mass, length = 0.6, 0.3
    radius = float(np.sqrt(mass / (STEEL_DENSITY * np.pi * length)))
    return Payload.from_parts(
        "rod", (Solid("cylinder", (radius, length), mass, (0.06, 0.0, 0.0), axis="x"),)
    )


def box() -> Payload:
    """A 1.0 kg box, 0.15 x 0.10 x 0.20 m (x, y, z; the 0.10 m side between the jaws),
    gripped 2 cm into its top face, 1 cm off centre along x: it hangs along ee z."""
    return Payload.from_parts("box", (Solid("box", (0.15, 0.10, 0.20), 1.0, (0.01, 0.0, 0.08)),))


def off_axis_weight() -> Payload:
    """0.8 kg: a 0.7 kg steel ball (nearly a point mass, radius 2.8 cm) 8 cm to the side
    (ee x) and 2 cm across (ee y) on a light 0.1 kg aluminium plate gripped at one end."""
    ball_mass = 0.7
    radius = float(np.cbrt(3 * ball_mass / (4 * np.pi * STEEL_DENSITY)))
    return Payload.from_parts(
        "off_axis_weight",
        (
            Solid("box", (0.14, 0.04, 0.0066), 0.1, (0.05, 0.0, 0.015)),
            Solid("sphere", (radius,), ball_mass, (0.08, 0.02, 0.015 + 0.0033 + radius)),
        ),
    )


def reference_payloads() -> tuple[Payload, Payload, Payload]:
    """The three payloads of the motion tests: rod, box, off-axis weight (all >= 0.5 kg)."""
    return rod(), box(), off_axis_weight()
