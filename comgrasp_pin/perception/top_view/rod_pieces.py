"""Pieces of one rod that a noisy depth image broke apart, joined again (top view).

A structured-light camera's depth at 1.25 m loses a rod's pixels in patches (its noise, the
projector's shadow beside a tall head): one hammer stands as two blobs on one line, which
the count of objects would take for two objects. A piece is joined to the rod when it lies
on the rod's axis (its centroid within MAX_OFFSET of it), beyond one of its ends by at most
MAX_GAP, and the gap between them stands above the table: its pixels' mean height at least
BRIDGE_SHARE of the lower piece's median height (the gap as wide as the rod's end that faces
the piece, not as its head). A piece on the axis that is not joined refuses the frame as
another object would (``rod_shape.check_one_object``), named with the gap's length and height
(``check_not_broken``): two objects end to end (table seen between them), or one rod whose
gap the depth's noise holds down (the gap is where the noise broke the rod, so its lowest
stretch: on a structured-light camera at 1.25 m, 8-10 mm of a 20 mm handle, 1.8-3.4 noise
stds of a median over the gap's shape on bare table).
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from comgrasp_pin.errors import AmbiguousObjectError
from comgrasp_pin.perception._points import opened_blobs
from comgrasp_pin.perception.top_view.rod_shape import MIN_OBJECT_PX, SECOND_OBJECT

MAX_OFFSET = 0.015  # m: a piece's centroid this near the rod's axis lies on it ...
MAX_GAP = 0.05  # ... and one this far at most beyond the rod's end (m) may be part of it
BRIDGE_SHARE = 0.5  # ... when the gap's mean height is this share of the lower piece's
MIN_BRIDGE_HALF_WIDTH = 0.004  # m: the gap is looked at this far either side of the axis
MIN_PIECE = 10  # px: a smaller blob is noise


def join_pieces(points: np.ndarray, standing: np.ndarray, mask: np.ndarray,
                table_z: float) -> tuple[np.ndarray, np.ndarray, list[Gap]]:  # fmt: skip
    """(the rod's mask, pieces joined; the gaps' pixels joined; the gaps not joined).

    The last: the gaps to the pieces that lie on the rod's axis and were not joined.
    ``points``: (H, W, 3) every pixel in the world (m, NaN where none); ``standing``: (H, W)
    bool, what stands on the table in the pick area; ``mask``: the rod's largest blob;
    ``table_z``: the table's height (m). Blobs of MIN_PIECE pixels or more are looked at.
    """
    count, labels, stats = opened_blobs(standing)
    mask, bridge = mask.copy(), np.zeros_like(mask)
    pieces = [k for k in range(1, count) if stats[k, cv2.CC_STAT_AREA] >= MIN_PIECE
              and not np.any(mask[labels == k])]  # fmt: skip
    joined = True
    left: list[Gap] = []
    while joined:  # until a pass over the pieces joins none: its gaps are those left
        joined, left = False, []
        for k in pieces:
            gap = _gap_if_on_axis(points, mask, labels == k, table_z)
            if gap is not None and gap.stands:
                mask |= (labels == k) | gap.pixels
                bridge |= gap.pixels & ~standing
                pieces.remove(k)
                joined = True
                break
            if gap is not None:
                left.append(gap)
    return mask, bridge, left


@dataclass(frozen=True)
class Gap:
    """Between the rod's end and a piece on its axis beyond it (m, above the table).

    Attributes:
        pixels: (H, W) bool, the gap's.
        piece: (H, W) bool, the piece's.
        length: along the axis.
        mean: the gap's mean height.
        least: the mean at which it stands: BRIDGE_SHARE of the lower piece's median.
    """

    pixels: np.ndarray
    piece: np.ndarray
    length: float
    mean: float
    least: float

    @property
    def stands(self) -> bool:
        """Whether the gap is the rod's: no pixel seen in it, or its mean at least least."""
        return not self.pixels.any() or self.mean >= self.least


def check_not_broken(objects: np.ndarray, mask: np.ndarray, gaps: list[Gap]) -> None:
    """AmbiguousObjectError for a piece on the rod's axis, named as what it may be.

    That is, for a piece of ``gaps`` that ``rod_shape.check_one_object`` would count as
    another object among ``objects`` beside the rod's ``mask`` (both (H, W) bool).
    """
    least = max(MIN_OBJECT_PX, SECOND_OBJECT * int(mask.sum()))  # (as check_one_object)
    large = [g for g in gaps if np.count_nonzero(g.piece & objects) >= least]
    if large:
        g = max(large, key=lambda g: int(g.piece.sum()))
        raise AmbiguousObjectError(
            f"a piece of {int(g.piece.sum())} px lies on the rod's axis "
            f"{1e3 * g.length:.0f} mm beyond its end, and the depth between them stands "
            f"{1e3 * g.mean:.1f} mm on average, short of the {1e3 * g.least:.1f} mm that "
            "would make them one rod: two objects end to end, or one rod that the depth's "
            "noise broke apart? The top view measures one rod alone on the table: clear the "
            "other, or view it closer or with a less noisy camera"
        )


def _gap_if_on_axis(points, mask, piece, table_z) -> Gap | None:
    """The gap between ``mask`` and ``piece`` if the piece lies on the rod's axis."""
    p_rod, p_piece = points[mask], points[piece]
    p_rod, p_piece = p_rod[np.isfinite(p_rod[:, 2])], p_piece[np.isfinite(p_piece[:, 2])]
    if len(p_rod) < 3 or len(p_piece) < 3:
        return None
    centre = p_rod[:, :2].mean(axis=0)
    axis = np.linalg.svd(p_rod[:, :2] - centre, full_matrices=False)[2][0]
    normal = np.array([-axis[1], axis[0]])
    if abs(float((p_piece[:, :2].mean(axis=0) - centre) @ normal)) > MAX_OFFSET:
        return None
    rod_along, piece_along = (p_rod[:, :2] - centre) @ axis, (p_piece[:, :2] - centre) @ axis
    lo, hi = float(rod_along.min()), float(rod_along.max())
    if piece_along.min() >= hi:
        start, end = hi, float(piece_along.min())
    elif piece_along.max() <= lo:
        start, end = float(piece_along.max()), lo
    else:
        return None  # beside the rod, not beyond an end
    if end - start > MAX_GAP:
        return None
    near_end = np.abs(rod_along - (hi if start == hi else lo)) < MAX_GAP  # the end it faces:
    widths = np.percentile((p_rod[near_end, :2] - centre) @ normal, [10, 90])  # (not a head)
    half = max(MIN_BRIDGE_HALF_WIDTH, 0.5 * float(widths[1] - widths[0]))
    xy = points[..., :2] - centre
    along, across = xy @ axis, xy @ normal
    gap = np.isfinite(points[..., 2]) & (along > start) & (along < end) & (np.abs(across) < half)
    lower = min(float(np.median(p_rod[:, 2])), float(np.median(p_piece[:, 2]))) - table_z
    mean = float(np.mean(points[gap][:, 2])) - table_z if gap.any() else 0.0
    return Gap(gap, piece, end - start, mean, BRIDGE_SHARE * lower)
