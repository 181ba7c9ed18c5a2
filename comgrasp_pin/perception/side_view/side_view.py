"""The rod held in the jaws, from the side camera on the gripper: its pose in the ee frame.

Segmentation again leans on depth and on what the robot knows about itself: pixels are
lifted to the ee frame (T_ee_cam comes from the robot description), and the rod is what lies
in the slab between the jaws (|y_ee| small) outside the gripper's own volume (fingers, pads,
palm, wrist) and, when the table is near, above it. The jaws centre the rod, so its axis
passes through y_ee = 0: its direction in the x-z plane comes from ``rod_axis``, its ends
and centre from ``rod_ends``, hence its geometric centre, where the jaws hold it, and tilt.
The depth is cleaned, and the handle's surface followed along the jaw axis, in
``side_depth``.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import cv2
import numpy as np

from comgrasp_pin import validate
from comgrasp_pin.camera import PinholeCamera
from comgrasp_pin.geometry import check_transform
from comgrasp_pin.perception._points import check_images
from comgrasp_pin.perception.frames.camera_input import camera_frame
from comgrasp_pin.perception.side_view.held_axis import RodPoints, rod_along_axis, rod_in_jaws
from comgrasp_pin.perception.side_view.held_pieces import (
    OFF_AXIS_MARGIN,
    check_length,
    check_no_gap,
    check_width,
)
from comgrasp_pin.perception.side_view.held_region import held_candidates, robot_volume
from comgrasp_pin.perception.side_view.rod_ends import centre_along, end_profile
from comgrasp_pin.perception.side_view.side_depth import clean_side_depth, surface_line

OFF_AXIS_PERCENTILE = 99.0  # SideView.off_axis: nearly the farthest point, robust to a stray


@dataclass(frozen=True)
class SideView:
    """The held rod in the ee frame. SI units, angles in rad.

    Attributes:
        T_ee_obj: (4, 4) pose of the rod: origin at its geometric centre, x along it (the
            end towards +x_ee), y along the jaw axis (ee y), z = x cross y.
        theta: tilt in the jaws: rotation of the rod's axis about ee-y from ee-x, signed
            (positive when the +x end is higher, i.e. towards -z_ee); in (-pi/2, pi/2).
        length: visible extent of the rod along its axis (m).
        grasp_offset: where the jaws hold it: the point of the axis nearest the TCP, along
            +x_obj from the rod's centre (m).
        mask: (H, W) bool rod pixels.
        rect: OpenCV rotated rectangle of the mask.
        axis_px: (2, 2) pixel ends of the axis.
        tcp_px: (2,) pixel of the TCP.
        radius: the handle's radius (m): from the jaws' opening, or fitted.
        off_axis: how far the rod's visible surface reaches from its axis (m, the
            OFF_AXIS_PERCENTILE-th percentile): a head or a weight reaches farther than the
            handle. The rod's CoM lies within this of the axis.
        axis_std: standard error of the axis' position from the handle's surface points
            (m): the spread of their distances from the fitted cylinder over sqrt(count).
        tilt_std: standard error of ``theta`` (rad) from the scatter of the rod's slice
            centres about its axis.
        surface_y: ee-y (m) of the handle's visible surface where the axis passes nearest
            the TCP, and surface_slope its change per metre along the rod (a line fitted to
            the handle's points); between two views they give the rod's shift along the jaw
            axis and its turn out of the jaws' plane. surface_y_std, surface_slope_std: their
            standard errors.
        creep: (4, 4) the rod's motion in the jaws while the view was averaged over a torque
            window (from a view at its start to one at its end), or None for a single frame.
        depth_slices: (k, 3) the depth line's slices: index of the 1 cm slice along ee
            ``x_axis`` from the TCP, its points' median position along and median ee-y (m);
            two views pair them slice by slice (``procedures.rod_motion.depth_change``), or
            None.
        camera_ee: (3,) the camera's optical centre in the ee frame (m), from T_ee_cam:
            what a calibration error turns the view about; or None.
    """

    T_ee_obj: np.ndarray
    theta: float
    length: float
    grasp_offset: float
    mask: np.ndarray
    rect: tuple
    axis_px: np.ndarray
    tcp_px: np.ndarray
    radius: float
    off_axis: float
    axis_std: float
    tilt_std: float
    surface_y: float
    surface_slope: float
    surface_y_std: float
    surface_slope_std: float
    creep: np.ndarray | None = None
    depth_slices: np.ndarray | None = None
    camera_ee: np.ndarray | None = None


def observe_held_rod(
    rgb: np.ndarray | None,
    depth: np.ndarray,
    camera: PinholeCamera | object,
    T_ee_cam: np.ndarray,
    T_world_ee: np.ndarray | None = None,
    table_z: float | None = None,
    rod_length: float | None = None,
    exclude_capsules: Sequence[tuple[np.ndarray, np.ndarray, float]] = (),
    centre_hint: float | None = None,
    handle_radius: float | None = None,
    tilt_only: bool = False,
    depth_scale: float | None = None,
    color_order: str = "rgb",
) -> SideView:
    """Locate the rod held in the jaws in a side-camera RGBD frame.

    Args:
        rgb: (H, W, 3) colour image, or None; only checked to match ``depth``.
        depth: (H, W) z-depth (m), inf where nothing is seen; or integers in the camera's
            units with ``depth_scale`` (m per unit).
        camera: intrinsics: a PinholeCamera, K, or a RealSense's or ROS's fields (the
            images undistorted where the lens model says so; ``camera_input``).
        T_ee_cam: (4, 4) optical frame of the camera in the ee frame.
        T_world_ee: (4, 4) pose of the ee in the world, or None. With ``table_z`` too,
            points within 3 mm of the table plane (world z) are left out, so that the rod
            can be seen while it still rests on the table.
        table_z: height of the table plane (world z, m), or None; see ``T_world_ee``.
        rod_length: the rod's length if known (e.g. from the top view, m). A steeply hanging
            rod may leave the image or hide an end behind the gripper; with the length, the
            centre is found from the one end that is seen whole.
        exclude_capsules: the robot's own links as (p0 (3,), p1 (3,), radius) capsules in
            the ee frame; points inside them are not the rod (self-filtering).
        centre_hint: where the rod's centre was along ee-x from the TCP when it was grasped
            (m; from the top view and the commanded grasp). Used only when neither end of
            the rod is seen whole: the rod turns in the jaws, it hardly slides along them.
        handle_radius: half the jaws' opening where they hold the rod (m), from the
            fingers' joint reading; fixes the radius of the fitted cylinder.
        tilt_only: for a slip watch, which looks for turns of degrees: a noisy image whose
            handle no cylinder fits gives the slice line's tilt (1-3 deg off at most)
            instead of an UntrustedImageError.
        depth_scale: metres per unit of an integer ``depth`` (``camera_input``).
        color_order: "rgb" or "bgr", the order of ``rgb``'s channels.

    Raises:
        ObjectNotFoundError: no rod in the image.
        ObjectCutByBorderError: the rod runs out of the image.
        AmbiguousObjectError: something in line with the rod, apart from it, between the
            jaws (``held_pieces``).
        InvalidDepthError: the depth image is unusable.
        UntrustedImageError: a noisy image of a handle no cylinder fits.
        InvalidInputError: a transform that is not a (4, 4) rigid one, or a length, radius,
            hint or table height that is not finite (or, for length and radius, not
            positive).
    """
    T_ee_cam = check_transform(T_ee_cam, "T_ee_cam")
    if T_world_ee is not None:
        T_world_ee = check_transform(T_world_ee, "T_world_ee")
    table_z, rod_length, centre_hint, handle_radius = _checked_numbers(
        table_z, rod_length, centre_hint, handle_radius
    )
    try:  # rounded to units of depth_scale; what is no array, camera_frame refuses
        integer = np.asarray(depth).dtype.kind in "ui"
    except (TypeError, ValueError):
        integer = False
    colour, depth, camera = camera_frame(rgb, depth, camera, depth_scale, color_order)
    rgb = colour() if callable(colour) else colour
    depth, noise, cleaned, measured = clean_side_depth(check_images(rgb, depth, camera))
    excluded = robot_volume(exclude_capsules)
    p, candidate = held_candidates(depth, camera, T_ee_cam, T_world_ee, table_z, excluded)
    quantum = float(depth_scale or 0.0) if integer else 0.0
    mask, handle, (x_axis, offset_xz), tilt_std = rod_in_jaws(
        p, candidate, handle_radius, noise, cleaned and not tilt_only, T_ee_cam[:3, 3], quantum
    )
    frame = _Frame(depth, camera, p, candidate, mask, np.linalg.inv(T_ee_cam), excluded,
                   measured)  # fmt: skip
    rod = rod_along_axis(p[mask], handle, x_axis, offset_xz, handle_radius)
    _check_one_rod(frame, rod, rod_length, handle_radius, cleaned)
    lo, hi, mid = _ends(frame, rod, rod_length, centre_hint)
    return _side_view(frame, rod, (lo, hi, mid), tilt_std, T_ee_cam[:3, 3])


def _checked_numbers(table_z, rod_length, centre_hint, handle_radius) -> tuple:
    """The optional numbers of ``observe_held_rod``, validated (InvalidInputError)."""
    return (
        validate.optional_number(table_z, "table_z (m)"),
        validate.optional_number(rod_length, "rod_length (m)", low=0.0, low_open=True),
        validate.optional_number(centre_hint, "centre_hint (m)"),
        validate.optional_number(handle_radius, "handle_radius (m)", low=0.0, low_open=True),
    )


@dataclass(frozen=True)
class _Frame:
    """One side-camera frame, as the checks look back into it.

    ``depth`` (H, W) m, the ``camera``, ``p`` (H, W, 3) its points in the ee frame,
    ``candidate`` (H, W) bool the pixels between the jaws, ``mask`` (H, W) bool the rod's,
    ``T_cam_ee`` (4, 4), the robot's own volume ``excluded`` and ``measured`` (H, W) bool
    the pixels the camera measured (``clean_side_depth``).
    """

    depth: np.ndarray
    camera: PinholeCamera
    p: np.ndarray
    candidate: np.ndarray
    mask: np.ndarray
    T_cam_ee: np.ndarray
    excluded: Callable[[np.ndarray], np.ndarray]
    measured: np.ndarray


def _check_one_rod(
    frame: _Frame, rod: RodPoints, rod_length: float | None, handle_radius, cleaned: bool
) -> None:
    """Refuse what is not one whole rod (``held_pieces``).

    A gap along it, a length unlike ``rod_length``, and, in a clean image, a width unlike
    one handle's.
    """
    near = rod.rho <= rod.radius + OFF_AXIS_MARGIN  # not a stray far across the slab
    axis = (rod.x_axis, rod.offset)
    check_no_gap(frame.mask, rod.along, near, axis, frame.depth, frame.camera, frame.T_cam_ee,
                 frame.excluded)  # fmt: skip
    check_length(rod.along[near], rod_length)
    if not cleaned:  # a noisy image of two rods fits no cylinder (UntrustedImageError)
        check_width(rod.points, rod.along, rod.handle, axis, handle_radius)


def _ends(
    frame: _Frame, rod: RodPoints, rod_length: float | None, centre_hint: float | None
) -> tuple[float, float, float]:
    """(lo, hi, mid): the rod's ends and centre along its axis (m).

    From its end profiles and, where an end is not seen whole, ``rod_length`` or
    ``centre_hint`` (``rod_ends``).
    """
    (lo, lo_sharp), (hi, hi_sharp) = (
        end_profile(rod.along, rod.rho, e, s, rod.radius)
        for e, s in ((rod.lo, -1.0), (rod.hi, 1.0))
    )
    mid = centre_along(
        rod.x_axis, (lo, hi), (lo_sharp, hi_sharp), rod.along, rod.offset, frame.depth,
        frame.p, frame.candidate, frame.mask, frame.camera, frame.T_cam_ee, rod_length,
        centre_hint, frame.excluded,
    )  # fmt: skip
    return lo, hi, mid


def _side_view(
    frame: _Frame, rod: RodPoints, ends: tuple, tilt_std: float, camera_ee: np.ndarray
) -> SideView:
    """The SideView of ``rod``: its pose, its picture in the image, its depth line.

    ``ends``: (lo, hi, mid), its ends and centre along its axis (m).
    """
    lo, hi, mid = ends
    x_axis, y_axis = rod.x_axis, np.array([0.0, 1.0, 0.0])
    centre = rod.offset + mid * x_axis
    T_ee_obj = np.eye(4)
    T_ee_obj[:3, :3] = np.column_stack([x_axis, y_axis, np.cross(x_axis, y_axis)])
    T_ee_obj[:3, 3] = centre
    theta = float(np.arctan2(-x_axis[2], x_axis[0]))
    grasp_offset = float(-centre @ x_axis)
    T_cam_ee = frame.T_cam_ee
    ends_ee = np.array([centre + s * x_axis for s in (lo - mid, hi - mid)])
    ends_cam = ends_ee @ T_cam_ee[:3, :3].T + T_cam_ee[:3, 3]
    tcp_cam = T_cam_ee[:3, 3]
    contours, _ = cv2.findContours(frame.mask.astype(np.uint8), cv2.RETR_EXTERNAL,
                                   cv2.CHAIN_APPROX_NONE)  # fmt: skip
    rect = cv2.minAreaRect(np.vstack(contours))
    off_axis = float(np.percentile(rod.rho, OFF_AXIS_PERCENTILE))
    y0, slope, y0_std, slope_std, slices = surface_line(
        rod.points, rod.along, rod.handle & frame.measured[frame.mask], rod.radius
    )
    handle, radius = rod.handle, rod.radius
    n_handle = max(int(handle.sum()), 1)
    axis_std = (
        float(np.std(rod.rho[handle] - radius) / np.sqrt(n_handle)) if handle.any() else radius
    )
    return SideView(T_ee_obj, theta, float(hi - lo), grasp_offset, frame.mask, rect,
                    frame.camera.project(ends_cam), frame.camera.project(tcp_cam[None])[0],
                    float(radius), off_axis, axis_std, tilt_std, y0, slope, y0_std, slope_std,
                    depth_slices=slices, camera_ee=camera_ee.copy())  # fmt: skip
