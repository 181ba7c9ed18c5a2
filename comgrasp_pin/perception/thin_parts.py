"""Does a thin part go on from the object, too low for the depth's threshold? A mallet's handle.

On a noisy depth image (a structured-light camera's, a table far away) a handle under 1 cm
high does not stand above the height threshold pixel by pixel, and what the top view finds
is the tool's head alone: a measurement of the wrong object, with nothing to say so. Along
a line the handle does stand out: the mean height of a strip LENGTH long, one pixel wide,
has a noise several times smaller than a pixel's. From the object's outline, rays are cast
every degree (OpenCV ``warpPolar`` around its centre); the mean height of each ray's
stretch beyond the outline, of each of LENGTHS, is compared with the same mean's noise
measured on the table (strips of the same length along the image's rows and columns, away
from the object).
"""

from __future__ import annotations

import cv2
import numpy as np

from comgrasp_pin.errors import UntrustedImageError
from comgrasp_pin.perception._points import noise_level

LENGTHS = (0.08, 0.16)  # the stretches of each ray looked at beyond the outline (m)
GAP = 0.01  # ... starting this far beyond it (m): the outline's own fringe and smear
SIGMAS = 4.0  # a stretch this many of its noise stds above the table is a thin part
MIN_MEAN = 0.003  # ... and at least this high (m): the top view's least height of an object
# (a cord or a cable lower than that is no part of a rod's extent in any image)
ANGLES = 360
_KERNEL5 = np.ones((5, 5), np.uint8)


def check_no_thin_part(heights: np.ndarray, mask: np.ndarray, table: np.ndarray,
                       px_per_m: float) -> None:  # fmt: skip
    """UntrustedImageError when a thin part lower than the threshold goes on from ``mask``.

    ``heights``: (H, W) heights above the table (m, NaN where none); ``mask``: (H, W) bool,
    the object found; ``table``: (H, W) bool, the pixels that see the empty table (where the
    noise is measured); ``px_per_m``: pixels per metre on the table at the object.
    """
    rows, cols = np.nonzero(mask)
    centre = (float(cols.mean()), float(rows.mean()))
    gap_px = max(2, int(round(GAP * px_per_m)))
    longest = max(5, int(round(max(LENGTHS) * px_per_m)))
    reach = np.hypot(rows - centre[1], cols - centre[0]).max() + gap_px + longest + 2
    size = (int(reach), ANGLES)  # (radius samples, angles): a row per angle
    flags = cv2.INTER_LINEAR | cv2.WARP_POLAR_LINEAR | cv2.WARP_FILL_OUTLIERS
    h = cv2.warpPolar(np.nan_to_num(heights).astype(np.float32), size, centre, reach, flags)
    seen = cv2.warpPolar(np.isfinite(heights).astype(np.float32), size, centre, reach, flags)
    inside = cv2.warpPolar(mask.astype(np.float32), size, centre, reach, flags) > 0.5
    radius = np.arange(h.shape[1])
    start = np.where(inside, radius, 0).max(axis=1) + gap_px  # beyond the outline, per ray
    for length in LENGTHS:
        length_px = max(5, int(round(length * px_per_m)))
        noise = _stretch_noise(heights, table, length_px)
        if not np.isfinite(noise) or noise <= 0:
            continue
        stretch = (radius >= start[:, None]) & (radius < (start + length_px)[:, None])
        stretch &= seen > 0.5
        counts = stretch.sum(axis=1)
        means = np.where(counts > length_px // 2,
                         (h * stretch).sum(axis=1) / np.maximum(counts, 1), 0.0)  # fmt: skip
        k = int(np.argmax(means))
        if means[k] > max(SIGMAS * noise, MIN_MEAN):
            raise UntrustedImageError(
                f"a thin part lower than the depth can tell pixel by pixel goes on from the "
                f"object (at {360.0 * k / ANGLES:.0f} deg in the image from its centre, u to "
                f"v: {1e3 * means[k]:.1f} mm high on average over {1e2 * length:.0f} cm, the "
                f"table's noise over the same stretch {1e3 * noise:.1f} mm): a handle? Its "
                "extent is not known from this depth; view it closer or with a less noisy "
                "camera"
            )


def _stretch_noise(heights: np.ndarray, table: np.ndarray, length_px: int) -> float:
    """The noise (m, robust std) of a stretch's mean height on the empty ``table``."""
    h = np.where(table & np.isfinite(heights), heights, 0.0).astype(np.float32)
    w = (table & np.isfinite(heights)).astype(np.float32)
    means = []
    for kernel in (np.ones((1, length_px), np.float32), np.ones((length_px, 1), np.float32)):
        total = cv2.filter2D(h, -1, kernel, borderType=cv2.BORDER_CONSTANT)
        count = cv2.filter2D(w, -1, kernel, borderType=cv2.BORDER_CONSTANT)
        means.append(total[count >= length_px - 0.5] / length_px)
    values = np.concatenate(means)
    return noise_level(values) if len(values) > 100 else float("nan")
