"""The rod on the table from the top-down RGBD camera: a grasp pose at its geometric centre.

The result is a ``RodDetection`` (``rod_detection``). Segmentation uses depth first: the rod
is what stands above the table plane inside the pick area, whatever its colour and whatever
shadows fall on it. A real camera's depth (noise, holes, flying pixels: ``view.cleaned``)
cannot tell a rod 1 cm thick from the table at its ends; there, given the colour image, the
rod is what differs from the table in colour (``table_view.differs_in_colour``) and the
depth measures its height and its points. As in the paper, the mask's smallest enclosing
rectangle (OpenCV ``minAreaRect``) represents the rod; for metric accuracy its direction and
extent are taken from the mask's pixels lifted to 3-D (perspective makes the 2-D
rectangle's centre drift by millimetres towards the image edges).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace

import cv2
import numpy as np

from comgrasp_pin.camera import PinholeCamera
from comgrasp_pin.errors import (
    AmbiguousObjectError,
    ColourDepthMismatchError,
    ObjectCutByBorderError,
    ObjectNotFoundError,
    PerceptionError,
    UntrustedImageError,
)
from comgrasp_pin.geometry import GraspPose
from comgrasp_pin.perception._points import check_images, pixel_slopes
from comgrasp_pin.perception.frames.camera_input import camera_frame
from comgrasp_pin.perception.top_view.end_heights import CLEANED_PX, check_ends_stand
from comgrasp_pin.perception.top_view.grasp_points import (  # noqa: F401 (their home before)
    nearest_graspable,
    nearest_on_handle,
    rod_widths,
)
from comgrasp_pin.perception.top_view.joined_part import follow_thin_part, thin_part_around
from comgrasp_pin.perception.top_view.rod_alongside import check_no_rod_alongside
from comgrasp_pin.perception.top_view.rod_detection import RodDetection
from comgrasp_pin.perception.top_view.rod_shape import check_ends_seen, check_one_rod
from comgrasp_pin.perception.top_view.standing import (  # noqa: F401 (the thresholds' names here too)
    DETECT_SNR,
    EDGE_BAND,
    HEIGHT_SIGMAS,
    MAX_HEIGHT,
    MIN_HEIGHT,
    MIN_PIXELS,
    ColourNoHelp,
    segment,
    stands_at,
)
from comgrasp_pin.perception.top_view.table_view import (
    TableView,
    check_no_dip,
    cut_end_of,
    overhang,
    view_table,
)
from comgrasp_pin.perception.top_view.thin_parts import check_no_hidden_part, refuse_thin_part

PICK_AREA = (0.30, 0.80, -0.35, 0.35)  # x_min, x_max, y_min, y_max of the table (m, world)
# In a cleaned image (``table_view``) the rod is measured without its 1 px fringe
ERODE_PX = 1  # (2 holds flying pixels better, 35 % dropouts worse)
KEEP_EXTENT = 0.8  # ... unless the eroded rod is shorter than this share (a thin rod's handle gone)
END_SNR = 8.0  # a rod below this many noise stds (down to ``standing.DETECT_SNR``): its
# ends are left to a colour image, if one is given


def detect_rod_top_down(
    rgb: np.ndarray | Callable[[], np.ndarray] | None,
    depth: np.ndarray,
    camera: PinholeCamera | object,
    T_world_cam: np.ndarray,
    pick_area: tuple[float, float, float, float] = PICK_AREA,
    depth_scale: float | None = None,
    color_order: str = "rgb",
) -> RodDetection:
    """Find the rod in a top-down RGBD frame (depth: (H, W) z-depth in m, inf = none).

    The frame may come as the camera gives it (``camera_input.camera_frame``): integer
    depth with ``depth_scale`` (m per unit), colour in ``color_order`` ("rgb" or "bgr"),
    ``camera`` as K or a RealSense's or ROS's intrinsics, the images undistorted where its
    lens model says so (then ``mask``, ``rect`` and ``axis_px`` are in the undistorted
    image).

    Raises:
        ObjectNotFoundError: nothing above the table.
        ObjectCutByBorderError: the rod leaves the image, or hangs down over the table's
            edge (a rod that lies over the edge on the table's plane is measured whole:
            ``RodDetection.overhang``). When it runs out of the image at one end only,
            the error's ``seen`` is the part seen (``RodDetection.cut_end``).
        AmbiguousObjectError: two objects, or two rods side by side, where one rod should be,
            or parts of the rod lost in a noisy image beyond the end seen.
        InvalidDepthError: unusable depth.

    Height first: the object is what stands above the table in the depth, measured alone
    first. When a real camera's depth (``view.cleaned``) cannot measure it (a 1 cm rod's
    ends near the noise, its handle broken in two, a thin part too low for the threshold)
    and the colour image ``rgb`` (H, W, 3 uint8) is given, the colour is checked against
    the depth (``registration``) and, where it lines up, marks the object's pixels with the
    depth (``standing.segment``). Colour that does not line up is refused
    (ColourDepthMismatchError) unless the depth alone measures the rod after all (a rod of
    DETECT_SNR to END_SNR noise stds, whose ends the colour was to give). ``rgb`` may be a
    function that takes the colour image: it is then called only when the colour is needed
    (a render saved on every other view).
    """
    rgb, depth, camera = camera_frame(rgb, depth, camera, depth_scale, color_order)
    depth = check_images(None if callable(rgb) else rgb, depth, camera)
    view = view_table(depth, camera, T_world_cam, pick_area, EDGE_BAND)
    try:
        return _detect(view, None, depth, camera, T_world_cam, pick_area, rgb is not None)
    except (ObjectNotFoundError, AmbiguousObjectError, UntrustedImageError) as exc:
        if rgb is None or not view.cleaned or isinstance(exc, ObjectCutByBorderError):
            raise
        if callable(rgb):
            rgb = rgb()
            check_images(rgb, depth, camera)
        try:
            return _detect(view, rgb, depth, camera, T_world_cam, pick_area)
        except (ColourNoHelp, PerceptionError) as again:
            if isinstance(exc, _LeftToColour):  # the depth alone may measure it after all
                try:
                    return _detect(view, None, depth, camera, T_world_cam, pick_area)
                except PerceptionError:
                    pass
            if isinstance(again, ColourNoHelp) or (
                isinstance(exc, AmbiguousObjectError)  # several objects: the scene's reason
                and not isinstance(again, (AmbiguousObjectError, ColourDepthMismatchError))
            ):
                raise exc from None
            raise again from exc


def _detect(view: TableView, rgb, depth, camera, T_world_cam, pick_area,
            colour_to_come: bool = False, part=None) -> RodDetection:  # fmt: skip
    """``detect_rod_top_down`` in ``view``, with the colour's help when ``rgb`` is given.

    ``colour_to_come``: the depth is measured alone first, and a colour image is there to
    help if it fails: a rod lower than END_SNR noise stds is then left to the colour (its
    ends), rather than measured from the depth down to DETECT_SNR. ``part``: (H, W) bool, a
    thin part too low to stand that goes on from the object, followed to its end
    (``joined_part``: the depth alone measures a tool whose handle no pixel shows).
    """
    mask, standing, unmeasured, cut, bump_px = segment(view, pick_area, rgb)
    if part is not None:  # its pixels' height is not measured, as the colour's
        mask, standing, unmeasured = mask | part, standing | part, unmeasured | part
    if unmeasured.any():
        view = _on_the_rods_axis(view, mask, unmeasured, camera, T_world_cam)
    measured = ~unmeasured[mask]
    pixel = _pixel_size(depth, mask, view, camera, T_world_cam)
    core, eroded_px = _core(view, mask) if view.cleaned else (mask, 0)
    p = view.points[core]
    centroid = p[:, :2].mean(axis=0)
    _, _, vt = np.linalg.svd(p[:, :2] - centroid, full_matrices=False)
    direction = vt[0]
    check_one_rod(view.points[mask], centroid, direction, view.table_z, view.points_noise,
                  measured, heads=view.cleaned)  # fmt: skip
    check_no_rod_alongside(view.points[mask], centroid, direction)
    threshold = stands_at(view)
    check_ends_stand(view.points, mask, unmeasured, view.table_z, centroid, direction, threshold,
                     view.points_noise, CLEANED_PX * pixel if view.cleaned else 0.0)  # fmt: skip
    low = thin_part_around(view, standing, mask, pixel, threshold) if view.cleaned else None
    if low is not None and low[2] is not None:  # a thin part: followed once, from depth alone
        around = (standing, mask, pixel, threshold, low[1])
        return _followed(view, rgb, depth, camera, T_world_cam, pick_area, colour_to_come,
                         part, low[2], around)  # fmt: skip
    along = (p[:, :2] - centroid) @ direction
    lo, hi = np.percentile(along, [0.02, 99.98])
    if view.cleaned:
        check_ends_seen(view.points, standing, mask, centroid, direction, (lo, hi), p, bump_px)
    check_no_dip(view, pick_area, centroid, direction, (lo, hi), p, threshold)
    centre = centroid + 0.5 * (lo + hi) * direction
    near_centre = np.abs(along - 0.5 * (lo + hi)) < 0.01
    heights = p[near_centre, 2] - view.table_z if near_centre.any() else p[:, 2] - view.table_z
    handle_height = float(np.median(heights))
    least = END_SNR if colour_to_come else DETECT_SNR
    told = not colour_to_come and mask.sum() > bump_px  # larger than the noise's bumps grow
    if view.cleaned and rgb is None and handle_height < least * view.points_noise and not told:
        bumps = (f" and covers {mask.sum()} px, no more than the noise's bumps reach "
                 f"({bump_px:.0f} px)") if np.isfinite(bump_px) else ""  # fmt: skip
        raise (_LeftToColour if colour_to_come else ObjectNotFoundError)(
            f"the rod stands {1e3 * handle_height:.0f} mm above the table, less than {least:g} "
            f"times the filtered depth noise ({1e3 * view.points_noise:.1f} mm){bumps}: it "
            "cannot be told from the noise's own bumps; view it closer or with a less noisy camera"
        )
    yaw = float(np.arctan2(direction[1], direction[0]))
    yaw = (yaw + np.pi / 2) % np.pi - np.pi / 2  # (-pi/2, pi/2]
    grasp = GraspPose(float(centre[0]), float(centre[1]), view.table_z + 0.5 * handle_height,
                      yaw)  # fmt: skip
    length = float(hi - lo)
    if eroded_px:  # the erosion took pixels off each end
        length += 2 * eroded_px * pixel
    widths = rod_widths(p, centroid, direction, along - 0.5 * (lo + hi), yaw)
    contours, _ = cv2.findContours(mask.astype(np.uint8), cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
    rect = cv2.minAreaRect(max(contours, key=cv2.contourArea))
    # (lo, hi are along the axis from the centroid)
    ends_world = np.array([[*(centroid + s * direction), view.table_z] for s in (lo, hi)])
    T_cam_world = np.linalg.inv(T_world_cam)
    ends_cam = ends_world @ T_cam_world[:3, :3].T + T_cam_world[:3, 3]
    cut_end = cut_end_of(view, mask, centroid, direction, (lo, hi), yaw) if cut else 0
    det = RodDetection(grasp, length, widths, view.table_z, handle_height, mask, rect,
                       camera.project(ends_cam), overhang(ends_world, pick_area),
                       cut_end)  # fmt: skip
    if cut_end:
        raise ObjectCutByBorderError(
            f"the object runs out of the top-down image at its {'+' if cut_end > 0 else '-'}"
            f"yaw end: {1e3 * length:.0f} mm of it are seen (the exception's ``seen``)",
            seen=det,
        )
    if low is not None:  # a short object: a head whose handle the noise hides?
        too_low, table, _ = low
        check_no_hidden_part(length, float(np.median(widths[:, 1])), too_low, table, 1.0 / pixel)
    return det


def _followed(view, rgb, depth, camera, T_world_cam, pick_area, colour_to_come, part, found,
              around) -> RodDetection:  # fmt: skip
    """The rod with the thin part ``found`` joined (``joined_part.follow_thin_part``).

    Refused as the thin part (UntrustedImageError, with why) where there is colour to ask
    (``rgb``), a part was already joined (``part``), its end is not known, or the whole is
    refused (but for a cut by the image's border, and a whole left to the colour to come,
    which keep their own errors); ``around``: (standing, mask, pixel, threshold, the bare
    table around the object) as ``_detect`` has them.
    """
    if rgb is not None or part is not None:
        refuse_thin_part(found)
    standing, mask, pixel, threshold, table = around
    lost = ~(np.isfinite(depth) & (depth > 0))
    part = follow_thin_part(view, lost, standing, mask, pixel, threshold, found, table)
    try:
        return _detect(view, rgb, depth, camera, T_world_cam, pick_area, colour_to_come, part)
    except (ObjectCutByBorderError, _LeftToColour):  # its own error; the colour's to try
        raise
    except PerceptionError as whole:
        refuse_thin_part(found, f"Followed to its end, the whole is refused: {whole}")
        raise  # (refuse_thin_part raises)


def _pixel_size(depth, mask, view: TableView, camera, T_world_cam) -> float:
    """A pixel's size at the rod (m): its median depth (lost pixels, 0, counted) over fx."""
    z = float(np.median(depth[mask & np.isfinite(depth)]))
    if not z > 0:  # the camera lost most of the rod (filled by the cleaning): its points
        T_cam_world = np.linalg.inv(T_world_cam)
        z_points = view.points[mask] @ T_cam_world[2, :3] + T_cam_world[2, 3]
        z = float(np.median(z_points[np.isfinite(z_points)]))
    return z / camera.fx


def _core(view: TableView, mask: np.ndarray) -> tuple[np.ndarray, int]:
    """(the pixels to measure the rod on, the pixels eroded off its outline).

    A real camera's outline of an object (flying pixels, holes filled, the median) is
    unreliable over a pixel: the mask eroded by ERODE_PX (or fewer) pixels, as long as the
    erosion keeps the rod's extent (a thin rod would lose its handle) and MIN_PIXELS; else
    the mask.
    """
    pts = view.points[mask][:, :2]
    axis = np.linalg.svd(pts - pts.mean(axis=0), full_matrices=False)[2][0]
    extent = np.ptp(pts @ axis)
    for px in range(ERODE_PX, 0, -1):
        kernel = np.ones((2 * px + 1, 2 * px + 1), np.uint8)
        core = cv2.erode(mask.astype(np.uint8), kernel).astype(bool)
        if np.count_nonzero(core) < MIN_PIXELS:
            continue
        if np.ptp(view.points[core][:, :2] @ axis) > KEEP_EXTENT * extent:
            return core, px
    return mask, 0


def _on_the_rods_axis(view: TableView, mask, unmeasured, camera, T_world_cam) -> TableView:
    """``view`` with the rod's pixels whose depth does not stand lifted to its axis.

    Those are ``unmeasured`` within ``mask`` (found by the colour or filled in by the
    closing); each goes where its ray meets the horizontal
    plane at half the rod's median height (a round rod's axis, where its outline lies seen
    from above). Their depth is the table's or noise; taken as it is, a pixel on a rod's
    edge seen at an angle would land a height x tan(angle) beside it (1 mm for 1 cm).
    """
    lift = mask & unmeasured
    z_top = 0.5 * (view.table_z + float(np.median(view.points[mask][:, 2])))
    row, col = np.nonzero(lift)  # each pixel's ray at unit depth, as depth_to_points has it
    x_per_z = pixel_slopes(camera.width, camera.cx, camera.fx)[col]
    y_per_z = pixel_slopes(camera.height, camera.cy, camera.fy)[row]
    rays = np.column_stack([x_per_z, y_per_z, np.ones(len(row))])
    rays = rays @ T_world_cam[:3, :3].T
    origin = T_world_cam[:3, 3]
    points = view.points.copy()
    points[lift] = origin + ((z_top - origin[2]) / rays[:, 2])[:, None] * rays
    return replace(view, points=points)


class _LeftToColour(ObjectNotFoundError):
    """A rod lower than END_SNR noise stds, whose ends are left to the colour image."""
