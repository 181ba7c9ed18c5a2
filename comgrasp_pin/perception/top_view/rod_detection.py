"""What the top view reports of a rod on the table: ``RodDetection``.

Made by ``top_down.detect_rod_top_down``; read by ``grasp_points`` (where the jaws can hold
it), ``draw`` and the procedures. A type of its own so that those read it without importing
the detector.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from comgrasp_pin.geometry import GraspPose


@dataclass(frozen=True)
class RodDetection:
    """A rod lying on the table, seen from above. World frame, SI units.

    Attributes:
        grasp: top-down grasp at the rod's geometric centre: (x, y) of the centre, z of the
            handle's axis (half the handle's height above the table), yaw of the rod.
        length: extent along the rod (m).
        widths: (K, 2) the rod's width across its axis (m) in 1 cm slices, as rows
            (position along the rod from its centre towards +yaw, width).
        table_z: height of the table plane (m).
        handle_height: the rod's height at its centre above the table (m).
        mask: (H, W) bool pixels of the rod.
        rect: OpenCV rotated rectangle ((u, v), (w, h), angle_deg) of the mask.
        axis_px: (2, 2) pixel ends of the axis.
        overhang: how far the rod reaches beyond the pick area (m), 0 when it lies within
            it: a rod laid back at the table's edge is seen whole as long as the camera
            sees it, and this says that it reaches over the edge.
        cut_end: 0 for a rod seen whole; +1 (-1) when its end towards +yaw (-yaw) runs
            out of the image: then ``grasp`` and ``length`` are the part seen's, and the
            detection comes only with an ObjectCutByBorderError (its ``seen``).
    """

    grasp: GraspPose
    length: float
    widths: np.ndarray
    table_z: float
    handle_height: float
    mask: np.ndarray
    rect: tuple
    axis_px: np.ndarray
    overhang: float = 0.0
    cut_end: int = 0
