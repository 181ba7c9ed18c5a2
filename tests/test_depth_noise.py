"""The realistic depth errors against their analytic model, on a real render of the table."""

from dataclasses import replace

import numpy as np
import pytest

from comgrasp_pin.config import DepthNoiseConfig, sensor_preset
from comgrasp_pin.simulation import Simulation
from comgrasp_pin.simulation.cameras import CameraRig
from comgrasp_pin.simulation.depth_noise import DepthNoise
from comgrasp_pin.simulation.scene import depth_noises
from comgrasp_pin.simulation.world import TOP_CAMERA
from comgrasp_pin.workcell import Q_PARK


@pytest.fixture(scope="module")
def table_depth():
    sim = Simulation()
    sim.reset_arm(Q_PARK)
    rig = CameraRig(sim.model)
    depth = rig.depth(sim.data, TOP_CAMERA)
    rig.close()
    return depth


def test_axial_noise_grows_with_the_square_of_depth(table_depth):
    top = sensor_preset("realistic").top_depth
    only_noise = DepthNoiseConfig(focal_px=top.focal_px, baseline=top.baseline,
                                  subpixel=top.subpixel, noise_corr_px=1.0)  # fmt: skip
    error = DepthNoise(only_noise, seed=1).apply(table_depth) - table_depth
    centre = table_depth[200:280, 280:360]  # the table, 1.25 m below
    d = float(np.median(centre))
    expected = d * d * 0.08 / (1005.0 * 0.055)  # Intel's d^2 s / (f b): 2.3 mm at 1.25 m
    assert error[200:280, 280:360].std() == pytest.approx(expected, rel=0.1)
    assert abs(error[200:280, 280:360].mean()) < 0.1 * expected


def test_holes_flying_pixels_dropouts_and_steps(table_depth):
    config = replace(sensor_preset("realistic").top_depth, focal_px=0.0, scale_std=0.0)
    out = DepthNoise(config, seed=2).apply(table_depth)
    lost = (out == 0) | ~np.isfinite(out)
    flat = np.zeros_like(lost)
    flat[150:330, 200:440] = True  # inside the table top: no depth edge
    assert lost[flat].mean() == pytest.approx(0.01, abs=0.003)
    valid = ~lost & np.isfinite(table_depth)
    steps = out[valid] / 0.001
    np.testing.assert_allclose(steps, np.round(steps), atol=1e-6)
    # Depth edges (a step of more than 1 cm within 3 x 3 pixels: the table's border, the
    # robot): half their pixels lost, 30 % of all of them flying between the two sides.
    padded = np.pad(np.where(np.isfinite(table_depth), table_depth, 100.0), 1, mode="edge")
    h, w = table_depth.shape
    window = np.stack([padded[1 + dy : 1 + dy + h, 1 + dx : 1 + dx + w]
                       for dy in (-1, 0, 1) for dx in (-1, 0, 1)])  # fmt: skip
    near, far = window.min(axis=0), window.max(axis=0)
    edge = far - near > 0.01
    assert edge.sum() > 1000
    assert lost[edge].mean() == pytest.approx(0.5, abs=0.03)
    between = ~lost & edge & (np.abs(out - table_depth) > 0.002)
    assert between.sum() / edge.sum() == pytest.approx(0.3, abs=0.1)
    assert np.all((out[between] >= near[between] - 1e-3) & (out[between] <= far[between] + 1e-3))


def test_calibration_error_is_one_millimetre_and_a_fifth_of_a_degree():
    noise = DepthNoise(sensor_preset("realistic").top_depth, seed=3)
    T = noise.T_cam_calibrated
    assert np.linalg.norm(T[:3, 3]) == pytest.approx(0.001)
    angle = np.degrees(np.arccos((np.trace(T[:3, :3]) - 1) / 2))
    assert angle == pytest.approx(0.2, rel=1e-6)
    other = DepthNoise(sensor_preset("realistic").top_depth, seed=4).T_cam_calibrated
    assert not np.allclose(T, other)  # drawn per episode


def test_ideal_preset_renders_as_they_are():
    assert depth_noises(sensor_preset("ideal"), 0) == {}
    assert set(depth_noises(sensor_preset("realistic"), 0)) == {"top_down", "side_camera"}
    assert not sensor_preset("ideal").top_depth.enabled
