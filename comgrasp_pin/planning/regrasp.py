"""The regrasp planner: decide from what the trial grasp showed, and where to grasp again.

Pure geometry (no simulator): it works on a real robot's measurements as well.

Decision (documented choice): put the rod down and grasp it again when slip was seen (the
side camera saw the tilt change, or the rod hangs tilted by more than ``slip_tilt_deg``), or
when the estimated CoM lies more than ``max_com_offset`` from the jaws along the rod even
though nothing slipped yet (the transport's accelerations add to the gravity moment, so an
off-centre grasp that holds at rest may still slip on the way).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from comgrasp_pin.config import RegraspConfig
from comgrasp_pin.errors import InvalidInputError, UnobservableError
from comgrasp_pin.geometry import GraspPose
from comgrasp_pin.planning.holding import holding_lever


@dataclass(frozen=True)
class RegraspDecision:
    """What the planner decided.

    Attributes:
        regrasp: True to put the rod down and grasp it at the CoM.
        reason: a short human-readable reason.
        x_com_obj: estimated CoM along the rod from its geometric centre (m).
        grasp_offset_obj: where the jaws held the rod, along it from its centre (m).
    """

    regrasp: bool
    reason: str
    x_com_obj: float
    grasp_offset_obj: float


def decide(
    theta: float,
    slip_seen: bool,
    x_com_obj: float,
    grasp_offset_obj: float,
    config: RegraspConfig,
) -> RegraspDecision:
    """Regrasp decision from the tilt ``theta`` (rad), the slip monitor's verdict, and the
    estimated CoM and grasp positions along the rod (m), with the thresholds of
    ``config`` (``slip_tilt_deg``, ``max_com_offset``)."""
    values = np.array([theta, x_com_obj, grasp_offset_obj], dtype=float)
    if not np.all(np.isfinite(values)):
        raise InvalidInputError(f"non-finite planner input: theta, x_com, grasp_offset = {values}")
    offset = abs(x_com_obj - grasp_offset_obj)
    if slip_seen:
        reason = "slip seen by the side camera"
    elif abs(np.degrees(theta)) > config.slip_tilt_deg:
        reason = f"rod hangs tilted by {np.degrees(theta):.1f} deg"
    elif offset > config.max_com_offset:
        reason = f"CoM {1e3 * offset:.0f} mm from the jaws"
    else:
        return RegraspDecision(False, "grasp holds near the CoM", x_com_obj, grasp_offset_obj)
    return RegraspDecision(True, reason, x_com_obj, grasp_offset_obj)


def needs_another_pose(
    x_com_std: float, mass: float, grip_force: float, config: RegraspConfig
) -> bool:
    """Whether the CoM is known too poorly for a regrasp at it to hold: its standard
    deviation along the rod (m) above ``holding_margin`` of the jaws' holding lever for a
    payload of ``mass`` (kg) at ``grip_force`` (N per finger, pads as the robot knows them:
    ``pad_friction``), over 1.96 (a 95 % miss stays within that share of the lever).
    An unknown std (NaN) counts as too large."""
    lever = holding_lever(mass, grip_force, config.pad_friction)
    tolerance = config.holding_margin * lever / 1.96
    return not (x_com_std <= tolerance)


def rod_axis_world(T_world_ee: np.ndarray, T_ee_obj: np.ndarray) -> np.ndarray:
    """(3,) unit horizontal direction of the rod's +x axis in the world, from a held rod."""
    axis = T_world_ee[:3, :3] @ T_ee_obj[:3, 0]
    horizontal = np.array([axis[0], axis[1], 0.0])
    norm = np.linalg.norm(horizontal)
    if norm < 1e-6:
        raise UnobservableError(
            "the rod's axis is vertical: its direction on the table is undefined"
        )
    return horizontal / norm


def com_grasp(
    rod: GraspPose,
    axis_hint_world: np.ndarray,
    x_com_obj: float,
    nearest_graspable: Callable[[float], float] | None = None,
) -> GraspPose:
    """Top-down grasp at the CoM of a rod lying on the table.

    Args:
        rod: the rod's centre and yaw as seen from the top camera (yaw defined modulo pi).
        axis_hint_world: (3,) direction of the rod's +x axis (its orientation is ambiguous
            in a top view; this resolves it, e.g. ``rod_axis_world`` before putting it down).
        x_com_obj: CoM along +x from the centre (m).
        nearest_graspable: maps a position along the rod (m from its centre, towards
            +yaw) to the nearest one the jaws can close on (a head or a blade may be too
            wide); the grasp then goes there, as near the CoM as the object allows.
    """
    d = np.array([np.cos(rod.yaw), np.sin(rod.yaw), 0.0])
    s = x_com_obj if d @ np.asarray(axis_hint_world, dtype=float) >= 0.0 else -x_com_obj
    if nearest_graspable is not None:
        s = nearest_graspable(s)
    return GraspPose(rod.x + s * d[0], rod.y + s * d[1], rod.z, rod.yaw)
