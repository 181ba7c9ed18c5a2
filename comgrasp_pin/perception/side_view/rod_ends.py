"""Where a held rod ends and where its centre lies along its axis, from the side camera.

The rod's axis is known (``rod_axis``); what is left is to find its two ends among the
visible points, to tell which ends are really ends (not cut by the image border, hidden
behind the gripper or lost in the robot's self-filter) and how precisely each is located,
and from the trusted ends and the rod's known length to place its centre. Ee frame, m.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from comgrasp_pin.camera import PinholeCamera
from comgrasp_pin.errors import ObjectCutByBorderError
from comgrasp_pin.perception._points import border_pixels

HEAD_BAND = 0.015  # the last this much of an end shows whether it carries a head (m)
HEAD_RATIO = 1.2  # an end standing this many handle radii off the axis is a head
ROUND_BAND = 1.2  # a round end's visible cap lies within this many radii of its extreme
ROUND_MIN_POINTS = 15
PEEK = 0.012  # look this far beyond an end to tell whether it is really the end (m)
END_SLACK = 0.003  # a point of the rod this little beyond an end found is at that end (m)
LENGTH_TOLERANCE = 0.01  # seen and known lengths this close agree (m)
LENGTH_EXCESS = 0.004  # seen this much longer than known, something joined the rod (m)
BORDER_NEAR = 0.03  # an end this close to where the rod meets the image border is cut (m)


def end_profile(
    along: np.ndarray, rho: np.ndarray, end: float, outwards: float, radius: float
) -> tuple[float, bool]:
    """An end of the rod from the profile of the visible points near it.

    Args:
        along: (N,) the points' coordinate along the axis (m).
        rho: (N,) the points' distance from the axis (m).
        end: the extreme coordinate seen at this end (m).
        outwards: +1 (hi end) or -1 (lo end).
        radius: the handle's radius (m).

    Returns:
        (the end's coordinate (m), sharp): a sharp end is located to a fraction of a
        millimetre, because it carries a head (it stands off the axis farther than the
        handle: its flat face is seen edge-on) or it is a round cap fitted by ``round_end``.
        A plain handle end too thin for the cap fit may fall short by up to its radius.
    """
    near_end = outwards * (end - along) < HEAD_BAND
    if np.percentile(rho[near_end], 90) > HEAD_RATIO * radius:
        return end, True
    tip = round_end(along, rho, end, outwards, radius)
    return (end, False) if tip is None else (tip, True)


def round_end(
    along: np.ndarray, rho: np.ndarray, end: float, outwards: float, radius: float
) -> float | None:
    """The tip of a round (hemispherical) end whose visible extreme is ``end``.

    Both are coordinates along the axis (m); None if the end does not show as a cap of the
    handle's ``radius``.

    The side camera sees a cap at the rod's end from behind and at a grazing angle, so the
    extreme of the visible points falls short of the tip (by up to half the radius). The
    visible cap points (``along``, distance ``rho`` from the axis; the cylinder's points
    lie at rho = radius) are on a sphere centred on the axis: each gives its centre as
    along - outwards * sqrt(radius^2 - rho^2). If they agree, the tip lies ``radius``
    beyond that centre.
    """
    cap = (outwards * (end - along) < ROUND_BAND * radius) & (rho < 0.85 * radius)
    if np.count_nonzero(cap) < ROUND_MIN_POINTS:
        return None
    centres = along[cap] - outwards * np.sqrt(radius**2 - rho[cap] ** 2)
    centre = np.median(centres)
    if np.median(np.abs(centres - centre)) > max(0.05 * radius, 5e-4):
        return None
    return float(outwards * max(outwards * end, outwards * centre + radius))


def centre_along(
    x_axis: np.ndarray,
    ends: tuple[float, float],
    sharp: tuple[bool, bool],
    along: np.ndarray,
    offset: np.ndarray,
    depth: np.ndarray,
    points: np.ndarray,
    candidate: np.ndarray,
    mask: np.ndarray,
    camera: PinholeCamera,
    T_cam_ee: np.ndarray,
    rod_length: float | None,
    centre_hint: float | None,
    excluded: Callable[[np.ndarray], np.ndarray],
) -> float:
    """Where the rod's centre lies along ``x_axis`` (coordinate, m), from its trusted ends.

    ``ends``: (lo, hi) coordinates of the ends seen; ``sharp``: whether each is located
    precisely (see ``end_profile``). An end is trusted when the point just beyond it is
    in the image, nothing nearer to the camera covers it, and it is not in a region left
    out as the robot's own (else the rod may go on out of view, behind the gripper, or
    into the self-filter). With the rod's length known, the centre is found from the
    trusted end that is best located.
    """
    lo, hi = ends
    along_border = points[border_pixels(mask)] @ x_axis
    trusted = [
        end_is_seen(
            offset + e * x_axis, s * x_axis, depth, points, candidate, camera, T_cam_ee,
            excluded,
        )
        and not np.any(np.abs(along_border - e) < BORDER_NEAR)
        for e, s in ((lo, -1.0), (hi, 1.0))
    ]  # fmt: skip
    if rod_length is None:
        if all(trusted):
            return 0.5 * (lo + hi)
        raise ObjectCutByBorderError(
            "an end of the held rod is out of view or hidden; pass rod_length (top view)"
        )
    if hi - lo > rod_length + LENGTH_EXCESS:
        # Something beyond the rod joined the mask: the rod is the length-L window that
        # holds the most points.
        centres = np.arange(lo + 0.5 * rod_length, hi - 0.5 * rod_length, 0.001)
        counts = [np.count_nonzero(np.abs(along - c) <= 0.5 * rod_length) for c in centres]
        return float(centres[np.asarray(counts) >= max(counts)].mean())
    if all(trusted) and hi - lo > rod_length - LENGTH_TOLERANCE and sharp[0] == sharp[1]:
        return 0.5 * (lo + hi)
    # One end: the trusted one; of two, the sharp one, else the farther from the jaws (the
    # nearer may be partly hidden by the fingers).
    rank = [(t, sh, abs(e)) for t, sh, e in zip(trusted, sharp, ends, strict=True)]
    best = int(np.argmax([rank[0] > rank[1], rank[1] > rank[0]]))
    if trusted[best]:
        return ends[best] - (-1.0, 1.0)[best] * 0.5 * rod_length
    if centre_hint is not None:
        # The rod reaches at least as far as seen at either end.
        return float(np.clip(centre_hint, hi - 0.5 * rod_length, lo + 0.5 * rod_length))
    raise ObjectCutByBorderError("neither end of the held rod is seen whole (side camera)")


def end_is_seen(
    end: np.ndarray,
    outwards: np.ndarray,
    depth: np.ndarray,
    points: np.ndarray,
    candidate: np.ndarray,
    camera: PinholeCamera,
    T_cam_ee: np.ndarray,
    excluded: Callable[[np.ndarray], np.ndarray],
) -> bool:
    """Whether the rod really ends at ``end`` (3-D point on the axis, ee frame, m).

    ``outwards`` is the unit axis direction. The rod ends there if the point PEEK beyond it
    is in the image and shows background behind it, or the rod's own end covering it in
    perspective.
    """
    beyond = end + PEEK * outwards
    in_robot = bool(excluded(beyond[None])[0])
    p_cam = T_cam_ee[:3, :3] @ beyond + T_cam_ee[:3, 3]
    if p_cam[2] <= 0:
        return False
    u, v = camera.project(p_cam[None])[0]
    if not (2 <= u < camera.width - 2 and 2 <= v < camera.height - 2):
        return False
    row, col = int(round(v)), int(round(u))
    if candidate[row, col]:
        # What may be the rod (the mask before its opening): a wide head seen in
        # perspective (its point lies within the end found), or the rod going on beyond
        # this end (it was cut off by the border).
        return bool((points[row, col] - end) @ outwards < END_SLACK)
    # Seen if what lies there is farther (background); hidden if something else, nearer,
    # covers it (the gripper). Within the robot's own volume, where the self-filter would
    # have removed the rod, only if it is clearly farther (the rod would be in front).
    return bool(depth[row, col] > p_cam[2] + (0.01 if in_robot else -0.01))
