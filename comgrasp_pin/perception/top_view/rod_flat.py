"""Does a rod lie flat on the table? A head turned on its side props one end up.

After a slip, pick-and-place lays a rod down; its head (obj1's weight, obj7's hammer head)
may come to rest turned on its side and prop one end of the handle up. From above, the
handle's top then rises steadily along it, while a rod lying on the table keeps one height
along its handle (a tapered body's top follows its width). The top view names such a rod
when it refuses it (``rod_shape.check_one_rod``), rather than calling it two rods. World
frame, m.
"""

from __future__ import annotations

import numpy as np

from comgrasp_pin.perception._points import slice_medians, slice_percentiles

MIN_SLICES = 6  # slices of 10 points or more, at least
FLAT_RISE = 0.01  # m: tops rising this much end to end, and their high end this far above
# the slices' width ...
FLAT_FIT = 0.6  # ... with this share of the tops ...
FLAT_BAND = 0.003  # ... within this (m, or 3 noise stds) of one line: not lying flat


def propped_ends(
    p: np.ndarray,
    centroid: np.ndarray,
    direction: np.ndarray,
    table_z: float,
    noise: float,
    measured: np.ndarray | None,
    slice_m: float,
) -> tuple[float, float] | None:
    """(the top's height at the rod's two ends) (m) where its tops rise steadily, else None.

    A slice's (``slice_m`` long, m) top: the 90th percentile of its measured heights (10 or
    more); the line: Theil-Sen's (a head's few slices do not move it). Steadily: FLAT_RISE
    or more end to end, FLAT_FIT of the tops within FLAT_BAND or 3 ``noise`` stds of the
    line, and its high end FLAT_RISE above those slices' median width (a tapered body lying
    flat, whose top is its width, is not propped). ``p`` (N, 3): the blob's points (world,
    m), along ``direction`` (2,) through ``centroid`` (2,); ``table_z`` (m); ``noise``: the
    heights' std (m); ``measured`` (N,) bool or None: the points whose height the depth
    measured.
    """
    keep = np.ones(len(p), bool) if measured is None else measured
    rel, height = p[keep, :2] - centroid, p[keep, 2] - table_z
    along, across = rel @ direction, rel @ np.array([-direction[1], direction[0]])
    slices = np.floor(along / slice_m).astype(int)
    x = slice_medians(slices, (along,), 10)[1][:, 0]
    if len(x) < MIN_SLICES:
        return None
    top = slice_percentiles(slices, height, (90,), 10)[1][:, 0]
    lowest, highest = slice_percentiles(slices, across, (0, 100), 10)[1].T
    width = highest - lowest
    i, j = np.triu_indices(len(x), 1)
    slope = float(np.median((top[j] - top[i]) / (x[j] - x[i])))
    offset = float(np.median(top - slope * x))
    on_line = np.abs(top - (slope * x + offset)) < max(FLAT_BAND, 3 * noise)
    ends = slope * x[[0, -1]] + offset
    flat = abs(ends[1] - ends[0]) < FLAT_RISE or on_line.mean() < FLAT_FIT
    if flat or max(ends) < np.median(width[on_line]) + FLAT_RISE:
        return None
    return float(ends[0]), float(ends[1])
