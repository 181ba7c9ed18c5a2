"""The baseline an excitation motion should beat: random motions of the same family.

Random rest-to-rest Fourier motions (standard normal free coefficients) about the same start,
each joint scaled to its tightest limit, with the limits, duration and sample grid of
``excitation.plan_excitation``; those that collide or dip below the floor are drawn again.
"""

from __future__ import annotations

import numpy as np

from comgrasp_pin.errors import CollisionError
from comgrasp_pin.estimation.payload_regressor import (
    condition_number,
    parameter_scale,
    payload_regressor,
)
from comgrasp_pin.motion.fourier import FourierMotion
from comgrasp_pin.planning.collision import SelfCollision
from comgrasp_pin.planning.excitation import (
    MAX_DURATION_S,
    ExcitationSettings,
    default_start,
    excitation_limits,
    within_limits,
)
from comgrasp_pin.planning.excitation_search import Grid, random_motions
from comgrasp_pin.planning.measurement_poses import feasible
from comgrasp_pin.robot import RobotModel


def random_condition_numbers(
    robot: RobotModel,
    duration_s: float = MAX_DURATION_S,
    start: np.ndarray | None = None,
    settings: ExcitationSettings | None = None,
    count: int = 20,
    seed: int = 1,
    srdf: str | None = None,
) -> np.ndarray:
    """(count,) scaled condition numbers of random motions: the baseline a plan should beat.

    Motions of the same family, length and limits as ``plan_excitation``'s (each joint
    scaled to its tightest limit), free of collision and of the floor, on the same grid.

    Raises:
        CollisionError: fewer than ``count`` of ``50 count`` random motions are free.
    """
    s = settings or ExcitationSettings()
    checker = SelfCollision(robot, srdf)
    start = default_start(robot, checker) if start is None else robot.check_q(start)
    lim = excitation_limits(robot, start, s)
    period_s = duration_s / s.periods
    scale = parameter_scale(s.typical_length_m)
    grid = Grid(robot, start, period_s, s.harmonics, s.samples_per_period, scale)
    t = np.linspace(0.0, duration_s, int(round(duration_s / s.sample_period_s)) + 1)
    rng = np.random.default_rng(seed)
    conds: list[float] = []
    for _ in range(50 * count):
        series = within_limits(
            FourierMotion.from_free(start, random_motions(grid, lim, 1, rng)[0], period_s), t, lim
        )
        q, qd, qdd = series.evaluate(t)
        if all(feasible(robot, checker, qi, s.min_height_m) for qi in q):
            conds.append(condition_number(payload_regressor(robot, q, qd, qdd), scale))
        if len(conds) == count:
            return np.array(conds)
    raise CollisionError(f"only {len(conds)} random motions of {50 * count} are free")
