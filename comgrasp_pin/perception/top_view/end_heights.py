"""Does the object stand up to its ends? A handle that slopes or fades into the table.

The top view's object is what stands above its height threshold (``standing.stands_at``).
Where the object's height falls steeply to the table at an end (a rod's end face, a head's
side), the threshold is crossed at the end. Where it slopes down into the table (a mallet's
handle lying on its head at one end and on the table at the other; a thin handle that a
smoothing depth camera sees lower towards its tip), the threshold is crossed where the depth
lost the object, short of its end: the object would be measured short, with nothing to say
so. On GQ-CNN's PrimeSense frame of a toy mallet, the handle's top falls from 8 mm to 2 mm
over its last 4 cm seen and goes on 3 cm further at 1 mm; the object stood 10 cm of 13.

An end slopes into the table when, next to it, the object stands near the threshold and
lower than just behind: over END_SPAN inside the end (from ``inset`` inside, a cleaned
depth's blur) the heights' median is less than END_MARGIN times the threshold, and the
median over the next BEHIND_SPAN inwards stands higher by DECLINE_SHARE of the threshold
and DECLINE_SIGMAS stds of that difference. A thin handle near a noisy depth's threshold with a
square end (obj1's 1 cm handle in the realistic preset) keeps its height up to the end:
flat within its noise, it is not refused.
An end the colour image found (pixels the depth does not measure) is the colour's.
"""

from __future__ import annotations

import numpy as np

from comgrasp_pin.errors import UntrustedImageError

END_SPAN = 0.005  # m: the stretch next to each end ...
BEHIND_SPAN = 0.01  # m: ... and the one behind it ...
END_MARGIN = 1.5  # ... the first stands less than this many times the height threshold ...
DECLINE_SHARE = 0.5  # ... and lower than the second by this share of the threshold ...
DECLINE_SIGMAS = 4.0  # ... and this many stds of the difference of their medians
MIN_END_PX = 5  # measured pixels in each stretch, at least (fewer: not judged)
FILTER_PX = 25  # a cleaned depth's pixels come from 5 x 5 medians: this many share their noise
CLEANED_PX = 2  # px: a cleaned depth's stretch begins this far inside the end


def check_ends_stand(
    points: np.ndarray,
    mask: np.ndarray,
    unmeasured: np.ndarray,
    table_z: float,
    centroid: np.ndarray,
    direction: np.ndarray,
    threshold: float,
    noise: float,
    inset: float = 0.0,
) -> None:
    """UntrustedImageError when the object's height slopes into the threshold at an end.

    ``points``: (H, W, 3) every pixel in the table's frame (m, NaN where none); ``mask``,
    ``unmeasured``: (H, W) bool, the object's pixels and those the depth does not measure
    (found by colour, or closed over); ``table_z`` (m); ``direction`` (2,) its axis through
    ``centroid`` (2,); ``threshold`` (m): the height at which a pixel stands; ``noise`` (m):
    a pixel's height noise (std); ``inset`` (m): how far inside each end the first stretch
    begins (a cleaned depth's blur; its pixels' noise is then shared by FILTER_PX).
    """
    along = (points[mask][:, :2] - centroid) @ direction
    height = points[mask][:, 2] - table_z
    measured = ~unmeasured[mask] & np.isfinite(height)
    shared = FILTER_PX if inset > 0 else 1
    for sign, end in ((-1, along.min()), (+1, along.max())):
        inside = sign * (end - along)  # how far inside the end (m)
        first = (inside >= inset) & (inside < inset + END_SPAN)
        behind = (inside >= inset + END_SPAN) & (inside < inset + END_SPAN + BEHIND_SPAN)
        if np.count_nonzero(first & ~measured):
            continue  # the colour's end
        counts = [np.count_nonzero(s & measured) for s in (first, behind)]
        if min(counts) < MIN_END_PX:
            continue  # too few pixels to judge
        top, back = (float(np.median(height[s & measured])) for s in (first, behind))
        # a median's std is about 1.25 stds / sqrt(n) (n: pixels whose noise is their own)
        spread = 1.25 * noise * np.sqrt(sum(shared / c for c in counts))
        declines = back - top > max(DECLINE_SHARE * threshold, DECLINE_SIGMAS * spread)
        if top < END_MARGIN * threshold and declines:
            raise UntrustedImageError(
                f"the object's height slopes into the table at its {'+' if sign > 0 else '-'}"
                f"yaw end: its last {1e3 * END_SPAN:.0f} mm stand {1e3 * top:.1f} mm, less "
                f"than {END_MARGIN:g} times the {1e3 * threshold:.1f} mm at which the depth "
                f"sees it, and the cm behind {1e3 * back:.1f} mm: the depth lost it there, "
                "short of its end (a handle lying on its head, a tapering tool?): view it "
                "closer or with a less noisy camera, or give the colour image"
            )
