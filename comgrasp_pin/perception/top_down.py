"""The rod on the table from the top-down RGBD camera: a grasp pose at its geometric centre.

Segmentation uses depth first: the rod is what stands above the table plane inside the pick
area, whatever its colour and whatever shadows fall on it; the RGB image only shows the
result. As in the paper, the mask's smallest enclosing rectangle (OpenCV ``minAreaRect``)
represents the rod; for metric accuracy the rod's direction and extent are then taken from
the mask's pixels lifted to 3-D (perspective makes the 2-D rectangle's centre drift by
millimetres towards the image edges).
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from comgrasp_pin.camera import PinholeCamera
from comgrasp_pin.errors import ObjectCutByBorderError, ObjectNotFoundError
from comgrasp_pin.geometry import GraspPose
from comgrasp_pin.perception._points import check_images, largest_component, points_in

PICK_AREA = (0.30, 0.80, -0.35, 0.35)  # x_min, x_max, y_min, y_max of the table (m, world)
MIN_HEIGHT = 0.003  # a pixel counts as object if it stands this far above the table (m)
MAX_HEIGHT = 0.15  # ... and no higher than this (the robot above the table is not the rod)
MIN_PIXELS = 40
EDGE_BAND = 0.01  # an object within 2 bands of the pick area's edge may leave it (m)


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
    """

    grasp: GraspPose
    length: float
    widths: np.ndarray
    table_z: float
    handle_height: float
    mask: np.ndarray
    rect: tuple
    axis_px: np.ndarray


def detect_rod_top_down(
    rgb: np.ndarray | None,
    depth: np.ndarray,
    camera: PinholeCamera,
    T_world_cam: np.ndarray,
    pick_area: tuple[float, float, float, float] = PICK_AREA,
) -> RodDetection:
    """Find the rod in a top-down RGBD frame (depth: (H, W) z-depth in m, inf = none).

    Raises:
        ObjectNotFoundError: nothing above the table.
        ObjectCutByBorderError: the rod leaves the image or reaches the edge of the pick area.
        InvalidDepthError: unusable depth.
    """
    depth = check_images(rgb, depth, camera)
    points = points_in(T_world_cam, depth, camera)
    x, y, z = points[..., 0], points[..., 1], points[..., 2]
    x0, x1, y0, y1 = pick_area

    def within(margin: float) -> np.ndarray:
        return (x > x0 + margin) & (x < x1 - margin) & (y > y0 + margin) & (y < y1 - margin)

    inside = within(EDGE_BAND) & np.isfinite(z)
    if inside.sum() < 100:
        raise ObjectNotFoundError("the pick area is not in view of the camera")
    table_z = float(np.median(z[inside]))  # the rod covers a small part of the table
    standing = (z > table_z + MIN_HEIGHT) & (z < table_z + MAX_HEIGHT)
    mask = largest_component(inside & standing, MIN_PIXELS, "top-down image")
    grown = cv2.dilate(mask.astype(np.uint8), np.ones((5, 5), np.uint8)).astype(bool)
    if np.any(grown & standing & ~within(2 * EDGE_BAND) & np.isfinite(z)):
        raise ObjectCutByBorderError("the object reaches the edge of the pick area")

    p = points[mask]
    centroid = p[:, :2].mean(axis=0)
    _, _, vt = np.linalg.svd(p[:, :2] - centroid, full_matrices=False)
    direction = vt[0]
    along = (p[:, :2] - centroid) @ direction
    lo, hi = np.percentile(along, [0.02, 99.98])
    centre = centroid + 0.5 * (lo + hi) * direction
    near_centre = np.abs(along - 0.5 * (lo + hi)) < 0.01
    heights = p[near_centre, 2] - table_z if near_centre.any() else p[:, 2] - table_z
    handle_height = float(np.median(heights))
    yaw = float(np.arctan2(direction[1], direction[0]))
    yaw = (yaw + np.pi / 2) % np.pi - np.pi / 2  # (-pi/2, pi/2]
    grasp = GraspPose(float(centre[0]), float(centre[1]), table_z + 0.5 * handle_height, yaw)

    contours, _ = cv2.findContours(mask.astype(np.uint8), cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
    rect = cv2.minAreaRect(max(contours, key=cv2.contourArea))
    ends_world = np.array([[*(centre + s * direction), table_z] for s in (lo, hi)])
    T_cam_world = np.linalg.inv(T_world_cam)
    ends_cam = ends_world @ T_cam_world[:3, :3].T + T_cam_world[:3, 3]
    across = (p[:, :2] - centroid) @ np.array([-direction[1], direction[0]])
    s_rel = along - 0.5 * (lo + hi)
    bins = np.floor(s_rel / 0.01).astype(int)
    widths = np.array([((b + 0.5) * 0.01, np.ptp(across[bins == b])) for b in np.unique(bins)])
    if direction @ np.array([np.cos(yaw), np.sin(yaw)]) < 0:  # rows towards +yaw
        widths = widths[::-1] * np.array([-1.0, 1.0])
    return RodDetection(grasp, float(hi - lo), widths, table_z, handle_height, mask, rect,
                        camera.project(ends_cam))  # fmt: skip


def nearest_graspable(
    det: RodDetection, s: float, max_width: float = 0.075, half_pad: float = 0.022
) -> float:
    """The position along the rod nearest ``s`` where the jaws fit.

    Positions are in m from the rod's centre, towards +yaw. The jaws fit where the rod is
    narrower than ``max_width`` over ``half_pad`` either side.
    """
    pos, width = det.widths[:, 0], det.widths[:, 1]
    ok = []
    for c in (s, *pos):  # ``s`` itself first: the slices are 1 cm apart
        near = np.abs(pos - c) <= half_pad
        if np.all(width[near] <= max_width) and abs(c) <= 0.5 * det.length - half_pad:
            ok.append(c)
    if not ok:
        raise ObjectNotFoundError("no part of the object is narrow enough to grasp")
    return float(min(ok, key=lambda c: abs(c - s)))


def nearest_on_handle(det: RodDetection, s: float, half_pad: float = 0.022) -> float:
    """The position along the rod nearest ``s`` where both pads lie on the handle.

    Positions are in m from the rod's centre, towards +yaw. Within ``half_pad`` either side
    the rod is no wider than its width at the centre (the handle) plus a quarter and 4 mm.
    A grasp on a head's shoulder stops the jaws on the head and barely holds the handle.
    """
    handle = det.widths[np.argmin(np.abs(det.widths[:, 0])), 1]
    return nearest_graspable(det, s, max_width=1.25 * handle + 0.004, half_pad=half_pad)
