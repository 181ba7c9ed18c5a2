"""A thin part that goes on from the object, followed to its end: a tool's handle from depth.

``thin_parts`` finds that a part too low for the height threshold goes on from the object:
a mallet's or obj1's 1 cm handle in a structured-light camera's depth at 1.25 m, whose
head alone stands. No pixel of the handle stands out of the noise, but its line does: the
heights along it are a step from the handle's mean height down to the table's at its end.
The line is the ray the check found, turned and shifted to where that step fits its heights
best (least squares); the band is as wide as the part's mean heights' profile across it;
the end is the band's best step, and every end whose fit is worse by less than END_CHI2 of
the noise's variance could be it. Where the camera lost most of the band's pixels (a
structured-light camera loses those near a depth step), the end is where their share steps
down to the table's (``_lost_end``). A part whose end is not known within END_TOLERANCE,
whose line runs into another object, the robot, the table's or the image's edge with no
bare table beyond its end, or whose height falls along it (FALL_SHARE: the depth losing it,
or two parts) is refused (as ``thin_parts`` refuses it, saying why). Otherwise its band's
pixels join the object as pixels whose height the depth did not measure (as the colour's
are), and the rod is measured whole. World frame, m; pixels as (u, v).
"""

from __future__ import annotations

import warnings

import cv2
import numpy as np

from comgrasp_pin.perception._points import opened_blobs
from comgrasp_pin.perception.top_view.rod_shape import MIN_OBJECT_PX, SECOND_OBJECT
from comgrasp_pin.perception.top_view.standing import MAX_HEIGHT
from comgrasp_pin.perception.top_view.thin_parts import (
    GAP,
    TableStretches,
    ThinPart,
    around_object,
    find_thin_part,
    refuse_thin_part,
    robot_parts,
)

MAX_REACH = 0.6  # a part is followed this far from the object's centre (m)
TURN_DEG, TURN_STEP_DEG = 3.0, 0.25  # the line: the ray turned by up to this (deg) ...
SHIFT_PX = 2  # ... and shifted across by up to this (px), to where a step fits it best
END_CHI2 = 4.0  # the ends whose fit is worse by less than this many noise variances ...
END_TOLERANCE = 0.03  # ... spread over more than this (m): the end is not known
MIN_BARE = 0.03  # the line must show this much table beyond the end (m)
UNKNOWN = "Its extent is not known from this depth"
FALL_SHARE = 0.2  # a part whose second half stands this share lower than its first fades
MAX_HALF_WIDTH_PX = 6  # the part's profile across its line is taken this far each side
# A part whose band's share of pixels without depth stands this much and this many stds above
# the table's beyond it: its end is where that share steps down (a structured-light camera's
# holes at depth steps)
MIN_LOST_SHARE, LOST_SIGMAS = 0.25, 5.0


def thin_part_around(view, standing: np.ndarray, mask: np.ndarray, pixel: float,
                     threshold: float) -> tuple:  # fmt: skip
    """(heights, table, the thin part found or None) around the object ``mask``.

    What stands (``standing``, above ``threshold``, m) is the object or another one; the
    robot's own parts are left out (``robot_parts``); the heights' level and the table's
    noise come from the bare table around the object (``thin_parts.around_object``), not
    from the pick area. ``view``: the ``TableView``; ``pixel``: a pixel's size at the
    object (m). The heights and table are ``thin_parts.check_no_hidden_part``'s.
    """
    height = view.points[..., 2] - view.table_z
    robot = robot_parts(height, threshold, pixel)
    heights, table = around_object(height, mask, standing, threshold, robot, 1.0 / pixel)
    return heights, table, find_thin_part(heights, mask, table, 1.0 / pixel)


def follow_thin_part(view, lost: np.ndarray, standing: np.ndarray, mask: np.ndarray,
                     pixel: float, threshold: float, part: ThinPart,
                     table: np.ndarray) -> np.ndarray:  # fmt: skip
    """(H, W) bool: the pixels of the thin ``part`` that goes on from ``mask`` (its band).

    The arguments are ``thin_part_around``'s, and what it found: the ``part`` and the bare
    ``table`` around the object; ``lost``: (H, W) bool, the pixels the camera gave no depth
    (before the view's cleaning filled them). Raises UntrustedImageError (``thin_parts``'
    refusal, with why) where the part's end is not known.
    """
    height = view.points[..., 2] - view.table_z
    robot = robot_parts(height, threshold, pixel)
    level = float(np.median(height[table]))
    with np.errstate(invalid="ignore"):  # NaN: no depth
        low = np.where(np.abs(height - level) <= threshold, height - level, np.nan)
        line = np.where(height < MAX_HEIGHT, height - level, np.nan)  # the noise's bumps too
    off_table = np.abs(np.nan_to_num(height - level)) >= MAX_HEIGHT  # beyond its edge
    blocked = _other_objects(standing, mask) | robot | off_table
    rows, cols = np.nonzero(mask)
    lines = _Lines(line, blocked, mask, np.array([cols.mean(), rows.mean()]), 1.0 / pixel)
    theta, shift = lines.best(np.radians(part.angle_deg))
    radii, samples, _ = lines.along(theta, [shift])
    first_end = _end(radii, samples, 0.0)[0] or radii[-1]
    offsets = _band(line, lines, theta, shift, np.arange(radii[0], first_end))
    radii, samples, stop = lines.along(theta, offsets)
    # the noise's variance per sample as the band's sums over END_TOLERANCE have it (correlated)
    n = max(3, int(round(END_TOLERANCE / pixel)))
    variance = n * _band_noise(low, table, len(offsets), n) ** 2
    end, spread = _end(radii, samples, variance)
    lost_end = _lost_end(lost.astype(float), lines, theta, offsets, radii[0], stop)
    if end is not None and lost_end is not None:  # the pixels without depth show its end
        end, spread = lost_end
    if end is None or spread > END_TOLERANCE / pixel or stop - end < MIN_BARE / pixel:
        where = "no end within the line" if end is None else (
            f"its end within {spread * pixel * 1e2:.1f} cm, with "
            f"{max(stop - end, 0) * pixel * 1e2:.0f} cm of table seen beyond it")  # fmt: skip
        refuse_thin_part(part, f"{UNKNOWN}: followed along its line, {where}")
    fall = _fall(samples[radii < end], low, table, len(offsets))
    if fall is not None:
        refuse_thin_part(part, f"{UNKNOWN}: followed along its line, its height falls from "
                         f"{fall[0]:.1f} to {fall[1]:.1f} mm, the depth losing it short of "
                         "its end")  # fmt: skip
    along, across = lines.coordinates(mask.shape, theta)
    band = (along >= 0.0) & (along <= end)
    band &= (across >= offsets.min() - 0.5) & (across <= offsets.max() + 0.5)
    return band & ~mask


class _Lines:
    """Lines from the object's ``centre`` (u, v), at an angle (rad, u to v), shifted across.

    ``image``'s pixels along them, from beyond the object's fringe (GAP from ``mask``) to
    MAX_REACH, the image's edge or what is ``blocked``, whichever comes first.
    """

    def __init__(self, image, blocked, mask, centre, px_per_m):
        self.image, self.blocked, self.centre = image, blocked.astype(float), centre
        self.dist = cv2.distanceTransform((~mask).astype(np.uint8), cv2.DIST_L2, 5)
        self.gap, self.radii = max(2.0, GAP * px_per_m), np.arange(int(MAX_REACH * px_per_m))

    def coordinates(self, shape, theta) -> tuple[np.ndarray, np.ndarray]:
        """(along, across): every pixel's coordinates (px) on the line at ``theta``."""
        rows, cols = np.ogrid[: shape[0], : shape[1]]
        u, v = cols - self.centre[0], rows - self.centre[1]
        return u * np.cos(theta) + v * np.sin(theta), v * np.cos(theta) - u * np.sin(theta)

    def sample(self, image, theta, shift, radii) -> np.ndarray:
        """``image`` at the pixels nearest the line's ``radii`` (NaN outside the image)."""
        u = self.centre[0] + radii * np.cos(theta) - shift * np.sin(theta)
        v = self.centre[1] + radii * np.sin(theta) + shift * np.cos(theta)
        ui, vi = np.rint(u).astype(int), np.rint(v).astype(int)
        inside = (ui >= 0) & (ui < image.shape[1]) & (vi >= 0) & (vi < image.shape[0])
        out = np.full(len(radii), np.nan)
        out[inside] = image[vi[inside], ui[inside]]
        return out

    def along(self, theta, shifts):
        """(radii (px), heights, the radius the band stops at (px)).

        The band's seen samples: the mean across the lines shifted by each of ``shifts`` (px).
        """
        near = self.sample(self.dist, theta, float(np.mean(shifts)), self.radii) < self.gap
        radii = self.radii[int(np.nonzero(near)[0].max()) + 1 if near.any() else 0 :]
        stops = np.sum([self.sample(self.blocked, theta, s, radii) for s in shifts], axis=0)
        ends = ~(stops == 0.0)  # blocked, or outside the image (NaN)
        stop = int(radii[np.argmax(ends)]) if ends.any() else int(radii[-1]) + 1
        radii = radii[radii < stop]
        with warnings.catch_warnings():  # (a radius none of whose pixels has a depth: NaN)
            warnings.simplefilter("ignore", RuntimeWarning)
            h = np.nanmean([self.sample(self.image, theta, s, radii) for s in shifts], axis=0)
        seen = np.isfinite(h)
        return radii[seen], h[seen], stop

    def best(self, theta0) -> tuple[float, float]:
        """(angle, shift): the line near the ray ``theta0`` a step to the table fits best.

        ``_step_fit``'s best, over the ray turned by up to TURN_DEG and shifted up to SHIFT_PX.
        """
        best = (-np.inf, theta0, 0.0)
        for turn in np.radians(np.arange(-TURN_DEG, TURN_DEG + 1e-9, TURN_STEP_DEG)):
            for shift in range(-SHIFT_PX, SHIFT_PX + 1):
                fit = _step_fit(self.along(theta0 + turn, [float(shift)])[1])
                if len(fit) and fit.max() > best[0]:
                    best = (float(fit.max()), theta0 + turn, float(shift))
        return best[1], best[2]


def _other_objects(standing: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """(H, W) bool: what stands apart from the object ``mask`` and is no bump of the noise.

    Blobs as ``rod_shape.check_one_object`` counts objects (MIN_OBJECT_PX, SECOND_OBJECT).
    """
    count, labels, stats = opened_blobs(standing & ~mask)
    least = max(MIN_OBJECT_PX, SECOND_OBJECT * int(mask.sum()))
    big = np.zeros(count, bool)
    big[1:] = stats[1:, cv2.CC_STAT_AREA] >= least
    return big[labels]


def _step_fit(h: np.ndarray) -> np.ndarray:
    """Per end (after each sample of ``h``): the step model's least-squares improvement.

    The step model: the part's mean up to the end, the table's level (0) beyond it. Its
    improvement over no part is the sum of the heights up to the end, squared, over their
    count (0 where the sum is negative).
    """
    total = np.cumsum(h)
    return np.where(total > 0, total**2 / np.arange(1, len(h) + 1), 0.0)


def _end(radii, h, variance) -> tuple[float | None, float]:
    """(the end's radius (px), the spread of the ends that fit within END_CHI2 (px)).

    The ends whose fit (``_step_fit``) is worse than the best by less than END_CHI2 times
    the noise's ``variance`` per sample; None where no end gives a part above the table.
    """
    fit = _step_fit(h)
    if len(h) < 3 or fit.max() <= 0:
        return None, np.inf
    best = int(np.argmax(fit))
    near = radii[fit >= fit[best] - END_CHI2 * variance]
    return float(radii[best]) + 0.5, float(near.max() - near.min())


def _lost_end(lost, lines: _Lines, theta, offsets, first: int, stop: int) -> tuple | None:
    """(end (px), spread (px)) of the part from the pixels the depth ``lost`` along its band.

    A structured-light camera loses most pixels within a few of a depth step: a part under
    a centimetre is mostly lost, and its band's share of lost pixels steps down to the
    table's at its end. The step (two levels, least squares) between ``first`` and ``stop``
    (px) counts where the part's share stands MIN_LOST_SHARE and LOST_SIGMAS of its std
    above the table's; the ends whose fit is worse by less than END_CHI2 of the residuals'
    variance could be it. The camera loses pixels as far beyond the part's end as beside
    it: the end lies up to half the lost band's width across the line (the shifts whose
    share stands at least halfway from the table's to the part's) short of the lost pixels'
    end. None where the lost pixels show no such step.
    """
    radii = np.arange(first, stop)
    share = np.mean([lines.sample(lost, theta, s, radii) for s in offsets], axis=0)
    n = len(share)
    if n < 6 or not np.isfinite(share).all():
        return None
    k = np.arange(2, n - 1)  # the part's samples: the first k
    s1, s2 = np.cumsum(share)[k - 1], np.cumsum(share**2)[k - 1]
    sse = s2 - s1**2 / k + (np.sum(share**2) - s2) - (np.sum(share) - s1) ** 2 / (n - k)
    best = int(np.argmin(sse))
    part, beyond = s1[best] / k[best], (np.sum(share) - s1[best]) / (n - k[best])
    variance = max(float(sse[best]) / (n - 2), 1e-12)
    std = np.sqrt(variance * (1 / k[best] + 1 / (n - k[best])))
    if part - beyond < max(MIN_LOST_SHARE, LOST_SIGMAS * std):
        return None
    near = radii[k[sse <= sse[best] + END_CHI2 * variance] - 1] + 0.5
    wide = np.arange(-2 * MAX_HALF_WIDTH_PX, 2 * MAX_HALF_WIDTH_PX + 1)
    mid = float(np.mean(offsets))
    across = np.array([np.mean(lines.sample(lost, theta, mid + o, radii[: k[best]]))
                       for o in wide])  # fmt: skip
    lossy = wide[np.nan_to_num(across) >= 0.5 * (part + beyond)]
    half_band = 0.5 * (lossy.max() - lossy.min() + 1) if len(lossy) else 0.0
    lo, hi = float(near.min()) - half_band, float(near.max())
    return 0.5 * (lo + hi), hi - lo


def _fall(h, low, table, width_px: int) -> tuple[float, float] | None:
    """(first half's, second half's mean height, mm) of a part the depth loses gradually.

    That is, of the part's samples ``h``, where the second half stands lower than the first
    by FALL_SHARE of it and by more than END_CHI2 ** 0.5 stds of their difference
    (``_band_noise`` over a half); else None.
    """
    half = len(h) // 2
    if half < 3:
        return None
    first, second = float(np.mean(h[:half])), float(np.mean(h[half:]))
    noise = _band_noise(low, table, width_px, half)
    if first - second > max(FALL_SHARE * first, np.sqrt(2.0 * END_CHI2) * noise):
        return 1e3 * first, 1e3 * second
    return None


def _band(line, lines: _Lines, theta, shift, radii) -> np.ndarray:
    """The shifts (px) across the line that the part covers (2 at least).

    Where its mean heights' profile across the line, over ``radii``, is at least half its
    highest.
    """
    offsets = np.arange(-MAX_HALF_WIDTH_PX, MAX_HALF_WIDTH_PX + 1)
    with warnings.catch_warnings():  # (a shift with no depth: NaN)
        warnings.simplefilter("ignore", RuntimeWarning)
        profile = np.array([np.nanmean(lines.sample(line, theta, shift + o, radii))
                            for o in offsets])  # fmt: skip
    peak = int(np.nanargmax(profile))
    above = np.nan_to_num(profile, nan=0.0) >= 0.5 * profile[peak]
    lo = peak - np.argmin(above[peak::-1]) + 1 if not above[: peak + 1].all() else 0
    hi = peak + np.argmin(above[peak:]) if not above[peak:].all() else len(above)
    if hi - lo < 2:
        lo, hi = peak, peak + 2
    return shift + offsets[lo:hi].astype(float)


def _band_noise(low, table, width_px: int, length_px: int) -> float:
    """The noise (m) of a band's mean height ``width_px`` wide and ``length_px`` long.

    On the bare ``table``: its strips (``TableStretches``) of the heights averaged over
    ``width_px`` x ``width_px`` squares wholly on the table.
    """
    seen = table & np.isfinite(low)
    k = (width_px, width_px)
    mean = cv2.blur(np.where(seen, low, 0.0).astype(np.float32), k)
    whole = cv2.blur(seen.astype(np.float32), k) > 1.0 - 1e-6
    return TableStretches(np.where(whole, mean, np.nan), whole).noise(length_px)
