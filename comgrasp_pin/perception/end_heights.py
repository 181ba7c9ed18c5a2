"""Does the object stand up to its ends? A handle that slopes or fades into the table.

The top view's object is what stands above its height threshold (``standing.stands_at``).
Where the object's height falls steeply to the table at an end (a rod's end face, a head's
side), the threshold is crossed at the end. Where it slopes down into the table (a mallet's
handle lying on its head at one end and on the table at the other; a thin handle that a
smoothing depth camera sees lower towards its tip), the threshold is crossed where the depth
lost the object, short of its end: the object would be measured short, with nothing to say
so. On GQ-CNN's PrimeSense frame of a toy mallet, the handle's top falls from 8 mm to 2 mm
over its last 4 cm seen and goes on 3 cm further at 1 mm; the object stood 10 cm of 13.

An end slopes into the table when the depth's heights over END_SPAN inside it (their
median; in a cleaned depth, from CLEANED_PX inside: its 5 x 5 median blurs an end so far)
stand less than END_MARGIN times the threshold, and less than END_SHARE of the object's
own (median) height, and END_SIGMAS noise stds below it: the object stands higher, and its
height falls to the threshold at the end. A rod that stands low all along, or whose end
the noise holds down a little (a noisy depth's steps near its threshold), is not refused
here; a round end stands more than END_SHARE of its rod.
An end the colour image found (pixels the depth does not measure) is the colour's.
"""

from __future__ import annotations

import numpy as np

from comgrasp_pin.errors import UntrustedImageError

END_SPAN = 0.005  # m: the last stretch inside each end ...
END_MARGIN = 1.5  # ... stands this many times the height threshold (its median) ...
END_SHARE = 0.75  # ... or this share of the object's median height ...
END_SIGMAS = 4.0  # ... or so many noise stds below it
MIN_END_PX = 5  # measured pixels in that stretch, at least (fewer: not judged)
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
    ``centroid`` (2,); ``threshold`` (m): the height at which a pixel stands; ``noise``
    (m): a pixel's height noise (std); ``inset``
    (m): how far inside each end the stretch begins (a cleaned depth's blur).
    """
    along = (points[mask][:, :2] - centroid) @ direction
    height = points[mask][:, 2] - table_z
    measured = ~unmeasured[mask] & np.isfinite(height)
    if not measured.any():
        return
    whole = float(np.median(height[measured]))
    for sign, end in ((-1, along.min()), (+1, along.max())):
        inside = sign * (end - along)  # how far inside the end (m)
        last = (inside >= inset) & (inside < inset + END_SPAN)
        if np.count_nonzero(last & ~measured) or np.count_nonzero(last & measured) < MIN_END_PX:
            continue  # the colour's end, or too few pixels to judge
        top = float(np.median(height[last & measured]))
        low = top < END_MARGIN * threshold and top < END_SHARE * whole
        if low and whole - top > END_SIGMAS * noise:
            raise UntrustedImageError(
                f"the object's height slopes into the table at its {'+' if sign > 0 else '-'}"
                f"yaw end: {1e3 * END_SPAN:.0f} mm inside it stand {1e3 * top:.1f} mm, less "
                f"than {END_MARGIN:g} times the {1e3 * threshold:.1f} mm at which the depth "
                f"sees it while the object stands {1e3 * whole:.0f} mm, so it ends where the "
                "depth lost it, not where it ends (a handle "
                "lying on its head, a tapering tool?): view it closer or with a less noisy "
                "camera, or give the colour image"
            )
