"""The rod held in the jaws, from the side camera on the gripper: its pose in the ee frame.

Segmentation again leans on depth and on what the robot knows about itself: pixels are
lifted to the ee frame (T_ee_cam comes from the robot description), and the rod is what lies
in the slab between the jaws (|y_ee| small) outside the gripper's own volume (fingers, pads,
palm, wrist) and, when the table is near, above it. The jaws centre the rod, so its axis
passes through y_ee = 0; a robust 3-D line fit on the visible surface gives its direction,
the extreme points along it give its ends, hence its geometric centre, length and tilt.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import cv2
import numpy as np

from comgrasp_pin.camera import PinholeCamera
from comgrasp_pin.errors import ObjectCutByBorderError, ObjectNotFoundError
from comgrasp_pin.perception._points import (
    blobs,
    border_pixels,
    check_images,
    fit_line,
    points_in,
)

SLAB_HALF_WIDTH = 0.08  # |y_ee| of the region the held object may occupy (m)
REACH = 0.40  # distance from the TCP beyond which nothing is the held object (m)
TABLE_MARGIN = 0.003  # points less than this above the table are the table (m)
MIN_PIXELS = 60
MAX_AXIS_FROM_TCP = 0.035  # a held rod's axis passes this close to the TCP (m)
MIN_EXTENT = 0.05  # a held rod is at least this long in view (m)
MAX_CYLINDER_MISFIT = 5e-4  # a round handle's points lie this close to the fitted cylinder (m)
# The gripper's own volume in the ee frame (from the URDF): fingers and pads (with margin),
# palm, and the wrist above it.
_FINGERS = (0.016, 0.06, -0.085, 0.018)  # |x| <, |y| <, z from, z to
_PALM = (0.035, 0.075, -0.14, -0.075)
_WRIST_RADIUS, _WRIST_BELOW_Z = 0.05, -0.13


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
        mask: (H, W) bool rod pixels; rect: OpenCV rotated rectangle of the mask;
        axis_px: (2, 2) pixel ends of the axis; tcp_px: (2,) pixel of the TCP.
    """

    T_ee_obj: np.ndarray
    theta: float
    length: float
    grasp_offset: float
    mask: np.ndarray
    rect: tuple
    axis_px: np.ndarray
    tcp_px: np.ndarray


def _gripper_volume(p: np.ndarray) -> np.ndarray:
    x, y, z = p[..., 0], p[..., 1], p[..., 2]
    inside = np.zeros(x.shape, dtype=bool)
    for ax, ay, z0, z1 in (_FINGERS, _PALM):
        inside |= (np.abs(x) < ax) & (np.abs(y) < ay) & (z > z0) & (z < z1)
    inside |= (np.hypot(x, y) < _WRIST_RADIUS) & (z < _WRIST_BELOW_Z)
    return inside


def observe_held_rod(
    rgb: np.ndarray | None,
    depth: np.ndarray,
    camera: PinholeCamera,
    T_ee_cam: np.ndarray,
    T_world_ee: np.ndarray | None = None,
    table_z: float | None = None,
    rod_length: float | None = None,
    exclude_capsules: Sequence[tuple[np.ndarray, np.ndarray, float]] = (),
    centre_hint: float | None = None,
    handle_radius: float | None = None,
) -> SideView:
    """Locate the rod held in the jaws in a side-camera RGBD frame.

    Args:
        depth: (H, W) z-depth (m), inf where nothing is seen.
        camera: intrinsics. T_ee_cam: (4, 4) optical frame of the camera in the ee frame.
        T_world_ee, table_z: with both, points within 3 mm of the table plane (world z) are
            left out, so that the rod can be seen while it still rests on the table.
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
    Raises ObjectNotFoundError, ObjectCutByBorderError, InvalidDepthError.
    """
    depth = check_images(rgb, depth, camera)
    p = points_in(T_ee_cam, depth, camera)
    finite = np.isfinite(p[..., 0])
    candidate = finite & (np.abs(p[..., 1]) < SLAB_HALF_WIDTH)
    candidate &= np.linalg.norm(np.nan_to_num(p, nan=1e3), axis=-1) < REACH
    if T_world_ee is not None and table_z is not None:
        z_world = np.nan_to_num(p, nan=1e3) @ T_world_ee[2, :3] + T_world_ee[2, 3]
        candidate &= z_world > table_z + TABLE_MARGIN

    def excluded(pts: np.ndarray) -> np.ndarray:
        """The robot's own volume (gripper and arm) among points (N, 3)."""
        inside = _gripper_volume(pts)
        for p0, p1, radius in exclude_capsules:
            inside |= _in_capsule(pts, np.asarray(p0, float), np.asarray(p1, float), radius)
        return inside

    idx = np.flatnonzero(candidate)  # the costlier tests only on what is left
    candidate.flat[idx[excluded(p.reshape(-1, 3)[idx])]] = False
    if not candidate.any():
        raise ObjectNotFoundError("nothing is held between the jaws (side camera)")
    mask = blobs(candidate, MIN_PIXELS, "side-camera image")
    points = p[mask]
    # Tilt lives in the ee x-z plane; the jaws fix the axis at y = 0.
    x_axis, offset_xz, handle = _centre_line(points[:, [0, 2]])
    if handle.sum() >= MIN_PIXELS:
        x_fit, offset_fit, misfit = _fit_cylinder(points[handle], x_axis, offset_xz, handle_radius)
        # Trust the refinement only near the slice estimate (it can lock on a wrong side)
        # and where the handle is round (a flat bar is no cylinder).
        if (
            x_fit @ x_axis > np.cos(np.radians(5.0))
            and np.linalg.norm(offset_fit - offset_xz) < 0.01
            and misfit < MAX_CYLINDER_MISFIT
        ):
            x_axis, offset_xz = x_fit, offset_fit
    x_axis = np.array([x_axis[0], 0.0, x_axis[1]])
    along = points @ x_axis
    lo, hi = np.percentile(along, [0.1, 99.9])
    offset = np.array([offset_xz[0], 0.0, offset_xz[1]])
    if np.linalg.norm(offset) > MAX_AXIS_FROM_TCP or hi - lo < MIN_EXTENT:
        raise ObjectNotFoundError(
            "nothing is held between the jaws: what the side camera sees "
            f"({100 * (hi - lo):.0f} cm long) does not pass through them"
        )
    rho = np.linalg.norm(points - offset - np.outer(along, x_axis), axis=1)
    radius = handle_radius if handle_radius else float(np.median(rho[handle]))
    (lo, lo_sharp), (hi, hi_sharp) = (
        _end_profile(along, rho, e, s, radius) for e, s in ((lo, -1.0), (hi, 1.0))
    )
    T_cam_ee = np.linalg.inv(T_ee_cam)
    mid = _centre_along(
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
    return SideView(T_ee_obj, theta, float(hi - lo), grasp_offset, mask, rect,
                    camera.project(ends_cam), camera.project(tcp_cam[None])[0])  # fmt: skip


HEAD_BAND = 0.015  # the last this much of an end shows whether it carries a head (m)
HEAD_RATIO = 1.2  # an end standing this many handle radii off the axis is a head
ROUND_BAND = 1.2  # a round end's visible cap lies within this many radii of its extreme
ROUND_MIN_POINTS = 15
PEEK = 0.012  # look this far beyond an end to tell whether it is really the end (m)
END_SLACK = 0.003  # a point of the rod this little beyond an end found is at that end (m)
LENGTH_TOLERANCE = 0.01  # seen and known lengths this close agree (m)
LENGTH_EXCESS = 0.004  # seen this much longer than known, something joined the rod (m)
BORDER_NEAR = 0.03  # an end this close to where the rod meets the image border is cut (m)


def _end_profile(along, rho, end, outwards, radius) -> tuple[float, bool]:
    """An end of the rod from the profile of the visible points near it.

    Args:
        along, rho: (N,) the points' coordinate along the axis and distance from it (m).
        end: the extreme coordinate seen at this end (m); outwards: +1 (hi end) or -1 (lo).
        radius: the handle's radius (m).
    Returns (the end's coordinate (m), sharp): a sharp end is located to a fraction of a
    millimetre, because it carries a head (it stands off the axis farther than the handle:
    its flat face is seen edge-on) or it is a round cap fitted by ``_round_end``. A plain
    handle end too thin for the cap fit may fall short by up to its radius.
    """
    near_end = outwards * (end - along) < HEAD_BAND
    if np.percentile(rho[near_end], 90) > HEAD_RATIO * radius:
        return end, True
    tip = _round_end(along, rho, end, outwards, radius)
    return (end, False) if tip is None else (tip, True)


def _round_end(along, rho, end, outwards, radius) -> float | None:
    """The tip of a round (hemispherical) end whose visible extreme is ``end`` (m, along
    the axis); None if the end does not show as a cap of the handle's ``radius``.

    The side camera sees a cap at the rod's end from behind and at a grazing angle, so the
    extreme of the visible points falls short of the tip (by up to half the radius). The
    visible cap points (``along``, distance ``rho`` from the axis; the cylinder's points
    lie at rho = radius) are on a sphere centred on the axis: each gives its centre as
    along - outwards * sqrt(radius^2 - rho^2). If they agree, the tip lies ``radius``
    beyond that centre.
    """
    cap = (outwards * (end - along) < ROUND_BAND * radius) & (rho < 0.85 * radius)
    if np.count_nonzero(cap) < ROUND_MIN_POINTS:
        return None
    centres = along[cap] - outwards * np.sqrt(radius**2 - rho[cap] ** 2)
    centre = np.median(centres)
    if np.median(np.abs(centres - centre)) > max(0.05 * radius, 5e-4):
        return None
    return float(outwards * max(outwards * end, outwards * centre + radius))


def _centre_along(
    x_axis, ends, sharp, along, offset, depth, points, candidate, mask, camera, T_cam_ee,
    rod_length, centre_hint, excluded,
) -> float:  # fmt: skip
    """Where the rod's centre lies along ``x_axis`` (coordinate, m), from its trusted ends.

    ``ends``: (lo, hi) coordinates of the ends seen; ``sharp``: whether each is located
    precisely (see ``_end_profile``). An end is trusted when the point just beyond it is
    in the image, nothing nearer to the camera covers it, and it is not in a region left
    out as the robot's own (else the rod may go on out of view, behind the gripper, or
    into the self-filter). With the rod's length known, the centre is found from the
    trusted end that is best located.
    """
    lo, hi = ends
    along_border = points[border_pixels(mask)] @ x_axis
    trusted = [
        _end_is_seen(
            offset + e * x_axis, s * x_axis, depth, points, candidate, camera, T_cam_ee,
            excluded,
        )
        and not np.any(np.abs(along_border - e) < BORDER_NEAR)
        for e, s in ((lo, -1.0), (hi, 1.0))
    ]  # fmt: skip
    if rod_length is None:
        if all(trusted):
            return 0.5 * (lo + hi)
        raise ObjectCutByBorderError(
            "an end of the held rod is out of view or hidden; pass rod_length (top view)"
        )
    if hi - lo > rod_length + LENGTH_EXCESS:
        # Something beyond the rod joined the mask: the rod is the length-L window that
        # holds the most points.
        centres = np.arange(lo + 0.5 * rod_length, hi - 0.5 * rod_length, 0.001)
        counts = [np.count_nonzero(np.abs(along - c) <= 0.5 * rod_length) for c in centres]
        return float(centres[np.asarray(counts) >= max(counts)].mean())
    if all(trusted) and hi - lo > rod_length - LENGTH_TOLERANCE and sharp[0] == sharp[1]:
        return 0.5 * (lo + hi)
    # One end: the trusted one; of two, the sharp one, else the farther from the jaws (the
    # nearer may be partly hidden by the fingers).
    rank = [(t, sh, abs(e)) for t, sh, e in zip(trusted, sharp, ends, strict=True)]
    best = int(np.argmax([rank[0] > rank[1], rank[1] > rank[0]]))
    if trusted[best]:
        return ends[best] - (-1.0, 1.0)[best] * 0.5 * rod_length
    if centre_hint is not None:
        # The rod reaches at least as far as seen at either end.
        return float(np.clip(centre_hint, hi - 0.5 * rod_length, lo + 0.5 * rod_length))
    raise ObjectCutByBorderError("neither end of the held rod is seen whole (side camera)")


def _end_is_seen(end, outwards, depth, points, candidate, camera, T_cam_ee, excluded) -> bool:
    """Whether the rod really ends at ``end`` (3-D point on the axis, ee frame, m;
    ``outwards``: unit axis direction): the point PEEK beyond it is in the image and shows
    background behind it, or the rod's own end covering it in perspective."""
    beyond = end + PEEK * outwards
    in_robot = bool(excluded(beyond[None])[0])
    p_cam = T_cam_ee[:3, :3] @ beyond + T_cam_ee[:3, 3]
    if p_cam[2] <= 0:
        return False
    u, v = camera.project(p_cam[None])[0]
    if not (2 <= u < camera.width - 2 and 2 <= v < camera.height - 2):
        return False
    row, col = int(round(v)), int(round(u))
    if candidate[row, col]:
        # What may be the rod (the mask before its opening): a wide head seen in
        # perspective (its point lies within the end found), or the rod going on beyond
        # this end (it was cut off by the border).
        return bool((points[row, col] - end) @ outwards < END_SLACK)
    # Seen if what lies there is farther (background); hidden if something else, nearer,
    # covers it (the gripper). Within the robot's own volume, where the self-filter would
    # have removed the rod, only if it is clearly farther (the rod would be in front).
    return bool(depth[row, col] > p_cam[2] + (0.01 if in_robot else -0.01))


def _centre_line(xz: np.ndarray, bin_width: float = 0.01):
    """The rod's axis in the ee x-z plane, from slice centres.

    The visible points are cut in slices across the rod; the median of each slice is a
    point of the centre line, and a line is fitted to those slice centres with outlier
    rejection. Heads and weights, which stand off the handle's axis over a few slices
    only, then do not pull the axis (a plain PCA of all points would).
    Returns (unit direction (2,) with positive x, the point nearest the TCP (2,), (N,) bool
    mask of the points in the slices kept: the handle).
    """
    _, direction = fit_line(np.c_[xz, np.zeros(len(xz))])
    direction = direction[:2] / np.linalg.norm(direction[:2])
    point = xz.mean(axis=0)
    in_kept = np.ones(len(xz), dtype=bool)
    for _ in range(2):
        normal = np.array([-direction[1], direction[0]])
        along, across = xz @ direction, xz @ normal
        bins = np.floor(along / bin_width).astype(int)
        labels = [b for b in np.unique(bins) if np.count_nonzero(bins == b) >= 5]
        if len(labels) < 3:
            break
        c = np.array([(np.median(along[bins == b]), np.median(across[bins == b])) for b in labels])
        keep = np.ones(len(c), dtype=bool)
        for _ in range(3):
            slope, intercept = np.polyfit(c[keep, 0], c[keep, 1], 1)
            residual = np.abs(c[:, 1] - (slope * c[:, 0] + intercept))
            keep = residual <= max(3.0 * np.median(residual[keep]), 0.002)
        point = intercept * normal
        direction = (direction + slope * normal) / np.hypot(1.0, slope)
        in_kept = np.isin(bins, np.array(labels)[keep])
    if direction[0] < 0:
        direction = -direction
    return direction, point - (point @ direction) * direction, in_kept


def _fit_cylinder(
    points: np.ndarray, direction: np.ndarray, point: np.ndarray, radius: float | None = None
):
    """Refine the axis (in the plane y = 0) by fitting a cylinder to the visible surface.

    The camera sees one side of the rod, so the visible points stand off the axis towards
    the camera; the slice centres inherit that offset, which changes along a tilted rod
    and biases the tilt. Fitting |(p - a) x u| = r (axis angle, its offset, radius r) by
    Gauss-Newton, with points far off the cylinder (heads, weights) left out, removes it.
    ``radius`` (m), when known (half the jaws' opening), is held fixed.
    Returns (direction (2,), point nearest the TCP (2,)) in the x-z plane, and the median
    distance of the points from the cylinder (m).
    """
    angle = np.arctan2(direction[1], direction[0])
    normal = np.array([-direction[1], direction[0]])
    params = np.array([angle, point @ normal, 0.0])

    def residuals(prm, pts):
        u = np.array([np.cos(prm[0]), 0.0, np.sin(prm[0])])
        n = np.array([-np.sin(prm[0]), 0.0, np.cos(prm[0])])
        rel = pts - prm[1] * n
        return np.linalg.norm(rel - np.outer(rel @ u, u), axis=1) - prm[2]

    params[2] = np.median(residuals(params, points)) if radius is None else radius
    free = 2 if radius is not None else 3
    keep = np.ones(len(points), dtype=bool)
    for _ in range(8):
        res = residuals(params, points[keep])
        jac = np.empty((len(res), free))
        for k, h in enumerate((1e-6, 1e-7, 1e-7)[:free]):
            step = np.zeros(3)
            step[k] = h
            jac[:, k] = (residuals(params + step, points[keep]) - res) / h
        # Levenberg-Marquardt step: damped, accepted only if it lowers the cost.
        jtj, jtr = jac.T @ jac, jac.T @ res
        for damping in (1e-6, 1e-3, 1e-1, 1.0):
            delta = np.linalg.solve(jtj + damping * np.diag(np.diag(jtj)), jtr)
            trial = params - np.r_[delta, np.zeros(3 - free)]
            if np.sum(residuals(trial, points[keep]) ** 2) < np.sum(res**2):
                params = trial
                break
        res_all = np.abs(residuals(params, points))
        keep = res_all < 3.0 * np.median(res_all[keep]) + 0.002
    u = np.array([np.cos(params[0]), np.sin(params[0])])
    if u[0] < 0:
        u = -u
    n = np.array([-np.sin(params[0]), np.cos(params[0])])
    return u, params[1] * n, float(np.median(res_all))


def _in_capsule(p: np.ndarray, p0: np.ndarray, p1: np.ndarray, radius: float) -> np.ndarray:
    """Bool mask of the points ``p`` (..., 3) within ``radius`` of the segment p0-p1."""
    d = p1 - p0
    t = np.clip(np.nan_to_num((p - p0) @ d / max(d @ d, 1e-12), nan=0.0), 0.0, 1.0)
    dist = np.linalg.norm(p - p0 - t[..., None] * d, axis=-1)
    return np.nan_to_num(dist, nan=np.inf) < radius
