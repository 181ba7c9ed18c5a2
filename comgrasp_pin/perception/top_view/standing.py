"""What stands on the table, height first: the object's mask in a top-down view.

The object is what stands above the table's plane in the depth (``table_view``) inside the
pick area. A colour image, where given, marks more of it only where it lines up with the
depth (``registration``); other objects are counted before anything else
(``rod_shape.check_one_object``: several objects, clutter), then whether the object runs
out of the image, then (colour) whether what the colour adds stands up at all.
"""

from __future__ import annotations

import cv2
import numpy as np

from comgrasp_pin.errors import ObjectCutByBorderError, ObjectNotFoundError
from comgrasp_pin.perception._points import (
    border_pixels,
    largest_component,
    noise_level,
    slice_medians,
)
from comgrasp_pin.perception.top_view.registration import check_registered
from comgrasp_pin.perception.top_view.rod_pieces import Gap, check_not_broken, join_pieces
from comgrasp_pin.perception.top_view.rod_shape import check_one_object, reaching_border
from comgrasp_pin.perception.top_view.table_view import (
    TableView,
    differs_in_colour,
    in_area,
    over_the_edge,
)

MIN_HEIGHT = 0.003  # a pixel counts as object if it stands this far above the table (m)
MAX_HEIGHT = 0.15  # ... and no higher than this (the robot above the table is not the rod)
MIN_PIXELS = 40
# In a cleaned image (``table_view``): a pixel stands on the table this many camera noise
# stds above it, and gaps of up to 4 px close.
HEIGHT_SIGMAS = 2.5
CLOSE_KERNEL = np.ones((5, 5), np.uint8)
TABLE_CLEAR = np.ones((9, 9), np.uint8)  # the table's noise is measured this far from what
# stands on it (``bare_table``)
MARK_PLACES = 20  # a colour mark's height noise: its shape laid at this many places at least
DETECT_SNR = 4.0  # what stands lower than this many noise stds (its median; after the
# cleaning's median) is not told from the noise's own bumps by its height ...
BUMP_FALSE_ALARM = 1e-3  # ... but by its size: larger than the view's bumps grow but with this
# probability (``largest_bump``)
MIN_BUMPS = 8  # fewer bumps in the pick area: their size is not measured (the height decides)
EDGE_BAND = 0.01  # the table's height and noise are measured this far inside its edge (m)


Segments = tuple[np.ndarray, np.ndarray, np.ndarray, bool, float]


def segment(view: TableView, pick_area, rgb) -> Segments:
    """(rod's mask, standing pixels, their unmeasured ones, meets border?, largest bump).

    That is: the rod's mask, the pixels standing on the table, those whose depth does not
    measure them, whether the rod reaches the image's border, and the area (px) that a blob
    of the noise's own reaches but rarely (``largest_bump``; inf where not measured). The
    first three (H, W) bool; the third are the standing pixels that the colour found or the
    closing filled in: their depth does not measure their height.

    The threshold follows the camera's own noise (the median's heights beside a tall head
    are biased by the noise before it); in a cleaned image gaps of a few pixels close (a
    thin rod broken by holes at its edges is one rod), and with a colour image ``rgb`` the
    pixels that differ from the table in colour stand too (a lit top may look like the
    table, a thin rod's ends are lost in the noise), in a blob whose median height stands
    above the table (a mark or a shadow does not), and only where it lines up with the
    depth (``registration.check_registered``). Raises ObjectNotFoundError,
    ObjectCutByBorderError, AmbiguousObjectError (a second object; ClutterError for more),
    ColourDepthMismatchError, and ColourNoHelp where the colour marks none of the object.
    """
    z = view.points[..., 2]
    height = z - view.table_z
    inside = in_area(view.points, pick_area, EDGE_BAND) & np.isfinite(z)
    min_height = stands_at(view)
    standing = (z > view.table_z + min_height) & (z < view.table_z + MAX_HEIGHT)
    in_depth = standing
    if view.cleaned and rgb is not None:
        colour = differs_in_colour(rgb, inside) & inside & (z < view.table_z + MAX_HEIGHT)
        if not check_registered(colour, closed(in_depth) & inside):
            raise ColourNoHelp
        standing = without_marks(closed(standing | colour), inside, in_depth, height, min_height)
    elif view.cleaned:
        standing = closed(standing)
    mask = largest_component(inside & standing, MIN_PIXELS, "top-down image")
    gaps: list[Gap] = []
    if view.cleaned:  # a rod broken apart by the noise, joined again
        mask, bridge, gaps = join_pieces(view.points, inside & standing, mask, view.table_z)
        standing = standing | bridge
    objects = inside & standing
    bump_px = float("inf")
    if view.cleaned:
        bumps, areas = noise_bumps(objects & ~mask, height, DETECT_SNR * view.points_noise)
        objects &= ~bumps
        bump_px = largest_bump(areas)
    pieces = np.zeros_like(mask)  # of the rod, on its axis, not joined
    for gap in gaps:
        pieces |= gap.piece
    # other objects are the reason to refuse first; then pieces that may be the rod's
    check_one_object(objects & ~pieces, mask, at_edge=reaching_border(standing))
    check_not_broken(objects, mask, gaps)
    if border_pixels(mask).any():
        raise ObjectCutByBorderError(
            "the object runs out of the top-down image (inside the pick area): part of it is "
            "out of view, so its extent and centre are not known; move it, or the camera"
        )
    if view.cleaned and rgb is not None:
        median, least = _stands(height, mask, bare_table(inside, standing), min_height)
        if not median >= least:
            raise _mark(median, least)
    mask, rod_standing = over_the_edge(view, mask, inside, standing, in_depth, min_height)
    return mask, rod_standing, standing & ~in_depth, bool(border_pixels(mask).any()), bump_px


def stands_at(view: TableView) -> float:
    """The height above the table at which a pixel stands (m).

    MIN_HEIGHT, or HEIGHT_SIGMAS of the camera's noise where that is higher.
    """
    return max(MIN_HEIGHT, HEIGHT_SIGMAS * view.noise)


def bare_table(area: np.ndarray, standing: np.ndarray) -> np.ndarray:
    """(H, W) bool: the bare table, where its noise is measured.

    That is: the pixels of ``area`` at least TABLE_CLEAR from what is ``standing`` (both
    (H, W) bool).
    """
    return area & ~cv2.dilate(standing.astype(np.uint8), TABLE_CLEAR).astype(bool)


def noise_bumps(
    blobs: np.ndarray, height: np.ndarray, least: float
) -> tuple[np.ndarray, np.ndarray]:
    """((H, W) bool, (n,) int): the noise's own bumps among ``blobs`` ((H, W) bool), areas.

    That is: the 8-connected blobs whose median ``height`` ((H, W), m) is below ``least``
    (m), which no height tells from an object, and their areas (px).
    """
    count, labels, stats, _ = cv2.connectedComponentsWithStats(blobs.astype(np.uint8),
                                                               connectivity=8)  # fmt: skip
    found = labels > 0
    ids, medians = slice_medians(labels[found], (height[found],), 1)
    low = np.zeros(count, bool)
    low[ids[medians[:, 0] < least]] = True
    return low[labels], stats[low, cv2.CC_STAT_AREA]


def largest_bump(areas: np.ndarray) -> float:
    """The area (px) the largest of the view's noise bumps exceeds but rarely.

    That is: with probability BUMP_FALSE_ALARM; inf where fewer than MIN_BUMPS bumps were
    seen (not measured).

    A Gaussian field's blobs above a high threshold have exponentially distributed areas
    (its excursion sets: tests/test_noise_bumps.py on such fields; the structured-light
    frames of ``benchmarks/unseen`` follow it to the tail, docs/design.md). With n bumps
    of mean area a (taken at its upper two-sigma bound, a (1 + 2 / sqrt(n))), the largest
    of n exceeds a ln(n / alpha) with probability alpha. ``areas``: the bumps' areas (px,
    ``noise_bumps``).
    """
    n = len(areas)
    if n < MIN_BUMPS:
        return float("inf")
    mean = float(np.mean(areas)) * (1 + 2 / np.sqrt(n))
    return mean * float(np.log(n / BUMP_FALSE_ALARM))


def median_noise(height: np.ndarray, blob: np.ndarray, table: np.ndarray) -> float:
    """The noise (m, robust std) of the median ``height`` over a blob of ``blob``'s shape.

    Measured, not modelled: the blob's shape is laid over the image at places on a grid, and
    the spread of the medians of ``height`` ((H, W), m) over its pixels that land on the bare
    ``table`` ((H, W) bool) is taken, where at least half of them do (a long rod's shape
    fits nowhere whole; a median over fewer pixels scatters more, so the noise is not
    underestimated). The depth's noise is correlated over a few pixels, which no count of
    pixels would say. NaN where fewer than MARK_PLACES places hold half the shape.
    """
    rows, cols = np.nonzero(blob)
    rows, cols = rows - rows.min(), cols - cols.min()
    h, w = table.shape
    steps = int(np.ceil(np.sqrt(16 * MARK_PLACES)))
    medians = []
    for r0 in np.linspace(-rows.max(), h - 1, steps).astype(int):
        for c0 in np.linspace(-cols.max(), w - 1, steps).astype(int):
            r, c = rows + r0, cols + c0
            seen = (r >= 0) & (r < h) & (c >= 0) & (c < w)
            on = np.zeros(len(r), bool)
            on[seen] = table[r[seen], c[seen]]
            if 2 * on.sum() >= len(r):
                medians.append(np.median(height[r[on], c[on]]))
    return noise_level(np.array(medians)) if len(medians) >= MARK_PLACES else float("nan")


def without_marks(standing: np.ndarray, inside: np.ndarray, in_depth: np.ndarray,
                  height: np.ndarray, min_height: float) -> np.ndarray:  # fmt: skip
    """``standing`` less the marks: what the colour adds that does not stand.

    A blob of ``inside & standing`` (of MIN_PIXELS or more) that the depth sees standing
    (``in_depth``) in less than half of its pixels is a mark or a shadow where its median
    ``height`` does not stand above the noise of such a median (``_stands``): a pattern on
    the table, or the table's edge in a colour image a few pixels off the depth. It is no
    object, to count or to measure. All (H, W); ``height`` above the table (m);
    ``min_height``: a pixel's threshold (``stands_at``). ObjectNotFoundError when nothing
    else as large is there.
    """
    count, labels, stats, _ = cv2.connectedComponentsWithStats(
        (inside & standing).astype(np.uint8), connectivity=8)  # fmt: skip
    areas = stats[:, cv2.CC_STAT_AREA]
    seen = np.bincount(labels[in_depth & standing], minlength=count)
    large = [k for k in range(1, count) if areas[k] >= MIN_PIXELS]
    table = bare_table(inside, standing)
    marks = []  # (area, label, median, least)
    for k in large:
        if 2 * seen[k] < areas[k]:
            median, least = _stands(height, labels == k, table, min_height)
            if not median >= least:
                marks.append((areas[k], k, median, least))
    if marks and len(marks) == len(large):
        raise _mark(*max(marks)[2:])
    return standing & ~np.isin(labels, [k for _, k, _, _ in marks])


def _stands(height: np.ndarray, blob: np.ndarray, table: np.ndarray,
            min_height: float) -> tuple[float, float]:  # fmt: skip
    """(median ``height`` over ``blob``, the least it must be to stand), m.

    The least: DETECT_SNR times the noise of such a median (``median_noise`` on the bare
    ``table``), not below MIN_HEIGHT; ``min_height`` where that noise is not measured.
    """
    median = float(np.median(height[blob]))
    noise = median_noise(height, blob, table)
    return median, max(MIN_HEIGHT, DETECT_SNR * noise) if np.isfinite(noise) else min_height


def _mark(median: float, least: float) -> ObjectNotFoundError:
    return ObjectNotFoundError(
        f"what differs from the table in colour stands {1e3 * median:.1f} mm above it "
        f"(less than {1e3 * least:.1f} mm): a mark or a shadow, not an object"
    )


def closed(mask: np.ndarray) -> np.ndarray:
    """``mask`` with gaps of a few pixels closed (CLOSE_KERNEL)."""
    return cv2.morphologyEx(mask.astype(np.uint8), cv2.MORPH_CLOSE, CLOSE_KERNEL) > 0


class ColourNoHelp(Exception):
    """The colour does not mark what the depth sees standing: it cannot help the depth."""
