"""Overlays a person can look at: mask outline, fitted rectangle, axis, grasp point, the CoM.

Every overlay carries a legend. Colours are BGR (OpenCV); pixel coordinates (u, v).
The CoM marks take pixels: projecting a 3-D point is the caller's (``PinholeCamera``).
"""

from __future__ import annotations

import cv2
import numpy as np

from comgrasp_pin.errors import InvalidInputError
from comgrasp_pin.geometry import tilt_from_level_deg
from comgrasp_pin.perception.side_view.side_view import SideView
from comgrasp_pin.perception.top_view.rod_detection import RodDetection

OUTLINE, RECT, AXIS, POINT = (0, 255, 255), (255, 255, 0), (255, 80, 0), (255, 0, 255)
ESTIMATE, TRUTH = (0, 140, 255), (0, 220, 0)
"""BGR: mask outline yellow, rectangle cyan, axis blue, grasp point magenta; the CoM
estimate orange (a dot on a bar: its interval), the true CoM green (a ring)."""
_FONT = cv2.FONT_HERSHEY_SIMPLEX
_WHITE = (255, 255, 255)


def _px(p) -> tuple[int, int]:
    return int(round(float(p[0]))), int(round(float(p[1])))


def put_text(img: np.ndarray, text: str, org, scale: float = 0.5, colour=_WHITE,
             box: bool = True) -> None:  # fmt: skip
    """Write ``text`` at ``org`` (its baseline's left end), on a darkened box.

    Legible on any background; ``scale`` is OpenCV's font scale; ``box`` False: no box
    (the background is dark already).
    """
    x, y = _px(org)
    thick = max(1, int(round(2 * scale)))
    if box:
        (w, h), base = cv2.getTextSize(text, _FONT, scale, thick)
        y0, y1 = max(y - h - 3, 0), min(y + base + 1, img.shape[0])
        x0, x1 = max(x - 3, 0), min(x + w + 3, img.shape[1])
        img[y0:y1, x0:x1] = (0.35 * img[y0:y1, x0:x1]).astype(img.dtype)
    cv2.putText(img, text, (x, y), _FONT, scale, colour, thick, cv2.LINE_AA)


def draw_com(img: np.ndarray, estimate_px=None, interval_px=None, truth_px=None,
             size: float = 1.0) -> np.ndarray:  # fmt: skip
    """Draw the CoM estimate with its interval, and the true CoM, on ``img``.

    Args:
        img: BGR image, drawn on in place (and returned).
        estimate_px: (2,) pixel of the estimated CoM: an orange dot.
        interval_px: (2, 2) pixels of its interval's ends (e.g. +-2 sigma along the rod):
            an orange bar with end ticks.
        truth_px: (2,) pixel of the true CoM: a green ring.
        size: scales the marks (1: for a 640 x 480 image).

    Any mark given as None is left out.
    """
    r = max(2, int(round(5 * size)))
    if interval_px is not None:
        a, b = _px(interval_px[0]), _px(interval_px[1])
        cv2.line(img, a, b, (0, 0, 0), max(1, r // 2) + 2, cv2.LINE_AA)
        cv2.line(img, a, b, ESTIMATE, max(1, r // 2), cv2.LINE_AA)
        d = np.subtract(b, a).astype(float)
        n = np.array([-d[1], d[0]]) / max(np.hypot(*d), 1e-9) * 1.5 * r
        for end in (a, b):  # end ticks, across the bar
            cv2.line(img, _px(end - n), _px(end + n), ESTIMATE, max(1, r // 2), cv2.LINE_AA)
    if estimate_px is not None:
        cv2.circle(img, _px(estimate_px), r + 1, (0, 0, 0), -1, cv2.LINE_AA)
        cv2.circle(img, _px(estimate_px), r, ESTIMATE, -1, cv2.LINE_AA)
    if truth_px is not None:
        thick = max(2, r // 2)
        cv2.circle(img, _px(truth_px), 2 * r + 1, (0, 0, 0), thick + 2, cv2.LINE_AA)
        cv2.circle(img, _px(truth_px), 2 * r + 1, TRUTH, thick, cv2.LINE_AA)
    return img


def draw_legend(img: np.ndarray, entries, corner: str = "bottom-left",
                scale: float = 0.45) -> np.ndarray:  # fmt: skip
    """Draw a legend box on ``img`` (in place, returned).

    Args:
        img: BGR image.
        entries: (label, BGR colour, mark) each; mark is one of "line", "box", "cross",
            "outline", "dot_bar" (the CoM estimate), "ring" (the true CoM).
        corner: "bottom-left", "top-left" or "bottom-right".
        scale: OpenCV font scale of the labels.
    """
    if not entries:
        return img
    line_h = int(round(34 * scale)) + 2
    sw = int(round(36 * scale))
    widths = [cv2.getTextSize(e[0], _FONT, scale, 1)[0][0] for e in entries]
    box_w, box_h = sw + 14 + max(widths), line_h * len(entries) + 6
    h, w = img.shape[:2]
    x0 = 6 if corner != "bottom-right" else w - box_w - 6
    y0 = 6 if corner == "top-left" else h - box_h - 6
    roi = img[y0 : y0 + box_h, x0 : x0 + box_w]
    roi[:] = (0.45 * roi).astype(img.dtype)  # darken behind the text
    for k, (label, colour, mark) in enumerate(entries):
        yc = y0 + 3 + k * line_h + line_h // 2
        a, b = (x0 + 5, yc), (x0 + 5 + sw, yc)
        mid = (x0 + 5 + sw // 2, yc)
        if mark in ("line", "outline"):
            cv2.line(img, a, b, colour, 2 if mark == "line" else 1, cv2.LINE_AA)
        elif mark == "box":
            cv2.rectangle(img, (a[0], yc - line_h // 3), (b[0], yc + line_h // 3), colour, 1)
        elif mark == "cross":
            cv2.drawMarker(img, mid, colour, cv2.MARKER_CROSS, line_h - 4, 2)
        elif mark == "dot_bar":
            draw_com(img, mid, np.array([a, b]), size=line_h / 25)
        elif mark == "ring":
            draw_com(img, truth_px=mid, size=line_h / 25)
        put_text(img, label, (x0 + sw + 10, yc + int(10 * scale)), scale, box=False)
    return img


def com_legend(estimate: bool = True, truth: bool = True) -> list:
    """Legend entries of ``draw_com``'s marks."""
    out = [("CoM estimate, +-2 sigma", ESTIMATE, "dot_bar")] if estimate else []
    return out + ([("true CoM (simulator)", TRUTH, "ring")] if truth else [])


def depth_image(depth: np.ndarray) -> tuple[np.ndarray, tuple[float, float]]:
    """(BGR image of ``depth``, the depth range (m) its colours span) to draw on.

    ``depth``: (H, W) z-depth in m; 0, negative or not finite: no depth (black). OpenCV's
    TURBO colour map over the 1st to 99th percentile of the valid pixels, near red, far
    blue (what stands on a table is warmer than the table); beyond the range, the end
    colours. ``depth_colour_bar`` draws its legend.
    """
    z = np.asarray(depth, dtype=float)
    valid = np.isfinite(z) & (z > 0)
    if not valid.any():
        return np.zeros((*z.shape, 3), np.uint8), (0.0, 0.0)
    lo, hi = (float(v) for v in np.percentile(z[valid], [1, 99]))
    near = (hi - np.where(valid, z, hi)) / max(hi - lo, 1e-6)  # 1 at lo (near), 0 at hi
    img = cv2.applyColorMap(np.round(255 * np.clip(near, 0, 1)).astype(np.uint8),
                            cv2.COLORMAP_TURBO)  # fmt: skip
    img[~valid] = 0
    return img, (lo, hi)


def depth_colour_bar(img: np.ndarray, depth_range: tuple[float, float], scale: float = 0.45):
    """The legend of ``depth_image``'s colours in ``img``'s top-right corner (in place)."""
    lo, hi = depth_range
    bar_w, bar_h = 120, 10
    ramp = np.linspace(255, 0, bar_w).round().astype(np.uint8)[None].repeat(bar_h, axis=0)
    text = f"depth {lo:.3f} m  ...  {hi:.3f} m"
    note = "black: no depth"
    w = max(cv2.getTextSize(t, _FONT, scale, 1)[0][0] for t in (text, note)) + 12
    x0, h = img.shape[1] - w - 6, int(round(34 * scale)) + 2
    roi = img[4 : 10 + 2 * h + bar_h, x0 : x0 + w]
    roi[:] = (0.35 * roi).astype(img.dtype)
    put_text(img, text, (x0 + 6, 4 + h), scale, box=False)
    bx = x0 + (w - bar_w) // 2
    img[8 + h : 8 + h + bar_h, bx : bx + bar_w] = cv2.applyColorMap(ramp, cv2.COLORMAP_TURBO)
    put_text(img, note, (x0 + 6, 6 + 2 * h + bar_h), scale, box=False)
    return img


def _bgr(rgb: np.ndarray) -> np.ndarray:
    return np.ascontiguousarray(rgb[:, :, ::-1]).copy()  # BGR for OpenCV


def _common(img: np.ndarray, mask: np.ndarray, rect: tuple, axis_px: np.ndarray) -> np.ndarray:
    """Outline, rectangle and axis drawn on the BGR ``img`` (in place, returned)."""
    contours, _ = cv2.findContours(mask.astype(np.uint8), cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
    cv2.drawContours(img, contours, -1, OUTLINE, 1)
    box = cv2.boxPoints(rect).astype(np.int32)
    cv2.polylines(img, [box], True, RECT, 1, cv2.LINE_AA)
    cv2.line(img, _px(axis_px[0]), _px(axis_px[1]), AXIS, 1, cv2.LINE_AA)
    return img


def _entries(point_label: str) -> list:
    return [("rod mask outline", OUTLINE, "outline"), ("smallest enclosing rectangle", RECT,
            "box"), ("rod axis", AXIS, "line"), (point_label, POINT, "cross")]  # fmt: skip


def _canvas(rgb: np.ndarray | None, depth: np.ndarray | None, mask: np.ndarray) -> np.ndarray:
    """The BGR image to draw on: the colour image, else the depth in colours.

    On the depth, its colours' legend is drawn and the object's ``mask`` outlined in black
    underneath (the outline's colour is then legible on any depth colour).
    """
    if rgb is not None:
        return _bgr(rgb)
    if depth is None:
        raise InvalidInputError("a view is drawn on the colour image or on the depth: give one")
    img, depth_range = depth_image(depth)
    depth_colour_bar(img, depth_range)
    contours, _ = cv2.findContours(mask.astype(np.uint8), cv2.RETR_EXTERNAL,
                                   cv2.CHAIN_APPROX_NONE)  # fmt: skip
    cv2.drawContours(img, contours, -1, (0, 0, 0), 3)
    return img


def draw_top_view(rgb: np.ndarray | None, det: RodDetection, grasp_px: np.ndarray,
                  depth: np.ndarray | None = None) -> np.ndarray:  # fmt: skip
    """BGR image: outline, rectangle, axis, the grasp point ``grasp_px`` (u, v), a legend.

    Drawn on the colour image ``rgb`` (RGB); without it (None), on the z-depth ``depth``
    (m) in colours (``depth_image``), with their legend.
    """
    img = _canvas(rgb, depth, det.mask)
    _common(img, det.mask, det.rect, det.axis_px)
    cv2.drawMarker(img, _px(grasp_px), POINT, cv2.MARKER_CROSS, 14, 2)
    text = f"yaw {np.degrees(det.grasp.yaw):.1f} deg, length {100 * det.length:.1f} cm"
    put_text(img, text, (8, 20))
    return draw_legend(img, _entries("grasp point (geometric centre)"))


def draw_side_view(rgb: np.ndarray | None, view: SideView, estimate_px=None, interval_px=None,
                   truth_px=None, depth: np.ndarray | None = None) -> np.ndarray:  # fmt: skip
    """BGR image: outline, rectangle, axis, the TCP, the tilt in the jaws, a legend.

    ``estimate_px``, ``interval_px``, ``truth_px``: the CoM marks of ``draw_com``
    (pixels), where given (the caller projects them with the camera). Drawn on the colour
    image ``rgb``, or without it (None) on the z-depth ``depth`` (m), as ``draw_top_view``.
    """
    img = _common(_canvas(rgb, depth, view.mask), view.mask, view.rect, view.axis_px)
    cv2.drawMarker(img, _px(view.tcp_px), POINT, cv2.MARKER_CROSS, 14, 2)
    text = (f"tilt in the jaws {tilt_from_level_deg(view.theta):.1f} deg from level, held "
            f"{100 * view.grasp_offset:+.1f} cm from centre")  # fmt: skip
    put_text(img, text, (8, 20))
    draw_com(img, estimate_px, interval_px, truth_px)
    entries = _entries("TCP (the jaws' centre)")
    entries += com_legend(estimate_px is not None, truth_px is not None)
    return draw_legend(img, entries)
