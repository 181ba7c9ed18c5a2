"""How a held rod moved in the jaws between two side views (pure geometry)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from comgrasp_pin.perception import SideView


def _same_direction(T: np.ndarray, T_ref: np.ndarray) -> np.ndarray:
    """``T`` turned half a turn about its z if its x points against ``T_ref``'s."""
    if T[:3, 0] @ T_ref[:3, 0] >= 0:
        return T
    T = T.copy()
    T[:3, :2] *= -1.0
    return T


def _paired_slices(first: SideView, second: SideView):
    """(position along the rod (m), change of the depth line (m)) of the 1 cm slices both
    views kept, or None where they cannot be paired (a view without slices, the two pointing
    opposite ways, fewer than 4 in common)."""
    a, b = first.depth_slices, second.depth_slices
    if a is None or b is None or second.T_ee_obj[:3, 0] @ first.T_ee_obj[:3, 0] < 0:
        return None
    common, ia, ib = np.intersect1d(a[:, 0], b[:, 0], return_indices=True)
    if len(common) < 4:
        return None
    return 0.5 * (a[ia, 1] + b[ib, 1]), b[ib, 2] - a[ia, 2]


def depth_change_std(first: SideView, second: SideView) -> tuple[float, float]:
    """Standard errors (m, and per m along the rod) of the change of the depth line from
    ``first`` to ``second``. Paired slice by slice where both views kept their slices and
    point the same way: a piece of surface seen in both cancels from the difference, so the
    error is the scatter of the slices' differences about a line; the two lines' standard
    errors combined otherwise (as if independent)."""
    paired = _paired_slices(first, second)
    if paired is None:
        return (float(np.hypot(first.surface_y_std, second.surface_y_std)),
                float(np.hypot(first.surface_slope_std, second.surface_slope_std)))  # fmt: skip
    _, cov = np.polyfit(*paired, 1, cov=True)  # scaled by the residuals
    return float(np.sqrt(cov[1, 1])), float(np.sqrt(cov[0, 0]))


def paired_depth_line(first: SideView, second: SideView) -> SideView:
    """``second`` with its depth line (``surface_y``, ``surface_slope``) put where ``first``'s
    lies plus the change their paired slices show: the line through the differences of the
    1 cm slices both views kept (at least 4; both pointing the same way), the fit whose
    scatter ``depth_change_std`` states. A piece of surface seen in both cancels from the
    difference, so the handle's profile does not enter (each view's own line depends on
    which slices it holds: a capsule's rounded end, a head's side, by up to a share of the
    radius). ``second`` itself where they cannot be paired.
    """
    paired = _paired_slices(first, second)
    if paired is None:
        return second
    dslope, dy = np.polyfit(*paired, 1)
    return replace(second, surface_y=first.surface_y + float(dy),
                   surface_slope=first.surface_slope + float(dslope))  # fmt: skip


def depth_agrees(first: SideView, second: SideView, max_shift: float, max_turn: float) -> bool:
    """Whether the two views' depth lines differ no more than a grasp's compliance moves a
    rod (``max_shift`` m along the jaw axis, ``max_turn`` rad out of the jaws' plane); more
    means the views saw different parts of the handle (a finger in the way), not a motion."""
    T2 = _same_direction(second.T_ee_obj, first.T_ee_obj)
    sign = 1.0 if T2 is second.T_ee_obj else -1.0
    shift = abs(second.surface_y - first.surface_y)
    turn = abs(np.arctan(sign * second.surface_slope) - np.arctan(first.surface_slope))
    return bool(shift <= max_shift and turn <= max_turn)


def rod_motion(
    first: SideView, second: SideView, slide: float = 0.0, depth: bool = True
) -> np.ndarray:
    """(4, 4) rigid motion in the ee frame that carried the rod from where the ``first`` view
    saw it to where the ``second`` saw it, from what a view measures well: the axis' turn in
    the jaws' plane (tilt), its turn out of that plane and its shift along the jaw axis (the
    change of the handle's depth line, ``surface_y`` and ``surface_slope``), the axis'
    offset across itself; the rod's slide along its own axis is ``slide`` (m; the views
    measure it poorly) and its roll about its axis is taken as none. ``depth`` False: the
    depth lines are not used (``depth_agrees`` said they disagree), the rod taken as not
    shifted along the jaws nor turned out of their plane.
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
    dy = second.surface_y - first.surface_y if depth else 0.0
    dslope = sign * second.surface_slope - first.surface_slope if depth else 0.0
    a2, p2 = axis_and_foot(second, T2, dy, dslope)
    R = _rotation_between(a1, a2)
    # the rod turns about where the jaws hold it (the first axis' foot), then shifts across
    # its axis onto the second: that foot lands on the point of the second axis nearest it
    c2 = p2 + ((p1 - p2) @ a2) * a2
    M = np.eye(4)
    M[:3, :3] = R
    M[:3, 3] = c2 + slide * a2 - R @ p1
    return M


def _rotation_between(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The smallest rotation taking the unit vector ``a`` to ``b`` (Rodrigues)."""
    v, c = np.cross(a, b), float(a @ b)
    if np.linalg.norm(v) < 1e-12:
        return np.eye(3)
    K = np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])
    return np.eye(3) + K + K @ K / (1.0 + c)


def mid_window_view(start: SideView | None, end: SideView) -> SideView:
    """The rod where it was, on average, while the torques were averaged between two views
    (the rod may creep in the jaws meanwhile): halfway from ``end`` back to ``start``, whose
    difference is kept as ``creep`` (the motion start to end). ``end`` alone when there is no
    start view."""
    if start is None:
        return end
    S = _same_direction(start.T_ee_obj, end.T_ee_obj)
    sign = 1.0 if S is start.T_ee_obj else -1.0
    half_turn = 0.5 * float(
        np.arctan2(-S[2, 0], S[0, 0]) - np.arctan2(-end.T_ee_obj[2, 0], end.T_ee_obj[0, 0])
    )
    c, s = np.cos(half_turn), np.sin(half_turn)
    R = np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])
    x, o = end.T_ee_obj[:3, 0], end.T_ee_obj[:3, 3]
    foot_end = o - (o @ x) * x
    foot_start = S[:3, 3] - (S[:3, 3] @ S[:3, 0]) * S[:3, 0]
    T = end.T_ee_obj.copy()
    T[:3, :3] = R @ T[:3, :3]
    T[:3, 3] = foot_end + R @ (o - foot_end) + 0.5 * (foot_start - foot_end)
    return replace(
        end,
        T_ee_obj=T,
        theta=float(np.arctan2(-T[2, 0], T[0, 0])),
        grasp_offset=float(-(T[:3, 3] @ T[:3, 0])),
        surface_y=0.5 * (start.surface_y + end.surface_y),
        surface_slope=0.5 * (sign * start.surface_slope + end.surface_slope),
        creep=rod_motion(start, end),
        depth_slices=_mean_slices(start, end) if sign > 0 else end.depth_slices,
    )


def _mean_slices(start: SideView, end: SideView) -> np.ndarray | None:
    """The two views' depth slices averaged where both have them."""
    a, b = start.depth_slices, end.depth_slices
    if a is None or b is None:
        return b
    _, ia, ib = np.intersect1d(a[:, 0], b[:, 0], return_indices=True)
    return 0.5 * (a[ia] + b[ib])
