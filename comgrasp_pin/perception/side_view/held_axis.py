"""The held rod's axis in the jaws, from the side camera's points in the ee frame.

The jaws centre the rod, so its axis passes through y_ee = 0: ``rod_in_jaws`` finds it in
the x-z plane (the slice line of ``held_pieces``, then a flat bar's face or a round
handle's fitted cylinder, ``_axis_in_jaws``); ``rod_along_axis`` places the rod's points
about it (``RodPoints``). ObjectNotFoundError when nothing held passes through the jaws.
SI units, the ee frame throughout.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from comgrasp_pin.errors import ObjectNotFoundError, UntrustedImageError
from comgrasp_pin.perception._points import blobs
from comgrasp_pin.perception.side_view.flat_face import face_points, looks_flat, strip_line
from comgrasp_pin.perception.side_view.held_pieces import rod_line
from comgrasp_pin.perception.side_view.rod_axis import (
    MAX_REFINE_SHIFT,
    MAX_REFINE_TURN_DEG,
    refine_axis,
)

MIN_PIXELS = 60
MAX_AXIS_FROM_TCP = 0.035  # a held rod's axis passes this close to the TCP (m)
MIN_EXTENT = 0.05  # a held rod is at least this long in view (m)
MAX_SLICE_BIAS_DEG = 1.0
"""Where no cylinder fits a noisy image, the slice line is taken for a handle whose slice
centres' bias scale (``slice_bias``, which then joins the tilt's std: the slice line's
measured rms error is 0.56-0.74 of it) is at most this: no more than the fitted cylinders
err on thin handles (0.4-0.5 deg rms on 1 and 2 cm handles in the realistic preset).
Thicker handles are refused there."""


@dataclass(frozen=True)
class RodPoints:
    """The held rod's points about its axis, in the ee frame (m).

    Attributes:
        points: (n, 3) the rod's points; handle: (n,) bool, the handle's.
        x_axis: (3,) the axis' direction, in the x-z plane; offset: (3,) its point nearest
            the TCP.
        along: (n,) each point's position along the axis; rho: (n,) its distance from it.
        lo, hi: the visible extent along the axis; radius: the handle's radius.
    """

    points: np.ndarray
    handle: np.ndarray
    x_axis: np.ndarray
    offset: np.ndarray
    along: np.ndarray
    rho: np.ndarray
    lo: float
    hi: float
    radius: float


def rod_in_jaws(
    p: np.ndarray,
    candidate: np.ndarray,
    handle_radius: float | None,
    noise: float,
    strict: bool,
    camera_ee: np.ndarray,
    quantum: float = 0.0,
) -> tuple:
    """The held rod in the ``candidate`` pixels between the jaws, and its axis.

    ``p``: (H, W, 3) the pixels' points in the ee frame. Returns (the rod's mask (H, W),
    its handle's points (n,) bool, its axis in the x-z plane as (direction (2,), point
    nearest the TCP (2,)), the tilt's standard error (rad)).

    Tilt lives in the ee x-z plane; the jaws fix the axis at y = 0. Not clutter in the
    slab. ObjectNotFoundError when nothing held passes through the jaws.
    """
    if not candidate.any():
        raise ObjectNotFoundError("nothing is held between the jaws (side camera)")
    mask = blobs(candidate, MIN_PIXELS, "side-camera image")
    mask, (x_axis, offset_xz, handle, tilt_std) = rod_line(mask, p, handle_radius,
                                                           MAX_AXIS_FROM_TCP)  # fmt: skip
    points = p[mask]
    _check_held(points, x_axis, offset_xz)  # before judging the image: is anything held?
    x_axis, offset_xz, tilt_std = _axis_in_jaws(
        points,
        handle,
        (x_axis, offset_xz, tilt_std),
        handle_radius,
        noise,
        strict,
        camera_ee,
        quantum,
    )
    return mask, handle, (x_axis, offset_xz), tilt_std


def rod_along_axis(
    points: np.ndarray,
    handle: np.ndarray,
    x_axis_xz: np.ndarray,
    offset_xz: np.ndarray,
    handle_radius: float | None,
) -> RodPoints:
    """The rod's ``points`` (n, 3) about its axis ``x_axis_xz`` through ``offset_xz``.

    Both are (2,) in the x-z plane; the radius is ``handle_radius`` or, if None, the
    handle's median distance from the axis.
    """
    along, lo, hi = _check_held(points, x_axis_xz, offset_xz)
    x_axis = np.array([x_axis_xz[0], 0.0, x_axis_xz[1]])
    offset = np.array([offset_xz[0], 0.0, offset_xz[1]])
    rho = np.linalg.norm(points - offset - np.outer(along, x_axis), axis=1)
    radius = handle_radius if handle_radius else float(np.median(rho[handle]))
    return RodPoints(points, handle, x_axis, offset, along, rho, lo, hi, radius)


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
    quantum: float = 0.0,
) -> tuple[np.ndarray, np.ndarray, float]:
    """The rod's axis in the x-z plane, from the slice line ``slice_line``.

    Returns (and ``slice_line`` is) (direction (2,), point nearest the TCP (2,), the
    angle's standard error (rad)).

    A flat bar seen edge-on (``flat_face.looks_flat``: narrower than the jaws' gap) is
    measured from its face: the mid-line of the face's points put on its plane
    (``flat_face``; near the slice line, else as a round handle). A round handle: the
    cylinder fitted to its surface (``rod_axis.refine_axis``); ``strict`` (a noisy image,
    not a slip watch) refuses one that no cylinder fits (UntrustedImageError), unless it is
    so thin that the slice line's bias scale stays within ``MAX_SLICE_BIAS_DEG``
    (``slice_bias``; then the slice line, the bias scale added to its tilt std).
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
    refined = refine_axis(points[handle], x_axis, offset_xz, radius, noise, quantum)
    if strict and refined[0] is x_axis:  # refine_axis hands the slice line back as it was
        bias = slice_bias(radius, camera_ee, x_axis, offset_xz)
        if bias > np.radians(MAX_SLICE_BIAS_DEG):
            why = (
                f"may bias the tilt by about {np.degrees(bias):.1f} deg for a handle this "
                f"thick (at most {MAX_SLICE_BIAS_DEG:g} deg is taken)"
                if np.isfinite(bias)
                else "bias the tilt by an amount that only the handle's radius bounds (give "
                "handle_radius: half the jaws' opening)"
            )
            raise UntrustedImageError(
                "no cylinder fits the held handle's points in this image with holes or "
                f"noise, and the slice centres alone {why}: a round handle, seen with fewer "
                "holes or less noise, is needed"
            )
        return x_axis, offset_xz, float(np.hypot(tilt_std, bias))
    return refined[0], refined[1], tilt_std


def slice_bias(
    radius: float | None, camera_ee: np.ndarray, x_axis: np.ndarray, offset_xz: np.ndarray
) -> float:
    """The scale of the slice centres' bias on a round handle's tilt (rad): (pi/4) r / D.

    The camera sees the half of the handle that faces it, whose points stand off the axis
    towards the camera by (pi/4) r on average (radius r). Along an ideal straight cylinder
    that offset is the same everywhere and the centres' line is parallel to the axis; the
    handle's ends, the fingers and the silhouette's edge pixels make it vary, over the
    distance D from the camera to the axis. An empirical scale, measured against the
    simulator's truth on realistic side views (50 accuracy grasps each, D = 0.31 m): the
    slice line's tilt errs by 0.54, 1.07, 1.62 and 2.38 deg rms for r = 5, 10, 20 and
    25 mm, 0.56-0.74 of (pi/4) r / D. Infinite without a radius.
    """
    if not radius:
        return float("inf")
    u = np.array([x_axis[0], 0.0, x_axis[1]])
    d = np.asarray(camera_ee, float) - np.array([offset_xz[0], 0.0, offset_xz[1]])
    distance = float(np.linalg.norm(d - (d @ u) * u))
    return float(np.pi / 4 * radius / distance) if distance > 0 else float("inf")
