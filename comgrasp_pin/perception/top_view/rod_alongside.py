"""A second rod alongside the first over part of its length: one of two objects, not one rod.

Two rods touching side by side over part of the length make one blob, and when the second is
the thinner or the shorter, no slice across it is split and the points' own axis turns
towards it: the pair was measured as one rod the length of the longer (MuJoCo renders of two
1-2.4 cm cylinders, 28-30 and 18-20 cm long). What tells them from a rod with a head: a
head (a hammer's, a weight, a lamp) widens the outline on both sides of the axis, a rod
alongside on one side only. Along the blob one edge of the outline then runs straight on,
while the other steps out by the second rod's width where it lies (or in, where it ends).
The edges are straightened by the slope they share (Theil-Sen); the slices of the width
most have give each edge's line; a slice of another width with one edge on its line is the
step. World frame, m.
"""

from __future__ import annotations

import numpy as np

from comgrasp_pin.errors import AmbiguousObjectError
from comgrasp_pin.perception._points import slice_percentiles
from comgrasp_pin.perception.top_view.rod_shape import MIN_SPLIT_SLICES, SLICE, SPLIT_SLICES

EDGE_PERCENTILE = 2.0  # a slice's edges across the axis: this percentile and 100 minus it
ON_LINE = 0.002  # an edge this close to its line (m) runs on ...
STEPPED = 0.005  # ... while the other steps out or in this far (m): a rod alongside there


def check_no_rod_alongside(p: np.ndarray, centroid: np.ndarray, direction: np.ndarray) -> None:
    """AmbiguousObjectError where a second rod lies alongside over part of the length.

    That is: the blob's points ``p`` (N, 3), in SLICE-wide slices across ``direction`` (2,)
    through ``centroid`` (2,), each slice's edges (EDGE_PERCENTILE) straightened by the slope
    both edges share (Theil-Sen); the slices of the width most have (within ON_LINE) give
    each edge's line. In at least SPLIT_SLICES (and MIN_SPLIT_SLICES) of the slices the
    outline is STEPPED or more wider or narrower while one edge stays within ON_LINE of its
    line (a rod's head, or its rounded end, changes both).
    """
    rel = p[:, :2] - centroid
    along = rel @ direction
    across = rel @ np.array([-direction[1], direction[0]])
    slices = np.floor(along / SLICE).astype(int)
    numbers, counts = np.unique(slices, return_counts=True)
    kept = numbers[counts >= 10]
    if len(kept) < 2 * MIN_SPLIT_SLICES:
        return
    edge = (EDGE_PERCENTILE, 100.0 - EDGE_PERCENTILE)  # np.percentile's, per kept slice
    edges = slice_percentiles(slices, across, edge, 10)[1]
    x = kept.astype(float)
    edges -= _shared_slope(x, edges) * x[:, None]
    width = edges[:, 1] - edges[:, 0]
    # the width most slices have (within ON_LINE of each other), and each edge's line there
    alike = np.abs(width[:, None] - width[None, :]) <= ON_LINE
    common = alike[np.argmax(alike.sum(axis=1))]
    line = np.median(edges[common], axis=0)
    stays = np.abs(edges - line) <= ON_LINE
    step = np.abs(width - np.median(width[common]))
    one_sided = (step >= STEPPED) & stays.any(axis=1)
    if np.count_nonzero(one_sided) >= max(MIN_SPLIT_SLICES, SPLIT_SLICES * len(kept)):
        typical = float(np.median(step[one_sided]))
        raise AmbiguousObjectError(
            f"what lies on the table is not one rod: along {np.count_nonzero(one_sided)} of "
            f"its {len(kept)} slices one side of its outline runs straight on while the other "
            f"steps out or in by about {1e3 * typical:.0f} mm (a second rod alongside over part of "
            "its length?); the top view measures one rod alone on the table: move the others away"
        )


def _shared_slope(x: np.ndarray, edges: np.ndarray) -> float:
    """The slope both edges share (``edges`` (K, 2) at ``x`` (K,), per slice).

    The median of the slopes between every two slices of each edge (Theil-Sen, pooled).
    """
    i, j = np.triu_indices(len(x), k=1)
    slopes = (edges[j] - edges[i]) / (x[j] - x[i])[:, None]
    return float(np.median(slopes))
