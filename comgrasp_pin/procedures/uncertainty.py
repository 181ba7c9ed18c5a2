"""How well the trial grasp knows where the CoM lies along the rod: every error source the
robot can know, propagated to the position.

The position is a function of the readings: the torques, and each side view's rod pose in
the jaws. Its variance is the sum of
- ``estimator``: the torque noise (and the axis prior), the estimate's covariance carried
  through the projection on the rod's axis (its Jacobian, by finite differences);
- ``tilt`` (one pose): the view's tilt is known to its standard error (``SideView.tilt_std``):
  the position recomputed with the view turned by it about the jaw axis;
- two poses: the rod's motion in the jaws between the poses, measured by the two views
  (``rod_motion``), is known to the views' standard errors: ``tilt`` (its turn
  in the jaws' plane), ``shift`` (along the jaw axis: the depth line's change, its slices'
  scatter and its error model, ``depth_line_std``), ``out of plane``; and ``slide``, along
  the rod's own axis, which the views do not measure well: half their disagreement on where
  the jaws hold the rod;
- ``off axis`` (one pose, closed form): the CoM's distance from the axis at the seen tilt;
- ``calibration``: the side camera's pose and depth scale, known to its calibration's
  stated accuracy (``calibration_std``); none for the ideal preset's exact camera.
Sensitivities are first order (finite differences of the same computation the estimate
ran: ``position``, the caller's), so a source the robot measured small stays small and none
is inflated by a factor. ``std_parts`` gathers them all.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pinocchio as pin

from comgrasp_pin.config import DepthLineErrorConfig, DepthNoiseConfig
from comgrasp_pin.estimation import ComEstimate, com_along_axis
from comgrasp_pin.procedures.rod_motion import depth_change_std

STEP = 1e-5
"""Finite-difference step for the CoM (m) and for angles (rad)."""


def rotate_about_jaws(T_ee_obj: np.ndarray, angle: float) -> np.ndarray:
    """``T_ee_obj`` turned by ``angle`` (rad) about the jaw axis (ee-y) through the rod's
    axis point nearest the TCP: a tilt error, or the rod turning in the jaws."""
    c, s = np.cos(angle), np.sin(angle)
    R = np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])
    x_axis, origin = T_ee_obj[:3, 0], T_ee_obj[:3, 3]
    pivot = origin - (origin @ x_axis) * x_axis
    T = T_ee_obj.copy()
    T[:3, :3] = R @ T_ee_obj[:3, :3]
    T[:3, 3] = pivot + R @ (origin - pivot)
    return T


def estimator_std(est: ComEstimate, T_ee_obj: np.ndarray) -> float:
    """Std of ``com_along_axis(est, T_ee_obj)`` from the estimate's covariance (m)."""
    if est.cov is None:
        return float("nan")
    x0 = com_along_axis(est, T_ee_obj)
    J = np.empty(3)
    for i in range(3):
        shifted = replace(est, com_ee=est.com_ee + STEP * np.eye(3)[i])
        J[i] = (com_along_axis(shifted, T_ee_obj) - x0) / STEP
    return float(np.sqrt(max(J @ est.cov[1:, 1:] @ J, 0.0)))


def calibration_std(
    est: ComEstimate,
    T_ee_obj: np.ndarray,
    camera_ee: np.ndarray,
    shift: float,
    turn: float,
    scale: float,
) -> float:
    """The position's std (m) from the side camera's calibration.

    Its pose is off by ``shift`` (m) in a random direction and by ``turn`` (rad) about a
    random axis through the camera (``camera_ee``, (3,) in the ee frame), its depth scale by
    ``scale`` (relative std). The error is common to every view of the episode: it moves
    the perceived rod, not the rod's motion between views (first order). A fixed length in
    a random direction puts a third of its variance on each axis.
    """
    x0 = com_along_axis(est, T_ee_obj)
    p, R0 = T_ee_obj[:3, 3], T_ee_obj[:3, :3]
    moved = []
    for axis in np.eye(3):
        T = T_ee_obj.copy()
        T[:3, 3] = p + shift / np.sqrt(3.0) * axis
        moved.append(T)
        R = pin.exp3(turn / np.sqrt(3.0) * axis)
        T = T_ee_obj.copy()
        T[:3, :3], T[:3, 3] = R @ R0, camera_ee + R @ (p - camera_ee)
        moved.append(T)
    T = T_ee_obj.copy()
    T[:3, 3] = camera_ee + (1.0 + scale) * (p - camera_ee)
    moved.append(T)
    return float(np.sqrt(sum((com_along_axis(est, T) - x0) ** 2 for T in moved)))


def tilt_std_one_view(est: ComEstimate, T_ee_obj: np.ndarray, tilt_std: float) -> float:
    """Change of the position (m) when the view is turned by its tilt's standard error."""
    x0 = com_along_axis(est, T_ee_obj)
    return abs(com_along_axis(est, rotate_about_jaws(T_ee_obj, tilt_std)) - x0)


def handle_distance(view) -> float:
    """Distance (m) from the side camera's optical centre (``view.camera_ee``) to the
    rod's axis at the middle of the slices its depth line was fitted on (along the view's
    axis from the TCP; at the axis' point nearest the TCP without slices); nan without a
    camera pose."""
    if view.camera_ee is None:
        return float("nan")
    x_axis, origin = view.T_ee_obj[:3, 0], view.T_ee_obj[:3, 3]
    slices = view.depth_slices
    along = float(np.median(slices[:, 1])) if slices is not None and len(slices) else 0.0
    point = origin + (along - origin @ x_axis) * x_axis
    return float(np.linalg.norm(point - view.camera_ee))


def depth_line_std(first, camera: DepthNoiseConfig,
                   model: DepthLineErrorConfig | None) -> float:  # fmt: skip
    """Std (m) of the depth line's change from the ``first`` view to a later one beyond its
    slices' scatter (``DepthLineErrorConfig.shift_std``): the handle's radius as the first
    view fitted it, the ``camera``'s depth resolution at ``handle_distance``; 0 without a
    ``model``."""
    if model is None:
        return 0.0
    distance = handle_distance(first)
    axial = camera.axial_std(distance) if np.isfinite(distance) else 0.0
    return model.shift_std(first.radius, axial)


def std_parts(est: ComEstimate, views: list, depth: list, bounds: tuple[float, float],
              position, calibration: DepthNoiseConfig, off_axis: float | None,
              depth_line: DepthLineErrorConfig | None) -> dict:  # fmt: skip
    """The CoM point's standard deviation along the rod (m) by source.

    ``est``: the estimate from the poses of ``views`` (each pose's SideView; the first
    defines the rod's axis). One view: its ``tilt``. Several: the rod's motion between them
    (``motion_stds``; ``depth``, ``bounds`` and ``position`` as there; the depth line's
    error model ``depth_line`` with the side camera's depth resolution, ``depth_line_std``).
    Then the ``estimator``'s, the side camera's ``calibration`` (its stated accuracy, where
    ``enabled``: ``calibration_std``) and ``off axis`` (m; None: not a source here).
    """
    first = views[0]
    T_ee_obj = first.T_ee_obj
    if len(views) > 1:
        x0 = com_along_axis(est, T_ee_obj)
        line_std = depth_line_std(first, calibration, depth_line)
        parts = motion_stds(position, views, depth, bounds, x0, line_std)
    else:
        parts = {"tilt": tilt_std_one_view(est, T_ee_obj, first.tilt_std)}
    parts["estimator"] = estimator_std(est, T_ee_obj)
    cal = calibration
    if first.camera_ee is not None and cal.enabled:
        parts["calibration"] = calibration_std(est, T_ee_obj, first.camera_ee,
                                               cal.extrinsic_shift,
                                               np.radians(cal.extrinsic_turn_deg),
                                               cal.scale_std)  # fmt: skip
    if off_axis is not None:
        parts["off axis"] = off_axis
    return parts


def motion_stds(position, views: list, depth: list, bounds: tuple[float, float],
                x0: float, line_std: float = 0.0) -> dict:  # fmt: skip
    """The several-pose position's error sources from the rod's motion between the views (m).

    ``position(views, depth, slides)``: the CoM point along the first view's rod axis (m)
    estimated with the rod moved between the views as they saw it (``rod_motion``, with the
    depth lines where ``depth`` says, each later view's slide along the rod in ``slides``);
    ``x0`` is its value for ``views`` as they are. Each of what the views measure of the
    motion is moved by its standard error and the position recomputed; the slide along the
    rod's axis, which the views do not separate from their own error, by half their
    disagreement on where the jaws hold it. Each source is summed in quadrature over the
    later views. Where a view's depth line was not used (``depth`` False), the shift and the
    out-of-plane turn are taken as uniform within the compliance's bounds (``bounds``: m,
    rad), standard error bound / sqrt 3. Where it was used, its change's standard error is
    its slices' scatter (``depth_change_std``) and ``line_std`` (m, the depth line's error
    model, ``depth_line_std``) in quadrature.
    """
    first = views[0]
    no_slide = [0.0] * (len(views) - 1)
    parts = {"tilt": 0.0, "shift": 0.0, "out of plane": 0.0, "slide": 0.0}
    for i, view in enumerate(views[1:]):
        if depth[i]:
            dy, dslope = depth_change_std(first, view)
            dy = float(np.hypot(dy, line_std))
        else:  # the depth lines disagree: the motion is within the compliance's bounds,
            # uniform there (std: bound / sqrt 3)
            dy, dslope = bounds[0] / np.sqrt(3.0), float(np.tan(bounds[1])) / np.sqrt(3.0)
            view = replace(view, surface_y=first.surface_y, surface_slope=(
                first.surface_slope if view.T_ee_obj[:3, 0] @ first.T_ee_obj[:3, 0] >= 0
                else -first.surface_slope))  # fmt: skip
        changed = {
            "tilt": (replace(view, T_ee_obj=rotate_about_jaws(
                view.T_ee_obj, float(np.hypot(first.tilt_std, view.tilt_std)))), 0.0),
            "shift": (replace(view, surface_y=view.surface_y + dy), 0.0),
            "out of plane": (replace(view, surface_slope=view.surface_slope + dslope), 0.0),
            "slide": (view, 0.5 * abs(abs(first.grasp_offset) - abs(view.grasp_offset))),
        }  # fmt: skip
        for name, (other_view, slide) in changed.items():
            moved = list(views)
            moved[i + 1] = other_view
            moved_depth = [*depth[:i], True, *depth[i + 1 :]]
            slides = [*no_slide[:i], slide, *no_slide[i + 1 :]]
            parts[name] += (position(moved, moved_depth, slides) - x0) ** 2
    parts["creep"] = _creep_std(position, views, depth, x0)
    return {name: float(np.sqrt(v)) for name, v in parts.items()}


def _creep_std(position, views: list, depth: list, x0: float) -> float:
    """Variance (m^2) from the rod creeping in the jaws while the torques were averaged: the
    mean position is taken halfway between the window's start and end views; where in
    between it really was is uniform over half the creep either way (std: half / sqrt 3),
    each view turned by that much about the jaws in turn."""
    total = 0.0
    no_slide = [0.0] * (len(views) - 1)
    for i, view in enumerate(views):
        if view.creep is None:
            continue
        creep_tilt = float(np.arctan2(view.creep[0, 2], view.creep[0, 0]))
        turned = list(views)
        turned[i] = replace(
            view, T_ee_obj=rotate_about_jaws(view.T_ee_obj, 0.5 * creep_tilt / np.sqrt(3.0))
        )
        total += (position(turned, depth, no_slide) - x0) ** 2
    return total
