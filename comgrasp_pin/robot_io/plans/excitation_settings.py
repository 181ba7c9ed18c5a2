"""The numbers that tune an excitation motion and its search, and their ranges.

``ExcitationSettings`` holds them (units in the names; what each does: ``excitation``);
``checked_settings`` refuses one out of its range, naming it.
"""

from __future__ import annotations

from dataclasses import dataclass

from comgrasp_pin import validate


@dataclass(frozen=True)
class ExcitationSettings:
    """Every number that tunes the motion and its search (units in the names; see module).

    ``periods`` repetitions of the fundamental period fill the duration; ``harmonics`` per
    period. Limits: ``velocity_scale`` of the URDF's, ``acceleration_limit`` (rad/s^2 or
    m/s^2, every joint), ``position_margin_rad`` inside the URDF's. The joints before the
    wrist keep ``arm_range_rad`` and ``arm_rate_scale`` of the velocity and acceleration
    limits. Search: ``samples_per_period`` grid points, ``n_random`` random motions,
    ``n_starts`` IPOPT refinements of ``max_iter`` iterations each, checked for collisions every
    ``check_every_iter`` iterations.

    The defaults are measured (``benchmarks/inertia_from_motion.py``): a payload's inertia
    shows in its torques in proportion to the accelerations, which a velocity limit caps at
    v * omega, so four 5 s periods at 0.8 of the URDF's velocity reach them where two 10 s
    periods at 0.5 do not (UR5: condition number 270 -> 72, moments off by up to 44 % ->
    within 10 %). 7.5 rad/s^2 is the Franka Panda's smallest joint acceleration limit
    (joint 2, Franka's data sheet); a UR arm's wrists allow more (``--acceleration 12``).
    """

    periods: int = 4
    harmonics: int = 5
    velocity_scale: float = 0.8
    acceleration_limit: float = 7.5
    position_margin_rad: float = 0.1
    wrist_joints: int = 3
    wrist_range_rad: float = 1.5
    arm_range_rad: float = 0.3
    arm_rate_scale: float = 1.0
    min_height_m: float = 0.05
    typical_length_m: float = 0.1
    sample_period_s: float = 0.01
    samples_per_period: int = 100
    n_random: int = 1000
    n_starts: int = 3
    max_iter: int = 60
    check_every_iter: int = 10


def checked_settings(s: ExcitationSettings) -> ExcitationSettings:
    """``s`` if every number is in its range, else InvalidInputError naming the field."""
    for name in ("velocity_scale", "acceleration_limit", "wrist_range_rad", "typical_length_m",
                 "sample_period_s", "arm_rate_scale"):  # fmt: skip
        validate.number(getattr(s, name), name, low=0, low_open=True)
    for name in ("position_margin_rad", "arm_range_rad", "min_height_m"):
        validate.number(getattr(s, name), name, low=0)
    validate.number(s.velocity_scale, "velocity_scale", high=1)
    validate.number(s.arm_rate_scale, "arm_rate_scale", high=1)
    for name, low in (("periods", 1), ("harmonics", 2), ("wrist_joints", 1),
                      ("samples_per_period", 10), ("n_random", 1), ("n_starts", 1),
                      ("max_iter", 0), ("check_every_iter", 1)):  # fmt: skip
        validate.integer(getattr(s, name), name, low=low)
    return s
