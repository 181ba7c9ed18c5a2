"""Does a thin part go on from the object, too low for the depth's threshold? A mallet's handle.

On a noisy depth image (a structured-light camera's, a table far away) a handle under 1 cm
high does not stand above the height threshold pixel by pixel, and what the top view finds
is the tool's head alone: a measurement of the wrong object, with nothing to say so. Along
a line the handle does stand out: the mean height of a strip a few cm long, one pixel
wide, has a noise several times smaller than a pixel's. From the object's outline, rays are
cast every degree (OpenCV ``warpPolar`` around its centre) and followed outwards; a
stretch's mean height is compared with the same stretch's noise measured on the table
(strips along the image's rows and columns, away from the object). Only what is too low to
stand is looked at: the robot's own parts in view (``robot_parts``: a gripper's fingers at
the image's edge) are never taken for a handle, and other objects are counted as such.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from comgrasp_pin.errors import UntrustedImageError
from comgrasp_pin.perception._points import noise_level
from comgrasp_pin.perception.top_view.rod_shape import reaching_border
from comgrasp_pin.perception.top_view.standing import MAX_HEIGHT, bare_table

GAP = 0.01  # rays are followed from this far beyond the outline (m): its fringe and smear
STEP = 0.01  # a part is followed along a ray in windows this long (m) up to the first
BARE_SIGMAS = 1.0  # ... whose mean is less than this many of its noise stds above the
# table: bare table, the part joined to the object ends there
BARE_NOISE = 0.001  # (windows 2 or 4 STEP long where a STEP's mean is noisier than this, m)
LENGTHS = (0.08, 0.16)  # a stretch of a ray this long beyond the fringe whose mean height
SIGMAS = 4.0  # ... stands this many of its noise stds above the table
MIN_MEAN = 0.003  # ... and at least this high (m): the top view's least height of an object
# (a cord or a cable lower than that is no part of a rod's extent in any image)
MIN_EXTENT = 0.02  # or a joined part at least this long (m) ...
JOINED_SIGMAS = 8.0  # ... whose mean height stands this many of its noise stds above the
# table (a realistic camera's smear at a rod's end: 4-5)
MIN_JOINED = 0.0005  # ... and at least this high (m): the table's own unevenness
ANGLES = 360
ROD_ASPECT = 3.0  # an object shorter than this many times its width is not a rod's shape
_KERNEL5 = np.ones((5, 5), np.uint8)


@dataclass(frozen=True)
class ThinPart:
    """A thin part found going on from the object.

    Along the ray at ``angle_deg`` (in the image from the object's centre, u to v),
    ``mean`` (m) high on average over ``length`` (m) joined to it, where the table's noise
    over the same stretch is ``noise`` (m).
    """

    angle_deg: float
    mean: float
    length: float
    noise: float


def check_no_thin_part(heights: np.ndarray, mask: np.ndarray, table: np.ndarray,
                       px_per_m: float) -> None:  # fmt: skip
    """UntrustedImageError when a thin part goes on from ``mask`` (``find_thin_part``)."""
    part = find_thin_part(heights, mask, table, px_per_m)
    if part is not None:
        refuse_thin_part(part)


def find_thin_part(heights: np.ndarray, mask: np.ndarray, table: np.ndarray,
                   px_per_m: float) -> ThinPart | None:  # fmt: skip
    """The thin part lower than the threshold that goes on from ``mask``, or None.

    ``heights``: (H, W) heights above the table (m, NaN where none); ``mask``: (H, W) bool,
    the object found; ``table``: (H, W) bool, the pixels that see the empty table (where the
    noise is measured); ``px_per_m``: pixels per metre on the table at the object.

    ``heights`` holds only what is too low to stand (NaN elsewhere, and on the robot's own
    parts: ``robot_parts``).
    Each ray is followed from where it is GAP from the object (beyond its fringe; along a
    long rod's side, beyond its end). A thin part is a stretch of each of LENGTHS whose
    mean height stands SIGMAS of its noise and MIN_MEAN above the table (a handle beyond
    the projector's shadow too), or the part joined to the object (up to the first window
    of bare table, ``BARE_SIGMAS``) at least MIN_EXTENT long whose own mean stands
    JOINED_SIGMAS and MIN_JOINED above it (a handle that fades into the table).
    """
    centre, reach = _reach(mask, px_per_m)
    gap_px, step_px, longest = _lengths_px(px_per_m)
    size = (int(reach), ANGLES)  # (radius samples, angles): a row per angle
    flags = cv2.INTER_LINEAR | cv2.WARP_POLAR_LINEAR | cv2.WARP_FILL_OUTLIERS
    h = cv2.warpPolar(np.nan_to_num(heights).astype(np.float32), size, centre, reach, flags)
    seen = cv2.warpPolar(np.isfinite(heights).astype(np.float32), size, centre, reach, flags)
    inside = cv2.warpPolar(mask.astype(np.float32), size, centre, reach, flags) > 0.5
    dist = cv2.distanceTransform((~mask).astype(np.uint8), cv2.DIST_L2, 5)
    away = cv2.warpPolar(dist, size, centre, reach, flags) >= gap_px
    radius = np.arange(h.shape[1])
    # per ray, the first sample beyond the outline at least GAP from the object: a ray
    # that grazes a long rod's side starts only where it leaves the rod's fringe
    outline = np.where(inside, radius, 0).max(axis=1)
    leaves = away & (radius > outline[:, None])
    start = np.where(leaves.any(axis=1), np.argmax(leaves, axis=1), h.shape[1])
    stretches = TableStretches(heights, table)
    step_px, noise = _bare_window(stretches, step_px)
    if not np.isfinite(noise):
        return None
    seen = seen > 0.5
    means = _window_means(h, seen, step_px)  # per ray, the window at each radius
    beyond = radius >= start[:, None]
    bare = beyond & (means < BARE_SIGMAS * noise)  # a window of table: the part ends
    end = np.where(bare.any(axis=1), np.argmax(bare, axis=1), h.shape[1])
    end = np.minimum(end, start + longest)
    extent_px = np.maximum(end - start, 0)
    joined = seen & (radius >= start[:, None]) & (radius < end[:, None])
    for length in LENGTHS:
        length_px = max(5, int(round(length * px_per_m)))
        stretch = seen & (radius >= start[:, None]) & (radius < (start + length_px)[:, None])
        counts = stretch.sum(axis=1)
        sums = (h * stretch).sum(axis=1)
        means = np.where(counts > length_px // 2, sums / np.maximum(counts, 1), 0.0)
        k = int(np.argmax(means))
        if means[k] <= MIN_MEAN:  # too low whatever the noise (which is not measured then)
            continue
        stretch_noise = stretches.noise(length_px)
        if np.isfinite(stretch_noise) and means[k] > SIGMAS * stretch_noise:
            return ThinPart(360.0 * k / ANGLES, float(means[k]), length, stretch_noise)
    for k in np.argsort(extent_px)[::-1][: ANGLES // 8]:
        extent = extent_px[k] / px_per_m
        if extent < MIN_EXTENT:
            return None
        if not joined[k].any():  # the ray's part is not seen (beyond the area, the robot)
            continue
        mean = float(h[k, joined[k]].mean())
        if mean <= MIN_JOINED:  # too low whatever the noise (which is not measured then)
            continue
        part_noise = stretches.noise(int(extent_px[k]))
        if np.isfinite(part_noise) and mean > JOINED_SIGMAS * part_noise:
            return ThinPart(360.0 * k / ANGLES, mean, extent, part_noise)
    return None


def _lengths_px(px_per_m: float) -> tuple[int, int, int]:
    """(GAP, STEP, the longest of LENGTHS) in pixels, at ``px_per_m``."""
    return (max(2, int(round(GAP * px_per_m))), max(3, int(round(STEP * px_per_m))),
            max(5, int(round(max(LENGTHS) * px_per_m))))  # fmt: skip


def _reach(mask: np.ndarray, px_per_m: float) -> tuple[tuple[float, float], float]:
    """((u, v) the object's centre in the image, the rays' reach from it (px)).

    The reach: its farthest pixel, then GAP, the longest stretch, a window and two pixels.
    """
    rows, cols = np.nonzero(mask)
    centre = (float(cols.mean()), float(rows.mean()))
    gap_px, step_px, longest = _lengths_px(px_per_m)
    reach = np.hypot(rows - centre[1], cols - centre[0]).max() + gap_px + longest + step_px + 2
    return centre, float(reach)


def around_object(height: np.ndarray, mask: np.ndarray, standing: np.ndarray,
                  threshold: float, robot: np.ndarray, px_per_m: float) -> tuple:  # fmt: skip
    """(heights, table) for the thin-part checks: the disc the rays reach around the object.

    ``height``: (H, W) above the table's plane (m, NaN where none); ``mask``, ``standing``,
    ``robot``: (H, W) bool, the object, what stands on the table (above ``threshold``, m)
    and the robot's own parts (``robot_parts``).

    Only the disc around the object that ``check_no_thin_part``'s rays reach counts, wherever
    the pick area's edges are and whatever the frame the heights are in (the same answer
    for the same scene): its bare table (within ``threshold`` of the plane, clear of
    what stands, in the pick area or beyond it, and of the robot; ``standing.bare_table``)
    gives both the level the heights are taken from (its median) and the noise
    (``TableStretches``). Returns the heights that are too low to stand (NaN elsewhere:
    above the threshold, far below the plane, the robot, outside the disc) and the bare
    table (H, W) bool.
    """
    (u, v), reach = _reach(mask, px_per_m)
    rows, cols = np.ogrid[: height.shape[0], : height.shape[1]]
    disc = ((cols - u) ** 2 + (rows - v) ** 2 <= reach**2) & ~robot
    with np.errstate(invalid="ignore"):  # NaN heights are no table
        stands = standing | (height > threshold)  # in the pick area or not
        table = bare_table(disc & (np.abs(height) <= threshold), stands)
        level = float(np.median(height[table])) if table.any() else 0.0
        low = disc & (np.abs(height - level) <= threshold)
    return np.where(low, height - level, np.nan), table


def check_no_hidden_part(length: float, width: float, heights: np.ndarray, table: np.ndarray,
                         px_per_m: float) -> None:  # fmt: skip
    """UntrustedImageError for a short object in a depth too noisy to see a thin part.

    That is: the object is shorter than ROD_ASPECT times its ``width`` (``length``, m: a
    mallet's head, a box) and a thin part MIN_MEAN high would not stand SIGMAS of its noise
    along a ray's max(LENGTHS) (``check_no_thin_part`` could not find it): it may be the
    head of a tool whose handle the noise hides. ``heights``, ``table``, ``px_per_m``: as
    ``check_no_thin_part`` has them. A rod's shape, or a depth that would show such a part,
    passes.
    """
    if length >= ROD_ASPECT * width:
        return
    longest = _lengths_px(px_per_m)[2]
    least = SIGMAS * TableStretches(heights, table).noise(longest)
    if not least > MIN_MEAN:  # (NaN: too little table to tell, as check_no_thin_part)
        return
    raise UntrustedImageError(
        f"the object is {1e2 * length:.0f} cm long and {1e2 * width:.1f} cm wide, not a rod's "
        f"shape, and a thin part lower than {1e3 * least:.1f} mm going on from it would be "
        "lost in this depth's noise: it may be a tool's head whose handle is not seen; view "
        "it closer, with a less noisy camera, or give the colour image"
    )


def robot_parts(height: np.ndarray, threshold: float, pixel: float) -> np.ndarray:
    """(H, W) bool: the robot's own parts in view, with a GAP around them.

    ``height``: (H, W) above the table (m, NaN where none); ``threshold``: the height a
    pixel stands at (m); ``pixel``: a pixel's size on the table (m). What stands and reaches
    the image's edge (a gripper's fingers reaching into the view), and anything higher
    than an object on the table may be (``standing.MAX_HEIGHT``): never a thin part of the
    object, nor their fringes. Other objects on the table are counted as such
    (``rod_shape.check_one_object``).
    """
    tall = np.isfinite(height) & (height > threshold)
    robot = reaching_border(tall) | (np.isfinite(height) & (height > MAX_HEIGHT))
    gap_px = max(2, int(round(GAP / pixel)))
    kernel = np.ones((2 * gap_px + 1, 2 * gap_px + 1), np.uint8)
    return cv2.dilate(robot.astype(np.uint8), kernel).astype(bool)


def refuse_thin_part(part: ThinPart, why: str = "Its extent is not known from this depth") -> None:
    """Raise UntrustedImageError for ``part``, saying ``why`` the rod is not measured."""
    raise UntrustedImageError(
        f"a thin part lower than the depth can tell pixel by pixel goes on from the object "
        f"(at {part.angle_deg:.0f} deg in the image from its centre, u to v: "
        f"{1e3 * part.mean:.1f} mm high on average over {1e2 * part.length:.0f} cm, joined to "
        f"it; the table's noise over the same stretch {1e3 * part.noise:.2f} mm): a handle? "
        f"{why}; view it closer or with a less noisy camera"
    )


def _bare_window(stretches: TableStretches, step_px: int) -> tuple[int, float]:
    """(window length (px), its mean's noise (m)) for telling bare table.

    STEP, or longer (2, 4 STEP) until the noise is at most BARE_NOISE: in a noisy image a
    short window of a handle may look bare.
    """
    for factor in (1, 2, 4):
        noise = stretches.noise(factor * step_px)
        if not noise > BARE_NOISE:
            break
    return factor * step_px, noise


def _window_means(h: np.ndarray, seen: np.ndarray, step_px: int) -> np.ndarray:
    """(angles, radii) the mean of ``h`` over the seen samples of each window.

    The window of ``step_px`` starting at each radius; 0 where fewer than half are seen.
    """
    csum = np.cumsum(np.pad(h * seen, ((0, 0), (1, step_px))), axis=1)
    ccount = np.cumsum(np.pad(seen.astype(np.float32), ((0, 0), (1, step_px))), axis=1)
    n = h.shape[1]
    total = csum[:, step_px : step_px + n] - csum[:, :n]
    count = ccount[:, step_px : step_px + n] - ccount[:, :n]
    return np.where(count > step_px / 2, total / np.maximum(count, 1), 0.0)


class TableStretches:
    """The noise of a stretch's mean height on the empty table, per stretch length.

    ``heights`` (H, W) as ``check_no_thin_part`` has them, ``table`` (H, W) bool its bare
    table's pixels. The stretches are the strips along the image's rows and columns wholly
    on seen table; their sums come from running sums along each row and column (one
    integral image), so each length costs a difference and a median (``noise``), and a
    length asked twice is computed once.
    """

    def __init__(self, heights: np.ndarray, table: np.ndarray):
        seen = table & np.isfinite(heights)
        h = np.where(seen, heights, 0.0).astype(np.float32)  # the depth's own precision
        total = cv2.integral(h, sdepth=cv2.CV_64F)  # (H + 1, W + 1): sums above and left
        count = cv2.integral(seen.astype(np.uint8))  # int32, exact
        # running sums along each row, and down each column (as rows: transposed), from 0
        self._running = [(np.diff(total, axis=0), np.diff(count, axis=0)),
                         (np.diff(total, axis=1).T, np.diff(count, axis=1).T)]  # fmt: skip
        self._noise: dict[int, float] = {}

    def noise(self, length_px: int) -> float:
        """The robust std (m) of the mean height of stretches ``length_px`` long.

        NaN where there are 100 or fewer.
        """
        n = length_px
        if n not in self._noise:
            means = []
            for total, count in self._running:
                whole = (count[:, n:] - count[:, :-n]) == n
                means.append((total[:, n:] - total[:, :-n])[whole] / n)
            values = np.concatenate(means)
            self._noise[n] = noise_level(values) if len(values) > 100 else float("nan")
        return self._noise[n]
