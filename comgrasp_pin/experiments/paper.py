"""The paper's reported numbers (docs/design.md section 8), to put beside ours; not results."""

from __future__ import annotations

from collections.abc import Sequence

# Accuracy (%) read from the paper's figure, by tilt theta (deg), objects 1 and 6.
ACCURACY_THETA_DEG = (0.1, 3.2, 5.7, 9.1, 10.3, 12.3, 13.6, 16.6, 20.6, 25.5, 30.8)
ACCURACY_PERCENT = {
    "obj1": (98.7, 97.7, 97.5, 96.8, 95.2, 93.6, 87.7, 83.4, 78.7, 73.6, 70.4),
    "obj6": (90.2, 88.0, 85.7, 85.3, 82.5, 78.1, 75.5, 74.0, 65.9, 63.9, 59.1),
}

# Pick-and-place success rate (%): (with the regrasp planner, geometry-only baseline).
SUCCESS_PERCENT = {
    "obj1": (93.2, 70.8),
    "obj2": (91.3, 65.6),
    "obj3": (90.5, 61.5),
    "obj4": (89.1, 60.6),
    "obj5": (87.6, 58.5),
    "obj6": (86.9, 58.0),
}

METHOD = "one pose, CoM line ∩ rod axis"
"""The paper's estimate (eq. 8): the vertical line through the CoM, from one static pose,
met with the rod's axis seen by the side camera; our ``accuracy_line`` column."""


def paper_accuracy_at(obj: str, theta_deg: float) -> float | None:
    """The paper's accuracy (%) for ``obj`` at ``theta_deg``, linearly interpolated between
    its points; None for objects 2-5 (not reported) or outside the reported range."""
    import numpy as np

    if obj not in ACCURACY_PERCENT:
        return None
    if not ACCURACY_THETA_DEG[0] <= theta_deg <= ACCURACY_THETA_DEG[-1]:
        return None
    return float(np.interp(theta_deg, ACCURACY_THETA_DEG, ACCURACY_PERCENT[obj]))


def paper_accuracy_bins(obj: str, edges: Sequence[float]) -> list[float | None]:
    """The paper's accuracy (%) for ``obj`` at the centre of each bin of ``edges`` (deg);
    None where the paper has no value (``paper_accuracy_at``)."""
    return [paper_accuracy_at(obj, 0.5 * (lo + hi)) for lo, hi in zip(edges[:-1], edges[1:])]
