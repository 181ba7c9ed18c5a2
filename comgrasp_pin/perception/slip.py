"""Slip monitor: the tilt of the rod in the jaws over time, and a slipping/settled verdict."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from comgrasp_pin import validate
from comgrasp_pin.errors import InvalidInputError

SLIP_RATE_DEG_S = 2.0  # |dθ/dt| above this over the recent window: slipping
SLIP_CHANGE_DEG = 1.0  # total change of θ since the first sample above this: slip was seen
WINDOW_S = 0.3  # length of the recent window for the rate (s)
MAX_TIME_S = 1e6  # sample times within +-MAX_TIME_S (s): a run is shorter than 11 days


@dataclass(frozen=True)
class SlipVerdict:
    """The monitor's verdict on the tilt samples so far.

    Attributes:
        slipping: θ is changing now.
        slip_seen: θ changed by more than SLIP_CHANGE_DEG since the first sample.
        rate_deg_s: recent |dθ/dt| (deg/s).
        change_deg: total change of θ (deg).
        theta: last θ (rad).
    """

    slipping: bool
    slip_seen: bool
    rate_deg_s: float
    change_deg: float
    theta: float


@dataclass
class SlipMonitor:
    """Feed (t, θ) samples (s, rad) as they come; ``verdict()`` at any time."""

    rate_deg_s: float = SLIP_RATE_DEG_S
    change_deg: float = SLIP_CHANGE_DEG
    window_s: float = WINDOW_S
    times: list[float] = field(default_factory=list)
    thetas: list[float] = field(default_factory=list)

    def add(self, t: float, theta: float) -> None:
        """Record the tilt ``theta`` (rad) at time ``t`` (s), later than every earlier sample.

        Raises:
            InvalidInputError: for a time or tilt that is not a finite number, a time beyond
                +-MAX_TIME_S, a tilt beyond one turn (+-2 pi), or a sample out of time order.
        """
        t = validate.number(t, "time t (s)", low=-MAX_TIME_S, high=MAX_TIME_S)
        theta = validate.number(theta, "tilt theta (rad)", low=-2 * np.pi, high=2 * np.pi)
        if self.times and t <= self.times[-1]:
            raise InvalidInputError(f"samples must come in time order: {t} after {self.times[-1]}")
        self.times.append(float(t))
        self.thetas.append(float(theta))

    def verdict(self) -> SlipVerdict:
        """Slipping now, slip seen, rate and change, from the samples so far.

        Raises:
            InvalidInputError: if there are no samples yet.
        """
        if not self.times:
            raise InvalidInputError("no tilt samples yet")
        t, th = np.array(self.times), np.degrees(np.array(self.thetas))
        recent = t >= t[-1] - self.window_s
        rate = 0.0
        if recent.sum() >= 2 and np.ptp(t[recent]) > 0:
            rate = abs(np.polyfit(t[recent], th[recent], 1)[0])
        steady = _smooth(th)  # one bad frame is not slip, a steady turn is
        change = float(np.max(np.abs(steady - steady[0])))
        return SlipVerdict(rate > self.rate_deg_s, change > self.change_deg, float(rate), change,
                           float(self.thetas[-1]))  # fmt: skip

    def largest_tilt(self) -> float:
        """The tilt of largest size seen so far (rad, signed), robust to one bad frame."""
        if not self.times:
            raise InvalidInputError("no tilt samples yet")
        steady = _despike(np.array(self.thetas))
        return float(steady[np.argmax(np.abs(steady))])

    def settled_tilt(self) -> float:
        """The tilt now (rad), robust to one bad frame: the median of the last three."""
        if not self.times:
            raise InvalidInputError("no tilt samples yet")
        return float(np.median(self.thetas[-3:]))


def _smooth(x: np.ndarray) -> np.ndarray:
    """Median of three, with Tukey's end-point rule at the ends.

    Each sample is replaced by the median of itself and its two neighbours; each end by the
    median of the end sample, its smoothed neighbour and the straight line through the two
    smoothed neighbours, carried to the end.

    A single outlier anywhere vanishes; a steady turn (a straight line) is kept whole, ends
    included, so even three samples of one tell it (``_despike`` flattens it).
    """
    if len(x) < 3:
        return x
    y = np.median(np.stack([x[:-2], x[1:-1], x[2:]]), axis=0)
    if len(y) == 1:  # three samples: the line runs through the middle one and the far end
        first = np.median([x[0], y[0], 2 * y[0] - x[2]])
        last = np.median([x[-1], y[0], 2 * y[0] - x[0]])
    else:
        first = np.median([x[0], y[0], 2 * y[0] - y[1]])
        last = np.median([x[-1], y[-1], 2 * y[-1] - y[-2]])
    return np.r_[first, y, last]


def _despike(x: np.ndarray) -> np.ndarray:
    """Each sample replaced by the median of itself and its two neighbours.

    The first and last are replaced by the median of the first and last three: single
    outliers vanish.
    """
    if len(x) < 3:
        return x
    middle = np.median(np.stack([x[:-2], x[1:-1], x[2:]]), axis=0)
    return np.r_[np.median(x[:3]), middle, np.median(x[-3:])]
