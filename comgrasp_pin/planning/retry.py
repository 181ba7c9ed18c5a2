"""Retrying a trial grasp that turned or fell: where to grasp next (pure, no simulator).

A careful trial grasp that sees the rod turn puts it down and tells which end went down:
the CoM lies on that side. The next grasp steps ``retry_shift`` of the rod's length that
way until the rod turns the other way, then bisects between the two last grasp points.
Positions ``s`` are counted along one world direction (the first heavy side seen), so a
rod seen turned by half a turn (its yaw is only known modulo pi) does not confuse them.

Which failures of a trial grasp are grasped again is a table, ``ON_FAILED_GRASP``, looked
up by the error's exact class (``on_failed_grasp``): a new kind of error is not retried
because it happens to derive from one that is, and a camera's failure is retried because
the table says so, not because it poses as a slip.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from comgrasp_pin.errors import HeldRodUnmeasuredError, RodDroppedError, RodSlippedError


@dataclass(frozen=True)
class OnFailedGrasp:
    """What a careful trial grasp's failure leads to.

    Attributes:
        grasp_again: grasp the rod again (towards the end that went down) while attempts
            remain; False: the episode fails with the error.
        laid_back: the trial grasp put the rod down itself (nothing to announce: the
            gripper only opens); False: the rod fell or is still in the jaws.
    """

    grasp_again: bool
    laid_back: bool


ON_FAILED_GRASP: dict[type[Exception], OnFailedGrasp] = {
    # fell out of the jaws (measured empty, lost from the side view, or at the rolled pose)
    RodDroppedError: OnFailedGrasp(grasp_again=True, laid_back=False),
    # turned as the careful lift began: put back where it was
    RodSlippedError: OnFailedGrasp(grasp_again=True, laid_back=True),
    # the side camera refused every frame of the held rod: laid back where it was grasped
    HeldRodUnmeasuredError: OnFailedGrasp(grasp_again=True, laid_back=True),
}
"""The failures of a trial grasp that are grasped again, by exact class; any other error
(perception of the table, IK, unstable physics, a bug) ends the attempt."""
GRASPED_AGAIN = tuple(ON_FAILED_GRASP)
"""The classes of ``ON_FAILED_GRASP``, for an ``except`` clause (``on_failed_grasp`` then
decides by the exact class)."""


def on_failed_grasp(exc: BaseException) -> OnFailedGrasp | None:
    """``ON_FAILED_GRASP``'s entry for ``exc``'s exact class, or None: not grasped again."""
    return ON_FAILED_GRASP.get(type(exc)) if isinstance(exc, Exception) else None


@dataclass(frozen=True)
class RetryState:
    """Where the CoM is known to be, along ``direction_world``.

    Attributes:
        direction_world: (3,) unit horizontal world direction positions are counted along,
            or None before any heavy side was seen.
        s: the next grasp point along it, from the rod's centre (m).
        below, above: the CoM lies beyond ``below`` and short of ``above`` (m), or None.
    """

    direction_world: np.ndarray | None = None
    s: float = 0.0
    below: float | None = None
    above: float | None = None


def grasp_offset(state: RetryState, rod_yaw: float) -> float:
    """The next grasp's offset (m) along a rod seen from above at ``rod_yaw`` (rad)."""
    if state.direction_world is None:
        return state.s
    d = np.array([np.cos(rod_yaw), np.sin(rod_yaw), 0.0])
    return state.s * float(np.sign(d @ state.direction_world) or 1.0)


def after_failure(
    state: RetryState, heavy_side_world: np.ndarray | None, rod_length: float, retry_shift: float
) -> RetryState:
    """The state after a grasp at ``state.s`` turned towards ``heavy_side_world`` ((3,), or
    None when nothing told which way: the same point is tried again)."""
    if heavy_side_world is None:
        return state
    heavy = np.asarray(heavy_side_world, dtype=float)
    u = heavy if state.direction_world is None else state.direction_world
    below, above = state.below, state.above
    if heavy @ u > 0:
        below = state.s
    else:
        above = state.s
    if below is not None and above is not None:
        s = 0.5 * (below + above)
    else:
        s = state.s + (1.0 if above is None else -1.0) * retry_shift * rod_length
    return replace(state, direction_world=u, s=s, below=below, above=above)


def heavy_side_from_tilt(
    largest_tilt: float | None, x_world_ee: np.ndarray, min_tilt: float
) -> np.ndarray | None:
    """(3,) unit horizontal world direction of the rod's end that went down, from the
    largest tilt the side camera saw (rad; None if it saw nothing) with the jaws' x axis at
    ``x_world_ee`` (3,): a positive tilt raises the ee +x end. None below ``min_tilt``."""
    if largest_tilt is None or abs(largest_tilt) < min_tilt:
        return None
    x = np.asarray(x_world_ee, dtype=float) * np.array([1.0, 1.0, 0.0])
    return -np.sign(largest_tilt) * x / np.linalg.norm(x)


def heavy_side_from_estimate(
    T_world_ee: np.ndarray, T_ee_obj: np.ndarray, x_com_obj: float, grasp_offset_obj: float
) -> np.ndarray:
    """(3,) unit horizontal world direction from the jaws towards the estimated CoM along
    the held rod (``T_ee_obj`` (4, 4); positions along the rod from its centre, m)."""
    x_world = T_world_ee[:3, :3] @ T_ee_obj[:3, 0] * np.array([1.0, 1.0, 0.0])
    side = np.sign(x_com_obj - grasp_offset_obj) or 1.0
    return side * x_world / max(np.linalg.norm(x_world), 1e-9)
