"""Laying a held rod down to grasp it again (pure geometry, no simulator).

A rod hanging tilted in the jaws is laid down as a person would: lowered until its low end
nearly touches the table, then the jaws move down and away from that end together, so that
the rod pivots on it and comes to lie flat where it is (lowering it straight down would push
it through the jaws and topple it). Only what the side camera measured is used (the rod's
axis and centre in the jaws, its length from the top view).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from comgrasp_pin.config import RegraspConfig
from comgrasp_pin.errors import UnobservableError
from comgrasp_pin.motion.ik import grasp_height, top_down_frame


@dataclass(frozen=True)
class PutDownPlan:
    """The poses of a put-down, all (4, 4) T_world_ee, top-down.

    Attributes:
        T_above: above the put-down spot, at the current height.
        T_touch: lowered until the rod's low end nearly touches the table.
        T_flat: moved along ee-x and down so that the rod lies flat, where the jaws open.
        p_pivot: (3,) the low end at ``T_touch`` (world, m): the rod pivots about it; its
            x, y is where that end stays as the rod lies down.
        low_is_plus: the low end is the rod's +x end (obj frame).
    """

    T_above: np.ndarray
    T_touch: np.ndarray
    T_flat: np.ndarray
    p_pivot: np.ndarray
    low_is_plus: bool


def plan_put_down(
    T_world_ee: np.ndarray,
    T_ee_obj: np.ndarray,
    rod_length: float,
    grasp_offset_obj: float,
    rod_axis_z: float,
    put_down_xy: tuple[float, float],
    config: RegraspConfig,
) -> PutDownPlan:
    """Put-down of a rod held at ``T_ee_obj`` (side view) with the jaws at ``T_world_ee``,
    laying it along the table's long side (world y) with its centre at ``put_down_xy``.

    ``grasp_offset_obj``: where the jaws hold the rod, from its centre (m);
    ``rod_axis_z``: height of the rod's axis lying on the table (top view, m).
    """
    yaw = np.pi / 2 if T_world_ee[1, 0] >= 0 else -np.pi / 2  # the nearer of the two
    x_axis, centre = T_ee_obj[:3, 0], T_ee_obj[:3, 3]
    ends = [centre + s * 0.5 * rod_length * x_axis for s in (-1.0, 1.0)]
    low = max(ends, key=lambda e: e[2])  # ee z points down
    low_is_plus = bool((low - centre) @ x_axis > 0)
    reach = float(np.hypot(low[0], low[2]))  # TCP to the low end, in the jaws' plane
    shift = low[0] - np.sign(low[0]) * reach  # TCP move along ee-x that lays the rod flat
    # Flat, the rod's centre lies -grasp_offset along ee-x from the TCP: put it on the spot.
    e_x = np.array([np.cos(yaw), np.sin(yaw)])
    xy_touch = np.asarray(put_down_xy) + (grasp_offset_obj - shift) * e_x
    T_above = top_down_frame(float(xy_touch[0]), float(xy_touch[1]), T_world_ee[2, 3], yaw)
    # Flat, the rod's axis lies where it is now below the TCP (its point nearest the TCP):
    # the TCP ends that far above the axis' height on the table (never lower than a grasp
    # of the rod lying there: the pads must not jam on the table).
    near = centre - (centre @ x_axis) * x_axis
    z_flat = max(rod_axis_z + near[2] + config.pad_clearance, grasp_height(rod_axis_z))
    T_touch = T_above.copy()
    T_touch[2, 3] = max(z_flat + low[2] + config.touch_clearance, z_flat)
    T_flat = T_above.copy()
    T_flat[:3, 3] += shift * T_above[:3, 0]
    T_flat[2, 3] = z_flat
    p_pivot = T_touch[:3, :3] @ low + T_touch[:3, 3]
    return PutDownPlan(T_above, T_touch, T_flat, p_pivot, low_is_plus)


def axis_hint_after_put_down(plan: PutDownPlan, rod_centre_xy: tuple[float, float]) -> np.ndarray:
    """(3,) world direction of the rod's +x end once it lies flat, seen from its new centre
    (top view): its low end stayed at the pivot as it lay down."""
    to_pivot = np.r_[plan.p_pivot[:2] - np.asarray(rod_centre_xy, dtype=float), 0.0]
    return to_pivot if plan.low_is_plus else -to_pivot


def put_back_jaws_xy(
    spot_xy: tuple[float, ...],
    x_world_ee: np.ndarray,
    tilt: float,
    rod_length: float,
    centre_hint: float,
    pick_area: tuple[float, ...],
    margin: float,
) -> np.ndarray:
    """(2,) world x, y (m) at which the jaws let go of a hanging rod so that it comes to lie
    centred on ``spot_xy``, its ends at least ``margin`` (m) inside ``pick_area`` (x_min,
    x_max, y_min, y_max; m) where the area is long enough.

    The rod hangs along the jaws' x axis (``x_world_ee`` (3,), world) at ``tilt`` (rad,
    signed: a positive tilt raises the ee +x end), its centre ``centre_hint`` (m) along
    ee-x from the jaws. Let go with its low end just above the table, it topples about that
    end, away from it, and comes to lie from there back towards the jaws: its centre ends
    (c - s l/2) cos(tilt) + s l/2 along ee-x from the jaws (s the sign of the tilt; level,
    c). Lowering the jaws above the spot instead lays a steep rod's centre about half its
    length beyond it (centimetres to decimetres over the table's edge).
    """
    u = np.asarray(x_world_ee, dtype=float)[:2]
    norm = float(np.hypot(*u))
    if norm < 1e-6:
        raise UnobservableError("the jaws' x axis is vertical: the rod's lean is undefined")
    u = u / norm
    s = float(np.sign(tilt))
    half = 0.5 * rod_length
    centre_from_jaws = (centre_hint - s * half) * np.cos(tilt) + s * half
    centre = _inside(np.asarray(spot_xy, dtype=float), u, half, pick_area, margin)
    return centre - centre_from_jaws * u


def _inside(centre: np.ndarray, u: np.ndarray, half: float, area, margin: float) -> np.ndarray:
    """``centre`` (2,) moved, per axis, so that the segment centre +- ``half`` ``u`` lies
    ``margin`` inside ``area``; centred in the area along an axis where it cannot."""
    out = centre.copy()
    for k, (lo, hi) in enumerate(((area[0], area[1]), (area[2], area[3]))):
        reach = half * abs(u[k]) + margin
        if hi - lo <= 2 * reach:
            out[k] = 0.5 * (lo + hi)
        else:
            out[k] = float(np.clip(out[k], lo + reach, hi - reach))
    return out
