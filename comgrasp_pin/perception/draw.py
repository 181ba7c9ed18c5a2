"""Overlays a person can look at: mask outline, fitted rectangle, axis and grasp point."""

from __future__ import annotations

import cv2
import numpy as np

from comgrasp_pin.perception.side_view import SideView
from comgrasp_pin.perception.top_down import RodDetection

_OUTLINE, _RECT, _AXIS, _POINT = (0, 255, 255), (0, 200, 0), (255, 80, 0), (255, 0, 255)


def _common(rgb: np.ndarray, mask: np.ndarray, rect: tuple, axis_px: np.ndarray) -> np.ndarray:
    img = np.ascontiguousarray(rgb[:, :, ::-1]).copy()  # BGR for OpenCV
    contours, _ = cv2.findContours(mask.astype(np.uint8), cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
    cv2.drawContours(img, contours, -1, _OUTLINE, 1)
    box = cv2.boxPoints(rect).astype(np.int32)
    cv2.polylines(img, [box], True, _RECT, 1, cv2.LINE_AA)
    a, b = (tuple(int(round(v)) for v in p) for p in axis_px)
    cv2.line(img, a, b, _AXIS, 1, cv2.LINE_AA)
    return img


def draw_top_view(rgb: np.ndarray, det: RodDetection, grasp_px: np.ndarray) -> np.ndarray:
    """BGR image: outline, rectangle, axis and the grasp point ``grasp_px`` (u, v)."""
    img = _common(rgb, det.mask, det.rect, det.axis_px)
    centre = tuple(int(round(v)) for v in grasp_px)
    cv2.drawMarker(img, centre, _POINT, cv2.MARKER_CROSS, 14, 2)
    text = f"yaw {np.degrees(det.grasp.yaw):.1f} deg, length {100 * det.length:.1f} cm"
    cv2.putText(img, text, (8, 20), cv2.FONT_HERSHEY_SIMPLEX, 0.5, (255, 255, 255), 1, cv2.LINE_AA)
    return img


def draw_side_view(rgb: np.ndarray, view: SideView) -> np.ndarray:
    """BGR image: outline, rectangle, axis, the TCP (grasp point) and the tilt."""
    img = _common(rgb, view.mask, view.rect, view.axis_px)
    tcp = tuple(int(round(v)) for v in view.tcp_px)
    cv2.drawMarker(img, tcp, _POINT, cv2.MARKER_CROSS, 14, 2)
    text = (
        f"tilt {np.degrees(view.theta):.1f} deg, held {100 * view.grasp_offset:+.1f} cm from centre"
    )
    cv2.putText(img, text, (8, 20), cv2.FONT_HERSHEY_SIMPLEX, 0.5, (255, 255, 255), 1, cv2.LINE_AA)
    return img
