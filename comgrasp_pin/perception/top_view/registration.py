"""Do the colour image and the depth image line up? Colour is used only where they do.

Many real colour/depth pairs are not registered (the depth not aligned to the colour
camera, or aligned with the wrong extrinsics): the object sits at other pixels in each.
Trusted pixel for pixel, such a colour mask keeps the part of the object where the two
happen to overlap (a mallet cut to its head). What the depth sees standing is compared with
the colour's mask moved by every shift up to MAX_SEARCH_PX (OpenCV ``matchTemplate``): no
shift beyond MAX_SHIFT_PX may mark GAIN more of it than none, and the colour must mark most
of it.
"""

from __future__ import annotations

import cv2
import numpy as np

from comgrasp_pin.errors import ColourDepthMismatchError

MAX_SHIFT_PX = 2.0  # the outlines may differ by this much (a pixel's rounding each side)
MIN_COVER = 0.5  # the colour must mark this share of the depth's object (its core)
MAX_SEARCH_PX = 40  # shifts of the colour looked at, each way (px)
GAIN = 0.1  # a shift that marks this much more of the object than none says: not registered
MIN_MATCH = 0.8  # ... where, moved, the colour marks at least this share of it (a light's
# patch or a texture that marks some of it anywhere is no sign of a shift)
_KERNEL3 = np.ones((3, 3), np.uint8)


def cover_by_shift(colour_mask: np.ndarray, core: np.ndarray) -> tuple[float, float, np.ndarray]:
    """(share of ``core`` the colour marks as it is, the best share over shifts, that shift).

    ``core``: (H, W) bool, the object the depth sees (its interior); the shift (du, dv) px,
    up to MAX_SEARCH_PX each way, is where the colour mask would have to move to mark most
    of it.
    """
    rows, cols = np.nonzero(core)
    r0, r1, c0, c1 = rows.min(), rows.max() + 1, cols.min(), cols.max() + 1
    template = core[r0:r1, c0:c1].astype(np.float32)
    padded = np.pad(colour_mask, MAX_SEARCH_PX).astype(np.float32)
    window = padded[r0 : r1 + 2 * MAX_SEARCH_PX, c0 : c1 + 2 * MAX_SEARCH_PX]
    score = cv2.matchTemplate(window, template, cv2.TM_CCORR) / template.sum()
    # of the shifts that mark the most (several, where the colour's mask is wider than the
    # depth's core), the least
    best = np.argwhere(score >= score.max() - 1e-6) - MAX_SEARCH_PX
    dv, du = best[np.argmin(np.hypot(best[:, 0], best[:, 1]))]
    at_zero = float(score[MAX_SEARCH_PX, MAX_SEARCH_PX])
    return at_zero, float(score.max()), np.array([du, dv])


def check_registered(colour_mask: np.ndarray, depth_mask: np.ndarray) -> bool:
    """Whether the colour may help the depth; ColourDepthMismatchError if they disagree.

    They disagree when the colour, moved by more than MAX_SHIFT_PX, marks GAIN more of what
    the depth sees than where it is, and at least MIN_MATCH of it.

    ``colour_mask``: (H, W) bool, the pixels that differ from the table in colour;
    ``depth_mask``: (H, W) bool, the object the depth sees standing. Returns False (the
    colour is no help, not a contradiction) when the depth sees too little to compare or
    the colour marks most of it neither where it is nor moved (an object of the table's
    colour, a textured table).

    Raises:
        ColourDepthMismatchError: the colour's outline sits more than MAX_SHIFT_PX from the
            depth's: the pair is not registered.
    """
    core = cv2.erode(depth_mask.astype(np.uint8), _KERNEL3).astype(bool)
    if np.count_nonzero(core) < 20 or not colour_mask.any():
        return False
    cover, best, shift = cover_by_shift(colour_mask, core)
    if best < MIN_COVER:  # the colour marks the object nowhere (its colour is the table's)
        return False
    if np.hypot(*shift) > MAX_SHIFT_PX and best > max(cover + GAIN, MIN_MATCH):
        raise ColourDepthMismatchError(
            f"colour and depth do not line up: the object's outline in colour sits "
            f"({shift[0]:+.0f}, {shift[1]:+.0f}) px (u, v) from its outline in depth; are they "
            "registered (the depth aligned to the colour camera)? Measure from the depth "
            "alone (no colour image), or register the pair"
        )
    return cover >= MIN_COVER
