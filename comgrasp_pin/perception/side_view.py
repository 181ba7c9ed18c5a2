"""The rod held in the jaws, from the side camera on the gripper: its pose in the ee frame.

Segmentation again leans on depth and on what the robot knows about itself: pixels are
lifted to the ee frame (T_ee_cam comes from the robot description), and the rod is what lies
in the slab between the jaws (|y_ee| small) outside the gripper's own volume (fingers, pads,
palm, wrist) and, when the table is near, above it. The jaws centre the rod, so its axis
passes through y_ee = 0: its direction in the x-z plane comes from ``rod_axis``, its ends
and centre from ``rod_ends``, hence its geometric centre, where the jaws hold it, and tilt.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import cv2
import numpy as np

from comgrasp_pin import validate
from comgrasp_pin.camera import PinholeCamera
from comgrasp_pin.errors import ObjectNotFoundError, UntrustedImageError
from comgrasp_pin.geometry import check_transform
from comgrasp_pin.perception._points import (
    blobs,
    check_images,
    denoise,
    drop_flying,
    fill_holes,
    noise_level,
    slice_medians,
)
from comgrasp_pin.perception.camera_input import camera_frame
from comgrasp_pin.perception.flat_face import face_points, looks_flat, strip_line
from comgrasp_pin.perception.held_pieces import (
    OFF_AXIS_MARGIN,
    check_length,
    check_no_gap,
    check_width,
    rod_line,
)
from comgrasp_pin.perception.held_region import held_candidates, robot_volume
from comgrasp_pin.perception.rod_axis import (
    MAX_REFINE_SHIFT,
    MAX_REFINE_TURN_DEG,
    refine_axis,
)
from comgrasp_pin.perception.rod_ends import centre_along, end_profile

MIN_PIXELS = 60
CLEAN_NOISE = 3e-4  # depth noisier than this (m, robust std about its median) is filtered
FLYING_MIN, FLYING_SIGMAS = 0.005, 4.0  # flying pixels: this far from all neighbours (m, stds)
MAX_AXIS_FROM_TCP = 0.035  # a held rod's axis passes this close to the TCP (m)
MIN_EXTENT = 0.05  # a held rod is at least this long in view (m)
DEPTH_MARGIN = 0.003  # the handle's surface lies within its radius (+ this) of y_ee = 0 (m)
DEPTH_SLICE = 0.01  # slices along the rod for its depth line (m)
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


def clean_side_depth(depth: np.ndarray) -> tuple[np.ndarray, float, bool]:
    """(depth, noise (m), cleaned): ``depth`` itself, 0 and False when it is clean.

    Else (pixels lost, i.e. 0, or noisier than CLEAN_NOISE against its 5 x 5 median) its
    flying pixels dropped, its holes (0 or inf) filled, the median taken, its noise, True.
    """
    smooth = denoise(fill_holes(depth))
    both = np.isfinite(depth) & np.isfinite(smooth)
    noise = noise_level(depth[both] - smooth[both])
    # A camera marks a lost pixel 0; inf is also what a render gives where nothing is seen.
    if np.any(depth <= 0) or noise > CLEAN_NOISE:
        grounded = drop_flying(depth, max(FLYING_MIN, FLYING_SIGMAS * noise))
        return denoise(fill_holes(grounded)), noise, True
    return depth, 0.0, False


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
    table_z = validate.optional_number(table_z, "table_z (m)")
    rod_length = validate.optional_number(rod_length, "rod_length (m)", low=0.0, low_open=True)
    centre_hint = validate.optional_number(centre_hint, "centre_hint (m)")
    handle_radius = validate.optional_number(handle_radius, "handle_radius (m)", low=0.0,
                                             low_open=True)  # fmt: skip
    colour, depth, camera = camera_frame(rgb, depth, camera, depth_scale, color_order)
    rgb = colour() if callable(colour) else colour
    depth, noise, cleaned = clean_side_depth(check_images(rgb, depth, camera))
    excluded = robot_volume(exclude_capsules)
    p, candidate = held_candidates(depth, camera, T_ee_cam, T_world_ee, table_z, excluded)
    if not candidate.any():
        raise ObjectNotFoundError("nothing is held between the jaws (side camera)")
    mask = blobs(candidate, MIN_PIXELS, "side-camera image")
    # Tilt lives in the ee x-z plane; the jaws fix the axis at y = 0. Not clutter in the slab.
    mask, (x_axis, offset_xz, handle, tilt_std) = rod_line(mask, p, handle_radius,
                                                           MAX_AXIS_FROM_TCP)  # fmt: skip
    points = p[mask]
    _check_held(points, x_axis, offset_xz)  # before judging the image: is anything held?
    x_axis, offset_xz, tilt_std = _axis_in_jaws(
        points, handle, (x_axis, offset_xz, tilt_std), handle_radius, noise,
        cleaned and not tilt_only, T_ee_cam[:3, 3],
    )  # fmt: skip
    along, lo, hi = _check_held(points, x_axis, offset_xz)
    x_axis = np.array([x_axis[0], 0.0, x_axis[1]])
    offset = np.array([offset_xz[0], 0.0, offset_xz[1]])
    rho = np.linalg.norm(points - offset - np.outer(along, x_axis), axis=1)
    radius = handle_radius if handle_radius else float(np.median(rho[handle]))
    T_cam_ee = np.linalg.inv(T_ee_cam)
    near = rho <= radius + OFF_AXIS_MARGIN  # not a stray far across the slab
    check_no_gap(mask, along, near, (x_axis, offset), depth, camera, T_cam_ee, excluded)
    check_length(along[near], rod_length)
    if not cleaned:  # a noisy image of two rods fits no cylinder (UntrustedImageError)
        check_width(points, along, handle, (x_axis, offset), handle_radius)
    (lo, lo_sharp), (hi, hi_sharp) = (
        end_profile(along, rho, e, s, radius) for e, s in ((lo, -1.0), (hi, 1.0))
    )
    mid = centre_along(
        x_axis, (lo, hi), (lo_sharp, hi_sharp), along, offset, depth, p, candidate, mask,
        camera, T_cam_ee, rod_length, centre_hint, excluded,
    )  # fmt: skip
    centre = offset + mid * x_axis
    y_axis = np.array([0.0, 1.0, 0.0])
    T_ee_obj = np.eye(4)
    T_ee_obj[:3, :3] = np.column_stack([x_axis, y_axis, np.cross(x_axis, y_axis)])
    T_ee_obj[:3, 3] = centre
    theta = float(np.arctan2(-x_axis[2], x_axis[0]))
    grasp_offset = float(-centre @ x_axis)

    ends = np.array([centre + s * x_axis for s in (lo - mid, hi - mid)])
    ends_cam = ends @ T_cam_ee[:3, :3].T + T_cam_ee[:3, 3]
    tcp_cam = T_cam_ee[:3, 3]
    contours, _ = cv2.findContours(mask.astype(np.uint8), cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
    rect = cv2.minAreaRect(np.vstack(contours))
    off_axis = float(np.percentile(rho, OFF_AXIS_PERCENTILE))
    # Where the handle's visible surface lies along the jaw axis (the camera's depth), as a
    # line along the rod: its change between two views is the rod shifting along the jaws
    # and turning out of their plane (the grasp's compliance), which the axis cannot show.
    # Only the handle's own surface (within its radius of the jaws' mid-plane): a head that
    # stands within the axis' silhouette but far across the jaws (an axe's blade) is not it.
    own = handle & (np.abs(points[:, 1]) <= radius + DEPTH_MARGIN)
    y0, slope, y0_std, slope_std, slices = _depth_line(along[own], points[own, 1])
    n_handle = max(int(handle.sum()), 1)
    axis_std = float(np.std(rho[handle] - radius) / np.sqrt(n_handle)) if handle.any() else radius
    return SideView(T_ee_obj, theta, float(hi - lo), grasp_offset, mask, rect,
                    camera.project(ends_cam), camera.project(tcp_cam[None])[0],
                    float(radius), off_axis, axis_std, tilt_std, y0, slope, y0_std, slope_std,
                    depth_slices=slices, camera_ee=T_ee_cam[:3, 3].copy())  # fmt: skip


def _check_held(points: np.ndarray, x_axis: np.ndarray, offset_xz: np.ndarray) -> tuple:
    """(the points' positions along the line, their 0.1 and 99.9 percentiles) (m).

    The line: ``x_axis`` (2,), ``offset_xz`` (2,) in the x-z plane. ObjectNotFoundError when
    it does not pass through the jaws or what it runs along is too short to be a held rod.
    """
    along = points @ np.array([x_axis[0], 0.0, x_axis[1]])  # as the axis in 3-D, to the bit
    lo, hi = np.percentile(along, [0.1, 99.9])
    if np.linalg.norm(offset_xz) > MAX_AXIS_FROM_TCP or hi - lo < MIN_EXTENT:
        raise ObjectNotFoundError(
            "nothing is held between the jaws: what the side camera sees "
            f"({100 * (hi - lo):.0f} cm long) does not pass through them"
        )
    return along, lo, hi


def _axis_in_jaws(
    points: np.ndarray,
    handle: np.ndarray,
    slice_line: tuple[np.ndarray, np.ndarray, float],
    radius: float | None,
    noise: float,
    strict: bool,
    camera_ee: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, float]:
    """The rod's axis in the x-z plane, from the slice line ``slice_line``.

    Returns (and ``slice_line`` is) (direction (2,), point nearest the TCP (2,), the
    angle's standard error (rad)).

    A flat bar seen edge-on (``flat_face.looks_flat``: narrower than the jaws' gap) is
    measured from its face: the mid-line of the face's points put on its plane
    (``flat_face``; near the slice line, else as a round handle). A round handle: the
    cylinder fitted to its surface (``rod_axis.refine_axis``); ``strict`` (a noisy image,
    not a slip watch) refuses one that no cylinder fits (UntrustedImageError).
    """
    x_axis, offset_xz, tilt_std = slice_line
    if handle.sum() < MIN_PIXELS:
        return slice_line
    normal = np.array([-x_axis[1], x_axis[0]])
    if looks_flat((points[handle][:, [0, 2]] - offset_xz) @ normal, radius):
        face = face_points(points[handle], camera_ee, noise)
        strip = None if face is None else strip_line(face[0], x_axis)
        if strip is not None and (
            strip[0] @ x_axis > np.cos(np.radians(MAX_REFINE_TURN_DEG))
            and np.linalg.norm(strip[1] - offset_xz) < MAX_REFINE_SHIFT
        ):
            return strip
    refined = refine_axis(points[handle], x_axis, offset_xz, radius, noise)
    if strict and refined[0] is x_axis:  # refine_axis hands the slice line back as it was
        raise UntrustedImageError(
            "no cylinder fits the held handle's points in this image with holes or noise, "
            "and the slice centres alone bias the tilt by up to 1-3 deg (measured): a "
            "round handle, seen with fewer holes or less noise, is needed"
        )
    return refined[0], refined[1], tilt_std


def _depth_line(along: np.ndarray, y: np.ndarray) -> tuple:
    """A line through (along, y): y at along = 0, dy/d along, their std, the slices.

    Fitted to the medians of 1 cm slices along the rod (the slices: (k, 3) of index,
    median along, median y): the points of one slice are one piece of surface, not
    independent samples, so the standard errors come from how the slices scatter about the
    line (point by point they would be some 30 times too small).
    """
    bins = np.floor(along / DEPTH_SLICE).astype(int)
    labels, medians = slice_medians(bins, (along, y), 5)
    if len(labels) < 3:
        y_mid = float(np.median(y)) if len(y) else 0.0
        return y_mid, 0.0, float("inf"), float("inf"), None
    c = np.column_stack([labels, medians])
    (slope, y0), cov = np.polyfit(c[:, 1], c[:, 2], 1, cov=True)  # scaled by the residuals
    return float(y0), float(slope), float(np.sqrt(cov[1, 1])), float(np.sqrt(cov[0, 0])), c
