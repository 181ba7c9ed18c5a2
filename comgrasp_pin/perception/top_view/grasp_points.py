"""Where the jaws can grasp a rod seen from above, and the whole of a rod seen in part.

Positions are along the rod from its centre (m), towards the detection's +yaw; pure
functions of a ``RodDetection`` (no images).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from comgrasp_pin.errors import ObjectCutByBorderError, ObjectNotFoundError
from comgrasp_pin.geometry import GraspPose
from comgrasp_pin.perception.top_view.rod_detection import RodDetection


def nearest_graspable(
    det: RodDetection, s: float, max_width: float = 0.075, half_pad: float = 0.022
) -> float:
    """The position along the rod nearest ``s`` where the jaws fit.

    Positions are in m from the rod's centre, towards +yaw. The jaws fit where the rod is
    narrower than ``max_width`` over ``half_pad`` either side.
    """
    pos, width = det.widths[:, 0], det.widths[:, 1]
    # (the pads on slices seen: a rod cut by the image's border is not seen to its end)
    seen_lo, seen_hi = pos.min() - 0.01, pos.max() + 0.01
    ok = []
    for c in (s, *pos):  # ``s`` itself first: the slices are 1 cm apart
        near = np.abs(pos - c) <= half_pad
        on_rod = abs(c) <= 0.5 * det.length - half_pad
        if np.all(width[near] <= max_width) and on_rod and seen_lo <= c - half_pad \
                and c + half_pad <= seen_hi:  # fmt: skip
            ok.append(c)
    if not ok:
        raise ObjectNotFoundError("no part of the object is narrow enough to grasp")
    return float(min(ok, key=lambda c: abs(c - s)))


def nearest_on_handle(det: RodDetection, s: float, half_pad: float = 0.022) -> float:
    """The position along the rod nearest ``s`` where both pads lie on the handle.

    Positions are in m from the rod's centre, towards +yaw. Within ``half_pad`` either side
    the rod is no wider than its width at the centre (the handle) plus a quarter and 4 mm.
    A grasp on a head's shoulder stops the jaws on the head and barely holds the handle.
    """
    handle = det.widths[np.argmin(np.abs(det.widths[:, 0])), 1]
    return nearest_graspable(det, s, max_width=1.25 * handle + 0.004, half_pad=half_pad)


def with_known_length(seen: RodDetection, length: float, min_share: float) -> RodDetection:
    """The whole rod of known ``length`` (m) of which ``seen`` is the part in view.

    ``seen``: an ObjectCutByBorderError's, one end out of view (``cut_end``). The result's
    centre is moved towards the cut end by half the part not seen, its length is
    ``length``; the widths (seen slices only) and pixels are as seen, ``cut_end`` is kept
    (the rod was not seen whole).

    A real robot knows the length from an earlier, whole view of the same rod.
    ObjectCutByBorderError when less than ``min_share`` of it is seen (too little to grasp
    it near its centre) or when ``seen`` is whole.
    """
    if not seen.cut_end:
        raise ObjectCutByBorderError("the detection is of a whole rod, not of a cut one")
    if seen.length < min_share * length:
        raise ObjectCutByBorderError(
            f"only {1e3 * seen.length:.0f} mm of the {1e3 * length:.0f} mm rod are in the top "
            f"camera's view (less than {100 * min_share:.0f} %): too little to grasp it by"
        )
    shift = 0.5 * seen.cut_end * max(length - seen.length, 0.0)
    g = seen.grasp
    grasp = GraspPose(g.x + shift * np.cos(g.yaw), g.y + shift * np.sin(g.yaw), g.z, g.yaw)
    widths = seen.widths - np.array([shift, 0.0])
    return replace(seen, grasp=grasp, length=float(length), widths=widths)


def check_seen_whole(rod: RodDetection, length: float, tolerance: float) -> RodDetection:
    """``rod``, seen again, if it is as long as an earlier whole view saw it.

    That is: within ``tolerance`` (m) of ``length`` (m) or longer; ObjectCutByBorderError
    when shorter: part of it is out of sight (hanging down over the table's edge, below the
    plane the top view measures), and its centre is not where it seems.
    """
    if rod.length < length - tolerance:
        raise ObjectCutByBorderError(
            f"the rod seen again is {1e3 * rod.length:.0f} mm long, {1e3 * length:.0f} mm "
            "when first seen: part of it is out of sight (hanging over the table's edge?)"
        )
    return rod


def rod_widths(p, centroid, direction, s_rel, yaw) -> np.ndarray:
    """(K, 2) the rod's width across its axis in 1 cm slices (m).

    Rows: (position along the rod from its centre towards +yaw, width).
    """
    across = (p[:, :2] - centroid) @ np.array([-direction[1], direction[0]])
    bins = np.floor(s_rel / 0.01).astype(int)
    widths = np.array([((b + 0.5) * 0.01, np.ptp(across[bins == b])) for b in np.unique(bins)])
    if direction @ np.array([np.cos(yaw), np.sin(yaw)]) < 0:  # rows towards +yaw
        widths = widths[::-1] * np.array([-1.0, 1.0])
    return widths
