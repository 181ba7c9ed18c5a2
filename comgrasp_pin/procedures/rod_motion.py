"""How a held rod moved in the jaws between two side views (pure geometry)."""

from __future__ import annotations

import numpy as np

from comgrasp_pin.perception import SideView


def _same_direction(T: np.ndarray, T_ref: np.ndarray) -> np.ndarray:
    """``T`` turned half a turn about its z if its x points against ``T_ref``'s."""
    if T[:3, 0] @ T_ref[:3, 0] >= 0:
        return T
    T = T.copy()
    T[:3, :2] *= -1.0
    return T


def rod_motion(first: SideView, second: SideView, slide: float = 0.0) -> np.ndarray:
    """(4, 4) rigid motion in the ee frame that carried the rod from where the ``first`` view
    saw it to where the ``second`` saw it, from what a view measures well: the axis' turn in
    the jaws' plane (tilt), its turn out of that plane and its shift along the jaw axis (the
    change of the handle's depth line, ``surface_y`` and ``surface_slope``), the axis'
    offset across itself; the rod's slide along its own axis is ``slide`` (m; the views
    measure it poorly) and its roll about its axis is taken as none.
    """

    def axis_and_foot(view: SideView, T: np.ndarray, dy: float, dslope: float):
        a = T[:3, 0] + np.array([0.0, dslope, 0.0])
        a /= np.linalg.norm(a)
        o = T[:3, 3]
        foot = o - (o @ T[:3, 0]) * T[:3, 0]  # the axis point nearest the TCP
        return a, foot + np.array([0.0, dy, 0.0])

    T1 = first.T_ee_obj
    T2 = _same_direction(second.T_ee_obj, T1)
    sign = 1.0 if T2 is second.T_ee_obj else -1.0
    a1, p1 = axis_and_foot(first, T1, 0.0, 0.0)
    a2, p2 = axis_and_foot(second, T2, second.surface_y - first.surface_y,
                           sign * second.surface_slope - first.surface_slope)  # fmt: skip
    R = _rotation_between(a1, a2)
    M = np.eye(4)
    M[:3, :3] = R
    M[:3, 3] = p2 + slide * a2 - R @ p1
    return M


def _rotation_between(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The smallest rotation taking the unit vector ``a`` to ``b`` (Rodrigues)."""
    v, c = np.cross(a, b), float(a @ b)
    if np.linalg.norm(v) < 1e-12:
        return np.eye(3)
    K = np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])
    return np.eye(3) + K + K @ K / (1.0 + c)
