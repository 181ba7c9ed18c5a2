"""Is what the top view found one rod? Refuse, rather than measure, two objects as one.

Two rods apart are two blobs; two rods side by side merge into one blob whose slices across
the axis cut two pieces (the handles, apart where the heads touch) or show two humps with a
valley between them (round handles touching). A single rod, with or without a head, is one
piece per slice with one top. World frame, m.
"""

from __future__ import annotations

import cv2
import numpy as np

from comgrasp_pin.errors import AmbiguousObjectError, ClutterError
from comgrasp_pin.perception._points import opened_blobs
from comgrasp_pin.perception.top_view.rod_flat import propped_ends

SECOND_OBJECT = 0.05  # another blob of this share of the rod's pixels is another object
MIN_OBJECT_PX = 40  # ... and of this many pixels at least
CLUTTER_OBJECTS = 3  # this many objects (or piles) in the pick area are clutter
END_REACH, END_BAND = 0.05, 0.003  # pixels this far beyond an end, on the axis (m) ...
END_PIXELS = 3  # ... this many: the rod may go on, unless each blob they are of is no
# larger than the table's own noise makes (``standing.largest_bump``)
SLICE = 0.01  # slices across the rod (m)
ACROSS_BIN = 0.002  # the across profile's resolution (m): about one pixel on the table
GAP_BINS = 2  # this many empty bins in a row between two pieces split a slice
MIN_VALLEY = 0.002  # a valley between two tops this deep (m) ...
VALLEY_SHARE = 0.3  # ... or this share of the lower top's height splits a slice
VALLEY_SIGMAS = 4.0  # ... and this many noise stds
SPLIT_SLICES = 0.2  # a blob with this share of its slices split is two objects
MIN_SPLIT_SLICES = 3
# A rod, heads and all, is symmetric about its axis: in each slice its piece's middle and
# its top (the median of the points within TOP_BAND or TOP_SIGMAS noise stds of the slice's
# highest) lie on the axis. A slice whose middle or top is OFF_AXIS (or OFF_AXIS_SHARE of
# its width) away counts as split: an L, a V, a rod crossing or beside another, a box.
OFF_AXIS, OFF_AXIS_SHARE = 0.005, 0.15  # m, or this share of the slice's width if more
TOP_BAND, TOP_SIGMAS = 0.002, 3.0  # m, noise stds
# Two equal rods side by side, touching: their slices' profiles, taken together (the median
# of each PROFILE_BIN across the axis over the slices), show two tops with a valley between
# deeper than PROFILE_VALLEY_SHARE of the lower top (and VALLEY_SIGMAS of its noise).
PROFILE_BIN = 0.001  # m
PROFILE_EDGE_BINS = 3  # bins at each side of the profile not looked at (its outline)
PROFILE_VALLEY_SHARE = 0.15
ALIKE = 1.5  # two rods side by side: the middle half of the slices' heights within this ratio
_KERNEL3, _KERNEL5 = np.ones((3, 3), np.uint8), np.ones((5, 5), np.uint8)


def check_one_object(standing: np.ndarray, blob: np.ndarray, min_pixels: int = MIN_OBJECT_PX,
                     at_edge: np.ndarray | None = None) -> None:  # fmt: skip
    """AmbiguousObjectError for a second object in the pick area, ClutterError for more.

    That is: besides ``blob``, other blobs of ``standing`` (both (H, W) bool) of at least
    SECOND_OBJECT of its size, each another object (or a pile of them): ClutterError when
    CLUTTER_OBJECTS or more lie there. ``at_edge``: (H, W) bool, what stands and reaches the
    image's edge (``reaching_border``): blobs on it are named as the robot's own parts.
    """
    count, labels, stats = opened_blobs(standing)
    area = int(blob.sum())
    own = set(np.unique(labels[blob & (labels > 0)]).tolist())
    least = max(min_pixels, SECOND_OBJECT * area)
    big = [k for k in range(1, count) if k not in own and stats[k, cv2.CC_STAT_AREA] >= least]
    edge = [] if at_edge is None else [k for k in big if np.any(at_edge[labels == k])]
    named = (f"; {len(edge)} of them reach the image's edge: the robot's own parts (a "
             "gripper's fingers?), keep the pick area off them") if edge else ""  # fmt: skip
    if 1 + len(big) >= CLUTTER_OBJECTS:
        raise ClutterError(
            f"clutter: {1 + len(big)} objects or piles lie in the pick area (the largest "
            f"{area} px seen from above){named}; the top view measures one rod alone on the "
            "table: clear the table around it"
        )
    if big:
        second = max(int(stats[k, cv2.CC_STAT_AREA]) for k in big)
        raise AmbiguousObjectError(
            f"2 objects lie in the pick area ({area} px and {second} px seen from above)"
            f"{named}; the top view measures one rod alone on the table: clear the other"
        )


def reaching_border(standing: np.ndarray) -> np.ndarray:
    """(H, W) bool: the blobs of ``standing`` that reach the image's border."""
    count, labels = cv2.connectedComponents(standing.astype(np.uint8), connectivity=8)
    edge = np.zeros(count, bool)
    edge[np.unique(np.concatenate([labels[0], labels[-1], labels[:, 0], labels[:, -1]]))] = True
    edge[0] = False
    return edge[labels]


def check_ends_seen(
    points: np.ndarray,
    standing: np.ndarray,
    blob: np.ndarray,
    centroid: np.ndarray,
    direction: np.ndarray,
    ends: tuple[float, float],
    p: np.ndarray,
    bump_px: float,
) -> None:
    """AmbiguousObjectError when the rod may go on beyond an end it seems to have.

    That is: blobs standing on the table apart from the rod's ``blob`` (``standing``, both
    (H, W) bool; ``points`` (H, W, 3)), after the same opening and more than 2 px from it,
    lie on its axis (``direction`` (2,) through ``centroid`` (2,)) within END_REACH beyond
    one of its ``ends`` (coordinates along the axis, m): parts of the rod lost in the image's
    holes and noise. ``p``: the rod's points (N, 3), whose spread across the axis sets the
    band. A blob no larger than ``bump_px`` (px: the area the view's noise bumps exceed but
    rarely, ``standing.largest_bump``; inf where too few bumps were seen to tell, and then
    every blob counts) is the table's noise, not the rod. The bound is fitted to all the
    bumps of the pick area: the largest bump alone would move with the area, and the same
    scene would be refused in one area and measured in another.
    """
    opened = cv2.morphologyEx(standing.astype(np.uint8), cv2.MORPH_OPEN, _KERNEL3) > 0
    others = opened & ~(cv2.dilate(blob.astype(np.uint8), _KERNEL5) > 0)
    if not others.any():
        return
    normal = np.array([-direction[1], direction[0]])
    half_width = np.percentile(np.abs((p[:, :2] - centroid) @ normal), 95) + END_BAND
    rel = np.nan_to_num(points[..., :2] - centroid, nan=1e9)  # none: 1e9 m along or across
    along, across = rel @ direction, np.abs(rel @ normal)
    lo, hi = ends
    beyond = ((along < lo) & (along > lo - END_REACH)) | ((along > hi) & (along < hi + END_REACH))
    corridor = beyond & (across < half_width)
    count, labels, stats, _ = cv2.connectedComponentsWithStats(others.astype(np.uint8))
    on_axis = np.unique(labels[corridor & others])
    # a blob no larger than the table's own noise makes (``bump_px``) is no part of the rod
    bump = bump_px if np.isfinite(bump_px) else 0.0
    in_corridor = np.bincount(labels[corridor & others], minlength=count)
    count = int(sum(in_corridor[k] for k in on_axis if stats[k, cv2.CC_STAT_AREA] > bump))
    if count >= END_PIXELS:
        raise AmbiguousObjectError(
            f"{count} px stand on the table on the rod's axis beyond the end seen: the rod "
            "may go on there, lost in the depth image's holes and noise; its length and centre "
            "are not known (a closer view or a less noisy camera is needed)"
        )


def check_one_rod(
    p: np.ndarray,
    centroid: np.ndarray,
    direction: np.ndarray,
    table_z: float,
    noise: float,
    measured: np.ndarray | None = None,
    heads: bool = False,
) -> None:
    """AmbiguousObjectError when the blob is not one rod.

    That is: the blob's points ``p`` (N, 3), which should lie along ``direction`` (2,)
    through ``centroid`` (2,): too many of its slices across the axis are split in two
    pieces or two tops (``split_slices``; ``measured``: see there). A rod whose tops rise
    steadily along it is named as not lying flat (``rod_flat.propped_ends``). ``heads``: a
    tool's head and handle may pass as one rod (``_profile_two_tops``), as where the
    thin-part checks then look for the rest of the tool (a cleaned depth).
    """
    split, total = split_slices(p, centroid, direction, table_z, noise, measured)
    if total and split >= max(MIN_SPLIT_SLICES, SPLIT_SLICES * total):
        ends = propped_ends(p, centroid, direction, table_z, noise, measured, SLICE)
        if ends is not None:
            raise AmbiguousObjectError(
                f"what lies on the table does not lie flat: its top rises steadily from "
                f"{1e3 * min(ends):.0f} to {1e3 * max(ends):.0f} mm along it, and {split} of "
                f"its {total} slices seem off its axis (propped on its head turned on its "
                "side, or on something?); the top view measures a rod lying on the table: "
                "lay it flat"
            )
        raise AmbiguousObjectError(
            f"what lies on the table is not one rod: {split} of its {total} slices across "
            "its axis show two pieces, two tops, or a middle or top off the axis (rods side "
            "by side, crossing or at an angle?); the top view measures one rod alone on the "
            "table: move the others away"
        )
    if _profile_two_tops(p, centroid, direction, table_z, noise, measured, heads):
        raise AmbiguousObjectError(
            "what lies on the table is not one rod: across its axis it shows two tops all "
            "along (two rods side by side, touching?); the top view measures one rod alone "
            "on the table: move the others away"
        )


def split_slices(
    p: np.ndarray,
    centroid: np.ndarray,
    direction: np.ndarray,
    table_z: float,
    noise: float,
    measured: np.ndarray | None = None,
) -> tuple[int, int]:
    """(slices split in two, slices) of the blob's points ``p`` (N, 3).

    The slices are SLICE wide, across ``direction``: a slice is split when its profile
    across the axis (the highest point per ACROSS_BIN) has an empty bin between occupied
    ones, or a valley between two tops deeper than MIN_VALLEY, VALLEY_SHARE of the lower top
    and VALLEY_SIGMAS noise stds. ``measured`` (N,) bool: the points whose height the depth
    measured (the others, found by colour, count for the gaps but not for the tops).
    """
    if measured is None:
        measured = np.ones(len(p), bool)
    rel = p[:, :2] - centroid
    along = rel @ direction
    across = rel @ np.array([-direction[1], direction[0]])
    height = p[:, 2] - table_z
    slices = np.floor(along / SLICE).astype(int)
    split = total = 0
    for s in np.unique(slices):
        sel = slices == s
        if np.count_nonzero(sel) < 10:
            continue
        total += 1
        bins = np.floor((across[sel] - across[sel].min()) / ACROSS_BIN).astype(int)
        top = np.full(bins.max() + 1, -np.inf)
        np.maximum.at(top, bins, np.where(measured[sel], height[sel], 0.0))
        heights = np.full(bins.max() + 1, -np.inf)
        np.maximum.at(heights, bins[measured[sel]], height[sel][measured[sel]])
        measured_top = heights[np.isfinite(heights)] if not measured[sel].all() else heights
        split += int(_two_pieces(top) or _two_tops(measured_top, noise)
                     or _off_axis(across[sel], height[sel], measured[sel], noise))  # fmt: skip
    return split, total


def _off_axis(across: np.ndarray, height: np.ndarray, measured: np.ndarray, noise: float) -> bool:
    """Whether a slice's middle or top lies OFF_AXIS or more from the rod's axis.

    ``across``: the slice's points across the axis (m); its top: the median of the
    ``measured`` points within TOP_BAND or TOP_SIGMAS ``noise`` stds of its highest
    ``height``.
    """
    middle = 0.5 * (across.min() + across.max())
    off = max(OFF_AXIS, OFF_AXIS_SHARE * np.ptp(across))
    if not measured.any():
        return bool(abs(middle) > off)
    h = height[measured]
    top = across[measured][h >= h.max() - max(TOP_BAND, TOP_SIGMAS * noise)]
    return bool(abs(middle) > off or abs(np.median(top)) > off)


def _profile_two_tops(p, centroid, direction, table_z, noise, measured, heads) -> bool:
    """Whether the slices' median profile across the axis has two tops.

    Two equal rods touching side by side, whose valley one slice's coarse profile misses.
    The arguments are ``split_slices``' and ``check_one_rod``'s ``heads``. Asked only where
    the depth measured half the object's slices at least, and, with ``heads``, where the
    middle half of their median heights lie within ALIKE of each other: two rods side by
    side all along. A tool's head and handle are not, and the median of their slices mixed
    leaves a valley in the middle; without ``heads`` that valley refuses it (a head whose
    handle's rest no check would look for).
    """
    if measured is None:
        measured = np.ones(len(p), bool)
    along_all = (p[:, :2] - centroid) @ direction
    along = along_all[measured]
    across = (p[measured, :2] - centroid) @ np.array([-direction[1], direction[0]])
    height = p[measured, 2] - table_z
    slices = np.floor(along / SLICE).astype(int)
    bins = np.floor(across / PROFILE_BIN).astype(int)
    slices -= slices.min()
    bins -= bins.min()
    grid = np.full((slices.max() + 1, bins.max() + 1), np.nan)
    np.fmax.at(grid, (slices, bins), height)
    seen = np.isfinite(grid).sum(axis=0)
    seen_rows = np.isfinite(grid).any(axis=1)  # the slices with a measured point
    rows = np.count_nonzero(seen_rows)
    if rows < max(MIN_SPLIT_SLICES, 0.5 * np.ptp(np.floor(along_all / SLICE))):
        return False  # (a tool's head whose handle the depth did not measure: not all along)
    kept = seen >= 0.5 * rows  # the bins most slices see
    tops = np.nanmedian(grid[seen_rows], axis=1)  # each slice's median height
    if heads and np.percentile(tops, 75) > ALIKE * np.percentile(tops, 25):
        return False  # (a tool's head and handle, not two rods all along)
    profile = np.nanmedian(grid[:, kept], axis=0)
    edge = slice(PROFILE_EDGE_BINS, -PROFILE_EDGE_BINS)  # (the outline: flying pixels)
    profile, counts = profile[edge], seen[kept][edge]
    if len(profile) < 3:
        return False
    left = np.maximum.accumulate(profile)
    right = np.maximum.accumulate(profile[::-1])[::-1]
    lower_top = np.minimum(left, right)
    need = np.maximum(
        np.maximum(MIN_VALLEY, PROFILE_VALLEY_SHARE * lower_top),
        VALLEY_SIGMAS * noise / np.sqrt(counts),
    )  # fmt: skip (each bin's own)
    return bool(np.any((lower_top - profile)[1:-1] > need[1:-1]))


def _two_pieces(top: np.ndarray) -> bool:
    """Whether the profile has GAP_BINS empty bins in a row between occupied ones."""
    empty = (~np.isfinite(top)).astype(int)
    run = np.convolve(empty, np.ones(GAP_BINS, int), mode="valid")
    return bool(np.any(run >= GAP_BINS))


def _two_tops(top: np.ndarray, noise: float) -> bool:
    """Whether the profile rises to a top on both sides of some valley deep enough."""
    left = np.maximum.accumulate(top)
    right = np.maximum.accumulate(top[::-1])[::-1]
    lower_top = np.minimum(left, right)
    depth = lower_top - top
    need = np.maximum(np.maximum(MIN_VALLEY, VALLEY_SHARE * lower_top), VALLEY_SIGMAS * noise)
    return bool(np.any(depth[1:-1] > need[1:-1]))
