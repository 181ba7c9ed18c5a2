"""Is what the side camera sees between the jaws one rod? Other things in the jaws' slab.

The side view takes every blob of points in the slab between the jaws (``held_region``) as
the rod: the near finger cuts a held rod in two, and heads and weights stand off its axis.
Clutter in the slab is then taken for the rod too (measured on scenes the project did not
build: ``benchmarks/unseen/wrist.py``): a box below the rod pulled its axis by 27 mm and 2.4
deg, and a box in line beyond its end, 4 cm away, was taken for its end (the grasp position
12 cm off). Two checks, each silent (the same mask, to the bit) on one rod:

- ``drop_off_axis``: a blob of at least OFF_AXIS_MIN_SHARE of the pixels none of whose
  points comes within the jaws' half gap + OFF_AXIS_MARGIN of the axis, nor within
  NEAR_JAWS of the TCP, is not the held rod (a rod's own pieces, its heads included, reach
  its axis, and those beside the near finger the jaws); it is left out and the axis fitted
  again.
- ``rod_line``: the axis from the slice centres (``rod_axis.centre_line``) after
  ``drop_off_axis``; when that line misses the jaws (a second rod 10 cm below pulled it
  away, and the view said nothing was held), once more from the blobs that come within
  NEAR_JAWS of the TCP (the held rod's pieces on either side of the near finger do).
- ``check_width``: in a clean image, a handle whose median slice is wider across the axis
  (in the x-z plane) than the jaws' gap times WIDTH_RATIO plus WIDTH_MARGIN is two things
  (a second rod touching it below: 1.5 deg and 7.5 mm off), refused. (A noisy image's
  flying pixels widen a 1 cm stick to 2 cm; there no cylinder fits two rods, and the view
  is refused as untrusted.)
- ``check_length``: a rod whose points near its axis reach farther than its known length
  (the top view's) by LENGTH_SLACK goes on into something else: a second rod touching its
  end in line (taken for its end: the grasp position 20 cm off). Refused.
- ``check_no_gap``: along the axis, the blobs seen may be apart only where something
  nearer the camera hides the rod (the near finger, the arm) or the robot's volume holds
  it. Where the camera sees past the axis over more than GAP_MIN, the rod is not there:
  two objects in line, refused (``AmbiguousObjectError``).
"""

from __future__ import annotations

from collections.abc import Callable

import cv2
import numpy as np

from comgrasp_pin.camera import PinholeCamera
from comgrasp_pin.errors import AmbiguousObjectError, UntrustedImageError
from comgrasp_pin.perception._points import slice_percentiles
from comgrasp_pin.perception.side_view.rod_axis import centre_line

OFF_AXIS_MIN_SHARE = 0.2  # smaller blobs are left as they were: the slice medians ignore them
OFF_AXIS_MARGIN = 0.015  # m beyond the jaws' half gap (the widest, when it is not known)
WIDEST_HALF_GAP = 0.045  # m: the jaws fully open
GAP_MIN = 0.02  # m along the axis: shorter gaps are not judged
GAP_STEP = 0.002  # m between the gap's samples
PAST_MARGIN = 0.005  # m: depth this far beyond the axis point is the camera seeing past it
PAST_SHARE = 0.6  # a gap is real when this share of its samples sees past the axis
NEAR_JAWS = 0.06  # m from the TCP: the held rod's pieces beside the near finger come nearer
WIDTH_RATIO, WIDTH_MARGIN = 1.4, 0.004  # a handle wider than the jaws' gap by this is two
LENGTH_SLACK = 0.10  # m beyond the known length (the project's own calls: up to 6.5 cm)


def rod_line(
    mask: np.ndarray, points: np.ndarray, half_gap: float | None, max_from_tcp: float
) -> tuple[np.ndarray, tuple]:
    """(the rod's mask (H, W), ``centre_line``'s answer for its points' x-z).

    ``points`` (H, W, 3) ee-frame points of the pixels (m); ``half_gap`` the jaws' half
    opening (m) or None; ``max_from_tcp``: how close to the TCP a held rod's axis passes (m).
    """
    line = centre_line(points[mask][:, [0, 2]])
    kept = drop_off_axis(mask, points, line[0], line[1], half_gap)
    if kept is not mask:
        mask, line = kept, centre_line(points[kept][:, [0, 2]])
    if np.linalg.norm(line[1]) <= max_from_tcp:
        return mask, line
    count, labels = cv2.connectedComponents(mask.astype(np.uint8), connectivity=8)
    near = [k for k in range(1, count)
            if np.linalg.norm(points[labels == k], axis=1).min() < NEAR_JAWS]  # fmt: skip
    if not near or len(near) == count - 1:
        return mask, line
    near_mask = np.isin(labels, near)
    near_line = centre_line(points[near_mask][:, [0, 2]])
    if np.linalg.norm(near_line[1]) > max_from_tcp:
        return mask, line
    return near_mask, near_line


def drop_off_axis(
    mask: np.ndarray,
    points: np.ndarray,
    x_axis_xz: np.ndarray,
    offset_xz: np.ndarray,
    half_gap: float | None,
) -> np.ndarray:
    """``mask`` (H, W) without its large blobs that keep away from the axis (itself when none).

    ``points`` (H, W, 3) ee-frame points of the pixels (m); the axis: direction
    ``x_axis_xz`` (2,) through ``offset_xz`` (2,) in the ee x-z plane, at y = 0.
    """
    count, labels, stats, _ = cv2.connectedComponentsWithStats(mask.astype(np.uint8),
                                                                connectivity=8)  # fmt: skip
    if count <= 2:
        return mask
    sizes = stats[:, cv2.CC_STAT_AREA]
    large = np.flatnonzero(sizes[1:] >= OFF_AXIS_MIN_SHARE * sizes[1:].sum()) + 1
    if len(large) < 2:
        return mask
    reach = (half_gap or WIDEST_HALF_GAP) + OFF_AXIS_MARGIN
    x_axis = np.array([x_axis_xz[0], 0.0, x_axis_xz[1]])
    offset = np.array([offset_xz[0], 0.0, offset_xz[1]])
    away = []
    for label in large:
        p = points[labels == label] - offset
        rho = np.linalg.norm(p - np.outer(p @ x_axis, x_axis), axis=1)
        if rho.min() > reach and np.linalg.norm(p + offset, axis=1).min() >= NEAR_JAWS:
            away.append(label)
    if not away or len(away) == len(large):
        return mask
    return mask & ~np.isin(labels, away)


def check_no_gap(
    mask: np.ndarray,
    along: np.ndarray,
    near: np.ndarray,
    axis: tuple[np.ndarray, np.ndarray],
    depth: np.ndarray,
    camera: PinholeCamera,
    T_cam_ee: np.ndarray,
    excluded: Callable[[np.ndarray], np.ndarray],
) -> None:
    """Refuse a gap between the rod's blobs along its axis where the camera sees past it.

    ``mask`` (H, W): the rod's pixels; ``along`` (N,): their points' positions along the
    axis (m; N pixels of ``mask`` in row-major order), ``near`` (N,) those near the axis
    (the blobs' extents along it are theirs); ``axis``: (direction (3,), point (3,)) in the
    ee frame; ``depth`` (H, W) the image (m), ``T_cam_ee`` (4, 4). Where the axis runs
    through the robot's own volume (``excluded``) the rod may be hidden or inside it: not
    judged. A gap within one blob is not judged either (a head's edge, lost pixels).

    Raises:
        AmbiguousObjectError: such a gap (two objects in line).
        UntrustedImageError: no point near the axis (the fit is not the rod's).
    """
    if not np.any(near):
        raise UntrustedImageError(
            "no point of the held rod lies within its radius of the axis fitted to it: the "
            "fit is not the rod's (too few or too scattered points in this frame)"
        )
    _, labels = cv2.connectedComponents(mask.astype(np.uint8), connectivity=8)
    blob = labels[mask][near]
    spans = sorted((along[near][blob == k].min(), along[near][blob == k].max())
                   for k in np.unique(blob))  # fmt: skip
    end = spans[0][1]
    for lo, hi in spans[1:]:
        if lo - end > GAP_MIN:
            _judge_gap(end, lo, axis, depth, camera, T_cam_ee, excluded)
        end = max(end, hi)


def _judge_gap(lo, hi, axis, depth, camera, T_cam_ee, excluded) -> None:
    """AmbiguousObjectError when the camera sees past the axis between ``lo`` and ``hi``."""
    x_axis, offset = axis
    t = np.arange(lo + GAP_STEP, hi - GAP_STEP / 2, GAP_STEP)
    a = offset + np.outer(t, x_axis)
    q = a @ T_cam_ee[:3, :3].T + T_cam_ee[:3, 3]
    uv = np.round(camera.project(q)).astype(int)
    inside = (uv[:, 0] >= 0) & (uv[:, 0] < camera.width) & (uv[:, 1] >= 0)
    inside &= (uv[:, 1] < camera.height) & (q[:, 2] > 0) & ~excluded(a)
    if inside.sum() < max(1, 0.5 * len(t)):
        return  # mostly out of the image or in the robot's volume: nothing to tell
    seen = depth[uv[inside, 1], uv[inside, 0]]
    past = seen > q[inside, 2] + PAST_MARGIN  # inf: nothing seen there; 0 (lost): not known
    if past.mean() >= PAST_SHARE:
        raise AmbiguousObjectError(
            f"two objects in line between the jaws: the side camera sees past the rod's "
            f"axis over {100 * (hi - lo):.0f} cm between {100 * lo:.0f} and {100 * hi:.0f} "
            "cm along it; the rod cannot be told from what lies beyond its end"
        )


def check_width(
    points: np.ndarray,
    along: np.ndarray,
    handle: np.ndarray,
    axis: tuple[np.ndarray, np.ndarray],
    half_gap: float | None,
) -> None:
    """Refuse a handle wider than the jaws hold.

    ``points`` (N, 3) the rod's points (ee frame, m), ``along`` (N,) their positions along
    the axis, ``handle`` (N,) bool its handle's; ``axis``: (direction (3,), point (3,));
    ``half_gap``: the jaws' half opening (m) or None (then nothing is judged).

    Raises:
        AmbiguousObjectError: a handle wider than the jaws' gap (two things).
    """
    if half_gap is None or handle.sum() < 3:
        return
    x_axis, offset = axis
    normal = np.array([-x_axis[2], 0.0, x_axis[0]])  # across the axis in the x-z plane
    across = (points[handle] - offset) @ normal
    bins = np.floor(along[handle] / 0.01).astype(int)
    _, ends = slice_percentiles(bins, across, (2, 98), 5)
    widths = ends[:, 1] - ends[:, 0]  # np.ptp of each slice's two
    width = float(np.median(widths)) if len(widths) else 0.0
    if width > 2 * half_gap * WIDTH_RATIO + WIDTH_MARGIN:
        raise AmbiguousObjectError(
            f"the held handle is {1e3 * width:.0f} mm wide across its axis, the jaws hold "
            f"{2e3 * half_gap:.0f} mm: two things between the jaws (a second rod against it)"
        )


def check_length(along_near: np.ndarray, rod_length: float | None) -> None:
    """Refuse a rod whose points near its axis reach too far for its length.

    ``along_near`` (N,): the positions along the axis of the rod's points near it (m);
    ``rod_length``: its known length (m; the top view's), or None (nothing is judged).

    Raises:
        AmbiguousObjectError: something in line with the rod, touching it.
    """
    if rod_length is None or len(along_near) < 2:
        return
    lo, hi = np.percentile(along_near, [0.1, 99.9])
    if hi - lo > rod_length + LENGTH_SLACK:
        raise AmbiguousObjectError(
            f"the held rod is seen {100 * (hi - lo):.0f} cm long along its axis, "
            f"{100 * rod_length:.0f} cm known: something in line with it, touching it"
        )
