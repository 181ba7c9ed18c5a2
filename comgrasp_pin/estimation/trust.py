"""When a payload estimate can be trusted: one set of rules, and the payload files' gate.

One set of rules for every source, and the gate that every payload file passes.

Pure functions, each rule tested on its own. The mass and CoM get one verdict (DESIGN.md 4f):

- ``identified``: no rule objects;
- ``nothing held``: the mass's 95 % interval holds 0 and nothing else objects;
- ``unreliable``: any rule objects (one reason per rule, saying what would help).

The rules every mode shares (``judge``): the result must be finite and have an uncertainty;
a payload heavier than the arm that holds it is a unit's mistake, not a payload; a mass
whose interval lies below 0 means the arm's own model is wrong. A mode adds its own findings
as reasons: along a motion ``motion_reasons`` (the arm's model, the share of the held-out
readings explained, the two halves), at rest a fit's residuals. The inertia a motion gives
has its own verdict (``inertia_verdict``).

A controller's payload file is written only for ``identified`` (``require_identified``);
the caller may insist (``--export-anyway``, ``anyway=True``), and the file then states the
verdict and its reasons.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from comgrasp_pin.errors import NotIdentifiedError

Z95 = 1.959963984540054
"""The two-sided 95 % quantile of the standard normal: a variance known, or estimated from
so many readings that Student's t is the normal (``t95`` of infinite degrees of freedom)."""
MIN_EXPLAINED = 0.8
"""Smallest share of the held-out readings the payload must explain. Below it they carry
more than a rigid payload: an arm model or friction that does not hold, a payload that moves
in the gripper, a gain that is wrong, a cable pulling on the sensor."""
MAX_HALVES_Z = 3.0
"""The two halves of the motion may differ in mass by this many of their difference's std."""

IDENTIFIED, NOTHING_HELD, UNRELIABLE = "identified", "nothing held", "unreliable"
NOT_FINITE = (
    "the result is not finite (NaN or inf in the mass, the CoM or their covariance): the "
    "readings do not determine a payload; check the log for damaged samples"
)
NOT_DETERMINED = "not determined"
"""The inertia's verdict where the motion did not determine it."""


@dataclass(frozen=True)
class Checks:
    """What a motion's own rules weigh.

    Attributes:
        mass_kg, mass_std_kg: the estimate and its std from every modelled source.
        arm_model: "empty run", "identified arm model" or "URDF model + friction" for the
            joint torques; None for a wrench alone (no arm in its readings).
        explained: share of the held-out readings the payload explains.
        halves_mass_kg: (m1, m2), each half of the motion fitted alone.
        halves_diff_std_kg: std of m1 - m2 (data and gains).
    """

    mass_kg: float
    mass_std_kg: float
    arm_model: str | None
    explained: float
    halves_mass_kg: tuple[float, float]
    halves_diff_std_kg: float


def t_quantile(dof, coverage: float):
    """The two-sided ``coverage`` quantile of Student's t with ``dof`` degrees of freedom.

    A variance estimated from few blocks or windows is itself uncertain: with nu degrees of
    freedom, (estimate - truth) / std follows Student's t. Infinite ``dof``: the normal's.
    ``dof`` a number or an array.
    """
    from scipy.stats import norm, t

    dof = np.asarray(dof, dtype=float)
    p = 0.5 + coverage / 2
    q = np.where(np.isfinite(dof), t.ppf(p, np.where(np.isfinite(dof), dof, 1.0)), norm.ppf(p))
    return float(q) if q.ndim == 0 else q


def t95(dof):
    """The 95 % quantile (``t_quantile``): 2.23 at nu = 10, 2.09 at 20, ``Z95`` at infinity."""
    return t_quantile(dof, 0.95)


def payload_seen(mass: float, mass_std: float, q: float = Z95) -> bool:
    """True where the mass's 95 % interval (half-width ``q`` std) lies above 0."""
    return mass - q * mass_std > 0


def motion_reasons(c: Checks) -> list[str]:
    """A motion's own objections: the arm's model, the share explained, the halves.

    Where no payload is seen the rules about the payload's fit are not asked: there is no
    payload to explain, and their reasons would blame a model that may be right.
    """
    reasons = []
    seen = payload_seen(c.mass_kg, c.mass_std_kg)
    if c.arm_model is not None and c.arm_model.startswith("URDF"):
        reasons.append(
            "the arm's own torques are the URDF's nominal model, whose error on this arm is "
            "not known (a real arm's can read as a payload of a kilogram): give an empty "
            "run of the same motion (--empty-csv/--empty-bag) or an identified arm model "
            "(comgrasp identify-arm, then --arm-model)"
        )
    if seen and c.explained < MIN_EXPLAINED:
        reasons.append(unexplained_reason(c.explained, "held-out readings"))
    m1, m2 = c.halves_mass_kg
    z = abs(m1 - m2) / max(c.halves_diff_std_kg, 1e-300)
    if seen and z > MAX_HALVES_Z:
        reasons.append(
            f"the motion's two halves disagree: {m1:.3f} and {m2:.3f} kg, {z:.1f} std apart "
            f"(at most {MAX_HALVES_Z:g}): an error the model leaves out changes along the "
            "motion (gains, friction, the arm model)"
        )
    return reasons


def unexplained_reason(explained: float, what: str) -> str:
    """The reason where the payload explains less than MIN_EXPLAINED of ``what``."""
    return (
        f"the payload explains {100 * explained:.0f} % of the {what} (at least "
        f"{100 * MIN_EXPLAINED:.0f} % expected): they hold more than a rigid payload (an arm "
        "model or friction that does not hold, wrong gains, a payload moving in the gripper, "
        "a contact or a cable)"
    )


def nominal_tool_reasons(nominal: bool, tool_mass_kg: float) -> list[str]:
    """A wrist sensor's tool taken from the URDF's links beyond it, at rest or in motion.

    Its error on the real tool is not known and goes straight into the payload (a gripper 3 %
    heavier than its URDF reads as a payload of tens of grams, tens of std away), so it is an
    objection wherever a tool of some mass was subtracted that way.
    """
    if not nominal or tool_mass_kg <= 0:
        return []
    return [
        f"the tool's own wrench is the URDF's links beyond the sensor ({tool_mass_kg:.3f} kg), "
        "whose error on this tool is not known and goes into the payload: identify the tool "
        "once with nothing held (at rest: --keep-tool, then --tool TOOL.json; from a motion: "
        "an empty run of any motion, --empty-csv/--empty-bag) or give its parameters"
    ]


def judge(
    mass: float,
    com_ee: np.ndarray,
    cov: np.ndarray | None,
    arm_mass_kg: float,
    findings: list[str] | tuple[str, ...] = (),
    q: float = Z95,
) -> tuple[str, tuple[str, ...]]:
    """(verdict, reasons) of a mass and CoM: the shared rules, then the mode's ``findings``.

    Args:
        mass: the estimate (kg).
        com_ee: (3,) its CoM (m).
        cov: (4, 4) the covariance of (mass, com_ee), or None.
        arm_mass_kg: the mass of the arm that holds it (its URDF's links).
        findings: the mode's own objections (``motion_reasons``, a fit's residuals).
        q: the mass's 95 % quantile (``t95`` of its variance's degrees of freedom).
    """
    if not np.isfinite(mass) or (cov is not None and not np.isfinite(cov[0, 0])):
        return UNRELIABLE, (NOT_FINITE, *findings)
    if cov is None:
        return UNRELIABLE, (
            "no uncertainty: as many readings as unknowns, so nothing shows the noise; give "
            "the sensor's noise (--torque-std) or more poses",
            *findings,
        )
    reasons = []
    if mass > arm_mass_kg:
        reasons.append(
            f"the payload ({mass:.4g} kg) is heavier than the arm that holds it ({arm_mass_kg:.4g}"
            " kg in its URDF): are the readings in the units expected (N, N m, A)? A force "
            "logged in mN or a torque in N mm reads 1000 times too heavy"
        )
    std = float(np.sqrt(max(cov[0, 0], 0.0)))
    if mass + q * std < 0:
        reasons.append(
            f"the mass comes out negative ({mass:.3f} +- {q * std:.3f} kg): the model of "
            "what the sensor carries besides the payload predicts more than it measures: "
            "identify the arm (comgrasp identify-arm) or record an empty run (with a wrist "
            "sensor: identify the tool, --keep-tool then --tool)"
        )
    reasons += list(findings)
    if not payload_seen(mass, std, q):
        if mass + q * std < 0:
            return UNRELIABLE, tuple(reasons)
        nothing = (f"no payload seen: the mass's 95 % interval ({mass:.3f} +- {q * std:.3f} "
                   "kg) holds 0")  # fmt: skip
        return (UNRELIABLE if reasons else NOTHING_HELD), (nothing, *reasons)
    if not (np.all(np.isfinite(com_ee)) and np.all(np.isfinite(cov))):
        reasons.insert(0, NOT_FINITE)
    return (UNRELIABLE if reasons else IDENTIFIED), tuple(reasons)


def principal_moments(inertia: np.ndarray, inertia_cov: np.ndarray):
    """((3,) principal moments (kg m^2), (3, 3) axes as columns, (3,) each moment's std).

    A moment's std is the inertia's covariance projected on u u^T (u its axis).
    """
    moments, axes = np.linalg.eigh(inertia)
    std = np.array([np.sqrt(max(np.kron(u, u) @ inertia_cov @ np.kron(u, u), 0.0))
                    for u in axes.T])  # fmt: skip
    return moments, axes, std


def inertia_verdict(
    inertia: np.ndarray, inertia_cov: np.ndarray, q: float = Z95
) -> tuple[str, tuple[str, ...]]:
    """(``identified`` or ``not determined``, reasons) of a motion's inertia about the CoM.

    ``q``: the moments' 95 % quantile (``t95``). Determined where every principal moment's 95 %
    half-width is below the largest moment: the tensor is then known to better than its own
    size. (A thin rod's smallest moment is near 0 and need not be resolved; one of 1e-3 kg m^2
    known to +-0.1 is not known.)
    """
    moments, _, std = principal_moments(inertia, inertia_cov)
    largest = float(np.max(moments))
    if np.all(np.isfinite(std)) and np.all(q * std < largest):
        return IDENTIFIED, ()
    text = " ".join(f"{m:.2g} +- {h:.2g}" for m, h in zip(moments, q * std))
    return NOT_DETERMINED, (
        f"the motion did not determine the inertia: principal moments (95 %) {text} kg m^2; "
        "excite the wrist more (comgrasp plan-motion) or give the inertia (--inertia)",
    )


def require_identified(verdict: str, reasons, anyway: bool = False) -> None:
    """Refuse to write a controller's payload file for a verdict other than ``identified``.

    Raises:
        NotIdentifiedError: unless ``verdict`` is ``identified`` or ``anyway`` is set.
    """
    if verdict == IDENTIFIED or anyway:
        return
    raise NotIdentifiedError(
        f"no payload file written: the verdict is {verdict!r}: "
        + "; ".join(reasons)
        + ". To write them anyway (their header then states this verdict), give "
        "--export-anyway (Python: anyway=True)"
    )


def arm_mass(robot) -> float:
    """The mass of the arm's model (kg): every link's of its URDF."""
    return float(sum(inertia.mass for inertia in robot.model.inertias[1:]))
