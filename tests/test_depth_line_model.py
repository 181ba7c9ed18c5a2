"""The wrist camera's depth-line error model (``config.DepthLineErrorConfig``, carried into
``pos_std_m`` by ``procedures.uncertainty``) and the depth line's measured pixels.

References: the formula written out here from the camera's numbers (D435: f 424 px,
baseline 50 mm, subpixel 0.08; the camera 0.30 m out along -y, 0.05 m along x and 0.06 m
towards the wrist, urdf/ur5_gripper.urdf), a linear position whose error is known, and a
synthetic depth frame of a round handle against nothing."""

from dataclasses import asdict, replace

import numpy as np
import pytest

from comgrasp_pin.config import (
    DepthLineErrorConfig,
    DepthNoiseConfig,
    EpisodeConfig,
    sensor_preset,
)
from comgrasp_pin.errors import InvalidInputError
from comgrasp_pin.perception.side_view.side_depth import clean_side_depth, surface_line
from comgrasp_pin.perception.side_view.side_view import SideView
from comgrasp_pin.procedures.rod_motion import paired_depth_line
from comgrasp_pin.procedures.uncertainty import depth_line_std, handle_distance, motion_stds

CAMERA_EE = np.array([0.05, -0.30, -0.06])
D435 = DepthNoiseConfig(focal_px=424.0, baseline=0.05, subpixel=0.08, quantum=0.001)


def _view(radius=0.02, along=(0.0, 0.1), y0=-0.017, y_std=1e-6, camera=CAMERA_EE) -> SideView:
    """A level rod along ee-x through the TCP, its depth line's slices at ``along``."""
    slices = np.column_stack([np.arange(len(along)), along, np.full(len(along), y0)])
    return SideView(np.eye(4), 0.0, 0.3, 0.0, None, None, None, None, radius, 0.0, 1e-4,
                    1e-4, y0, 0.0, y_std, 1e-6, depth_slices=slices,
                    camera_ee=None if camera is None else camera.copy())  # fmt: skip


def test_shift_std_is_the_radius_and_depth_resolution_terms_in_quadrature():
    model = DepthLineErrorConfig(radius_share=0.03, axial_share=1.5)
    r, sigma_z = 0.025, 4e-4
    assert model.shift_std(r, sigma_z) == pytest.approx(
        np.sqrt((0.03 * r) ** 2 + (1.5 * 4e-4) ** 2)
    )
    assert model.shift_std(0.0, 0.0) == 0.0
    with pytest.raises(InvalidInputError):
        DepthLineErrorConfig(radius_share=-0.01)


def test_depth_line_std_follows_the_geometry():
    """Distance from the camera to the axis at the slices' middle; sigma_z = d^2 s / (f b)."""
    model = DepthLineErrorConfig(radius_share=0.027, axial_share=1.0)
    view = _view(radius=0.02, along=(0.02, 0.06, 0.10))  # median along 0.06 m
    d = np.linalg.norm(np.array([0.06, 0.0, 0.0]) - CAMERA_EE)
    assert handle_distance(view) == pytest.approx(d)
    sigma_z = d * d * 0.08 / (424.0 * 0.05)
    expected = np.hypot(0.027 * 0.02, sigma_z)
    assert depth_line_std(view, D435, model) == pytest.approx(expected)
    # grows with the radius and with the distance; no model, no term
    assert depth_line_std(replace(view, radius=0.03), D435, model) > expected
    far = _view(radius=0.02, along=(0.15, 0.19, 0.23))
    assert handle_distance(far) > d
    assert depth_line_std(far, D435, model) > expected
    assert depth_line_std(view, D435, None) == 0.0
    # a clean render (ideal: no emulated sensor) has the radius term alone
    assert depth_line_std(view, DepthNoiseConfig(), model) == pytest.approx(0.027 * 0.02)
    # no camera pose: no distance, the radius term alone
    assert depth_line_std(_view(camera=None), D435, model) == pytest.approx(0.027 * 0.02)


def test_presets_carry_the_model_and_the_run_records_it():
    ideal, real = sensor_preset("ideal"), sensor_preset("realistic")
    # one model for every preset: the camera's part is its own depth resolution
    assert ideal.side_depth_line == real.side_depth_line == DepthLineErrorConfig(0.003, 1.0)
    assert not ideal.side_depth.enabled  # the ideal render stays clean
    tree = asdict(EpisodeConfig(sensors=real))
    assert tree["sensors"]["side_depth_line"] == {"radius_share": 0.003, "axial_share": 1.0}


def test_position_z_scores_are_unit_with_the_modelled_depth_line_error():
    """A position linear in the depth line's change, its error drawn from the modelled
    spread: the std ``motion_stds`` states for it makes z ~ N(0, 1)."""
    model = DepthLineErrorConfig(radius_share=0.027, axial_share=1.0)
    first = _view(radius=0.025)
    line_std = depth_line_std(first, D435, model)
    lever = 3.0  # m of CoM position per m of shift

    def position(views, depth, slides):
        return lever * (views[1].surface_y - views[0].surface_y)

    rng = np.random.default_rng(3)
    z = []
    for error in rng.normal(0.0, line_std, 2000):
        second = replace(first, surface_y=first.surface_y + error)
        views = [first, second]
        x0 = position(views, [True], [0.0])
        parts = motion_stds(position, views, [True], (0.002, np.radians(2.0)), x0, line_std)
        total = np.sqrt(sum(v * v for v in parts.values()))
        z.append(x0 / total)  # the true change is 0
    z = np.array(z)
    assert np.sqrt(np.mean(z**2)) == pytest.approx(1.0, abs=0.06)
    assert np.mean(np.abs(z) <= 1.96) == pytest.approx(0.95, abs=0.02)
    # without the model the stated std is the slices' scatter alone: far too small
    parts = motion_stds(position, [first, replace(first, surface_y=first.surface_y + line_std)],
                        [True], (0.002, np.radians(2.0)), lever * line_std)  # fmt: skip
    assert parts["shift"] < 0.01 * lever * line_std


def test_filled_outline_is_left_out_of_the_depth_line():
    """A round handle seen against nothing: filling the holes grows its outline by a few
    pixels at the depth of its edge; those are not measured, and the depth line of the
    measured pixels lies where the visible half-cylinder's median does (r cos 30 deg in
    front of the axis), the filled outline's behind it."""
    r, px, y_axis = 0.01, 0.0005, 0.0  # radius, pixel (m), axis along the jaw axis (ee y)
    rows, cols = 80, 60
    u = (np.arange(rows) - rows / 2 + 0.5) * px  # across the rod
    depth = np.full((rows, cols), np.inf)
    inside = np.abs(u) < r
    depth[inside, :] = (0.3 + y_axis - np.sqrt(r * r - u[inside] ** 2))[:, None]
    depth[int(rows / 2), 7] = 0.0  # a lost pixel: the frame is cleaned
    cleaned, _, was_cleaned, measured = clean_side_depth(depth)
    assert was_cleaned
    grown = np.isfinite(cleaned) & ~np.isfinite(depth)
    assert grown.any() and not measured[grown].any()
    assert measured[inside, :].sum() == inside.sum() * cols - 1
    along = np.tile(np.arange(cols) * px, (rows, 1))
    y_ee = cleaned - 0.3
    keep = np.isfinite(cleaned)
    pts = np.column_stack([along[keep], y_ee[keep], np.zeros(keep.sum())])
    handle_all = np.ones(len(pts), bool)
    handle_measured = measured[keep]
    y_all = surface_line(pts, pts[:, 0], handle_all, r)[0]
    y_measured = surface_line(pts, pts[:, 0], handle_measured, r)[0]
    assert y_measured == pytest.approx(y_axis - r * np.cos(np.radians(30.0)), abs=0.03 * r)
    assert y_all > y_measured + 0.01 * r  # the filled outline pulls it behind


def test_paired_depth_line_cancels_the_handle_profile():
    """Two views of a handle whose end slice lies 3 mm further back (a rounded end): the
    second view, shifted 0.5 mm along the jaws, lost that end slice. Each view's own line
    moves by the profile; the paired slices' difference is the shift."""
    along = np.arange(-0.10, 0.06, 0.01) + 0.005
    profile = np.where(along > 0.05, 0.003, 0.0)  # the end slice, behind the rest
    a = np.column_stack([np.floor(along / 0.01), along, -0.017 + profile])
    b = a[:-1].copy()
    b[:, 2] += 0.0005
    first, second = _view(), _view()
    line = [np.polyfit(s[:, 1], s[:, 2], 1) for s in (a, b)]
    first = replace(first, depth_slices=a, surface_y=line[0][1], surface_slope=line[0][0])
    second = replace(second, depth_slices=b, surface_y=line[1][1], surface_slope=line[1][0])
    own = second.surface_y - first.surface_y
    assert abs(own - 0.0005) > 1e-4  # the profile moves each view's own line
    paired = paired_depth_line(first, second)
    assert paired.surface_y - first.surface_y == pytest.approx(0.0005, abs=1e-12)
    assert paired.surface_slope - first.surface_slope == pytest.approx(0.0, abs=1e-9)
    # too few common slices, or a view pointing the other way: left as it is
    few = replace(second, depth_slices=b[:3])
    assert paired_depth_line(first, few) is few
    flipped = second.T_ee_obj.copy()
    flipped[:3, :2] *= -1.0
    other_way = replace(second, T_ee_obj=flipped)
    assert paired_depth_line(first, other_way) is other_way
