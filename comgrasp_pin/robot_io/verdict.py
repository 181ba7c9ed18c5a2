"""Whether a motion's payload estimate can be trusted: a verdict and its reasons.

A pure function of the estimate's checks, so that each rule is tested on its own. The
verdict is ``identified`` when no rule objects, ``unreliable`` otherwise, with one reason
per rule that objects, each saying what would help.
"""

from __future__ import annotations

from dataclasses import dataclass

Z95 = 1.959963984540054
"""The two-sided 95 % quantile of the standard normal."""
MIN_EXPLAINED = 0.8
"""Smallest share of the held-out torque difference the payload must explain. Below it the
torques carry more than a rigid payload: an arm model or friction that does not hold, a
payload that moves in the gripper, a gain that is wrong."""
MAX_HALVES_Z = 3.0
"""The two halves of the motion may differ in mass by this many of their difference's std."""

IDENTIFIED, UNRELIABLE = "identified", "unreliable"


@dataclass(frozen=True)
class Checks:
    """What the verdict weighs.

    Attributes:
        mass_kg, mass_std_kg: the estimate and its std from every modelled source.
        arm_model: "empty run", "identified arm model" or "URDF model + friction".
        explained: share of the held-out torque difference the payload explains.
        halves_mass_kg: (m1, m2), each half of the motion fitted alone.
        halves_diff_std_kg: std of m1 - m2 (data and gains).
    """

    mass_kg: float
    mass_std_kg: float
    arm_model: str
    explained: float
    halves_mass_kg: tuple[float, float]
    halves_diff_std_kg: float


def verdict(c: Checks) -> tuple[str, list[str]]:
    """(``identified`` or ``unreliable``, reasons): every rule that objects gives one.

    Where no payload is seen (the mass's interval holds 0, or lies below it) the rules about
    the payload's fit (the share explained, the halves) are not asked: there is no payload
    to explain, and their reasons would blame a model that may be right.
    """
    reasons = []
    payload_seen = c.mass_kg - Z95 * c.mass_std_kg > 0
    if c.mass_kg + Z95 * c.mass_std_kg < 0:
        reasons.append(
            f"the mass comes out negative ({c.mass_kg:.3f} +- {Z95 * c.mass_std_kg:.3f} kg): "
            "the arm's own model predicts more torque than the arm needs; identify the arm "
            "(comgrasp identify-arm) or record an empty run of the same motion"
        )
    elif c.mass_kg - Z95 * c.mass_std_kg <= 0:
        reasons.append(
            f"no payload seen: the mass's 95 % interval ({c.mass_kg:.3f} +- "
            f"{Z95 * c.mass_std_kg:.3f} kg) holds 0"
        )
    if c.arm_model.startswith("URDF"):
        reasons.append(
            "the arm's own torques are the URDF's nominal model, whose error on this arm is "
            "not known (a real arm's can read as a payload of a kilogram): give an empty "
            "run of the same motion (--empty-csv/--empty-bag) or an identified arm model "
            "(comgrasp identify-arm, then --arm-model)"
        )
    if payload_seen and c.explained < MIN_EXPLAINED:
        reasons.append(
            f"the payload explains {100 * c.explained:.0f} % of the held-out torque "
            f"difference (at least {100 * MIN_EXPLAINED:.0f} % expected): the torques hold "
            "more than a rigid payload (an arm model or friction that does not hold, wrong "
            "gains, a payload moving in the gripper)"
        )
    m1, m2 = c.halves_mass_kg
    z = abs(m1 - m2) / max(c.halves_diff_std_kg, 1e-300)
    if payload_seen and z > MAX_HALVES_Z:
        reasons.append(
            f"the motion's two halves disagree: {m1:.3f} and {m2:.3f} kg, {z:.1f} std apart "
            f"(at most {MAX_HALVES_Z:g}): an error the model leaves out changes along the "
            "motion (gains, friction, the arm model)"
        )
    return (UNRELIABLE if reasons else IDENTIFIED), reasons
