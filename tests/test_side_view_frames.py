"""The side view under a real camera's errors: frames averaged in time, the flat bar, refusals.

Real MuJoCo renders (headless EGL) with the realistic preset's wrist-camera errors
(simulation/depth_noise.py); errors against the simulator's truth seen through the
calibration error (tests/_corruption.py). The temporal filter is checked against a per-pixel
formula written here.
"""

import numpy as np
import pytest
from _corruption import realistic
from hypothesis import given, settings
from hypothesis import strategies as st
from test_perception import _held_rod_scene, _side_view_errors

from comgrasp_pin.config import SensorConfig, sensor_preset
from comgrasp_pin.errors import (
    ComGraspError,
    InvalidDepthError,
    InvalidInputError,
    ObjectNotFoundError,
    UntrustedImageError,
)
from comgrasp_pin.perception import average_depth_frames, observe_held_rod
from comgrasp_pin.simulation.cameras import CameraRig
from comgrasp_pin.simulation.depth_noise import DepthNoise
from comgrasp_pin.simulation.eyes import (
    arm_capsules,
    handle_radius,
    look_from_side,
    side_camera_pose,
)
from comgrasp_pin.simulation.objects import OBJECTS
from comgrasp_pin.simulation.world import SIDE_CAMERA
from comgrasp_pin.workcell import TABLE_Z

FLAT_POSES = ((0.0, 0.03), (15.0, -0.03), (-20.0, -0.04), (35.0, 0.0), (50.0, 0.02), (-60.0, 0.0))
TILT_BOUND_DEG = 1.0  # the perception contract: about 1 deg ...
POSITION_BOUND = 3e-3  # ... and 3 mm (axis and grasp position)


def _per_pixel(frames, tolerance):
    """The filter's formula, one pixel at a time."""
    h, w = frames[0].shape
    out = np.empty((h, w))
    for i in range(h):
        for j in range(w):
            values = [f[i, j] for f in frames]
            valid = [v for v in values if np.isfinite(v) and v > 0]
            near = [v for v in valid if abs(v - np.median(valid)) <= tolerance] if valid else []
            if near:
                out[i, j] = np.mean(near)
            elif not valid and any(v == np.inf for v in values):
                out[i, j] = np.inf  # nothing seen
            else:
                out[i, j] = 0.0  # lost
    return out


_PIXEL = st.one_of(
    st.floats(0.2, 0.6), st.floats(0.2, 0.6), st.just(0.0), st.just(np.inf)
)  # fmt: skip


@settings(max_examples=60, deadline=None)
@given(
    st.integers(1, 6).flatmap(
        lambda n: st.lists(
            st.lists(st.lists(_PIXEL, min_size=3, max_size=3), min_size=2, max_size=2),
            min_size=n,
            max_size=n,
        )
    ),
    st.floats(1e-4, 0.05),
)
def test_the_average_of_frames_is_the_mean_of_the_valid_values_near_their_median(raw, tol):
    frames = [np.array(f, dtype=float) for f in raw]
    np.testing.assert_allclose(average_depth_frames(frames, tol), _per_pixel(frames, tol),
                               rtol=1e-12, atol=0.0)  # fmt: skip


def test_averaged_frames_fill_holes_drop_flyers_and_resolve_below_the_quantum():
    rng = np.random.default_rng(0)
    truth = 0.3004  # between two 1 mm steps
    frames = []
    for _ in range(16):
        f = np.round((truth + 4e-4 * rng.standard_normal((20, 20))) / 1e-3) * 1e-3
        f[rng.random((20, 20)) < 0.2] = 0.0  # holes
        f[rng.random((20, 20)) < 0.05] = 0.35  # flying pixels, 5 cm off
        frames.append(f)
    out = average_depth_frames(frames)
    assert np.all(out > 0) and np.all(np.isfinite(out))  # every hole filled
    assert abs(np.mean(out) - truth) < 5e-5  # dithered steps resolved; flyers left out
    assert np.std(out) < 2.5e-4  # 0.4 mm noise (plus steps) over ~12 frames


def test_one_frame_is_itself_and_lost_everywhere_stays_lost():
    f = np.array([[0.3, 0.0], [np.inf, 0.5]])
    np.testing.assert_array_equal(average_depth_frames([f]), f)
    lost = average_depth_frames([np.array([[0.0, np.inf]]), np.array([[0.0, 0.0]])])
    np.testing.assert_array_equal(lost, [[0.0, np.inf]])
    assert average_depth_frames([f, f, f], min_valid=4)[0, 0] == 0.0  # too few frames


@pytest.mark.parametrize(
    "frames, kwargs, error",
    [
        ([], {}, InvalidDepthError),
        ([np.zeros((2, 2)), np.zeros((3, 2))], {}, InvalidDepthError),
        ([np.zeros(4)], {}, InvalidDepthError),
        ([np.full((2, 2), np.nan)], {}, InvalidDepthError),
        ([np.ones((2, 2), dtype=np.uint16)], {}, InvalidDepthError),
        ([np.ones((2, 2), dtype=complex)], {}, InvalidInputError),
        (42, {}, InvalidDepthError),
        ([np.ones((2, 2))], {"tolerance": 0.0}, InvalidInputError),
        ([np.ones((2, 2))], {"tolerance": np.inf}, InvalidInputError),
        ([np.ones((2, 2))], {"min_valid": 0}, InvalidInputError),
    ],
)
def test_bad_frames_are_refused_naming_what_is_wrong(frames, kwargs, error):
    with pytest.raises(error) as info:
        average_depth_frames(frames, **kwargs)
    assert isinstance(info.value, ComGraspError) and str(info.value)


def test_side_frames_is_a_checked_knob():
    assert sensor_preset("realistic").side_frames >= 1
    for bad in (0, -1, 2.0, True):
        with pytest.raises(InvalidInputError, match="side_frames"):
            SensorConfig(side_frames=bad)
    with pytest.raises(InvalidInputError, match="side_frames_tolerance"):
        SensorConfig(side_frames_tolerance=0.0)


@pytest.fixture(scope="module")
def flat_bar(ur5):
    sim, rig, place = _held_rod_scene(ur5, "obj3")
    yield sim, rig, place
    rig.close()


def _inputs(ur5, sim, rig, name):
    T_world_ee, T_ee_cam = side_camera_pose(ur5, sim.q)
    rest = (T_world_ee, TABLE_Z, OBJECTS[name].length, arm_capsules(ur5, sim.q), None,
            handle_radius(sim.finger_q[0]))  # fmt: skip
    return T_ee_cam, rest


@pytest.mark.parametrize("seed", [None, 0, 1])
def test_a_flat_bar_is_measured_within_the_contract(ur5, flat_bar, seed):
    """obj3 (a 3 cm x 1 cm steel bar) held edge-on: no cylinder fits it, and a noisy image
    of it used to be refused; measured from its face it is within 1 deg and 3 mm of the
    truth in a clean render (seed None) and under the realistic preset's errors."""
    sim, rig, place = flat_bar
    errors = []
    for tilt, offset in FLAT_POSES:
        T_ee_obj = place(tilt, offset)
        depth = rig.depth(sim.data, SIDE_CAMERA)
        T_ee_cam, rest = _inputs(ur5, sim, rig, "obj3")
        T_cal = np.eye(4)
        if seed is not None:
            noise = realistic("side", seed)
            depth, T_cal = noise.apply(depth), noise.T_cam_calibrated
        view = observe_held_rod(None, depth, rig.intrinsics(SIDE_CAMERA), T_ee_cam @ T_cal,
                                *rest)  # fmt: skip
        T_seen = T_ee_cam @ T_cal @ np.linalg.inv(T_cal) @ np.linalg.inv(T_ee_cam) @ T_ee_obj
        tilt_err, axis_err, grasp_err = _side_view_errors(view, T_seen, offset)
        errors.append((tilt, np.degrees(tilt_err), axis_err, grasp_err))
    assert all(e[1] < TILT_BOUND_DEG for e in errors), errors
    assert all(e[2] < POSITION_BOUND and e[3] < POSITION_BOUND for e in errors), errors
    if seed is None:  # the clean render: the edge-on face gives the axis to 1.5 mm
        assert all(e[1] < 0.5 and e[2] < 1.5e-3 for e in errors), errors


@pytest.mark.parametrize(("kind", "amplitude"), [("ripple", 4e-3), ("ripple", 1.5e-2),
                                                  ("steps", 8e-3)])  # fmt: skip
def test_a_handle_no_model_fits_is_refused_or_measured_within_the_contract(ur5, kind, amplitude):
    """A round handle (obj2) whose noisy surface is rippled along the rod, or stepped in a
    checkerboard, by millimetres (what no cylinder and no flat face is) is never measured
    wrong: refused as untrusted, or within the contract (the cleaning and the fit's inliers
    see through it: measured, 2.1 mm and 0.16 deg off at the 15 mm ripple)."""
    sim, rig, place = _held_rod_scene(ur5, "obj2")
    try:
        T_ee_obj = place(15.0, 0.02)
        depth = rig.depth(sim.data, SIDE_CAMERA)
        T_ee_cam, rest = _inputs(ur5, sim, rig, "obj2")
        noise = realistic("side", 4)
        rows, cols = np.indices(depth.shape)
        pattern = (np.sin(2 * np.pi * cols / 12.0) if kind == "ripple"
                   else np.sign(np.sin(2 * np.pi * (rows + cols) / 16.0)))  # fmt: skip
        near = np.isfinite(depth) & (depth < 0.36)  # the held rod and the fingers
        corrupted = noise.apply(depth + np.where(near, amplitude * pattern, 0.0))
        T_cam = T_ee_cam @ noise.T_cam_calibrated
        try:
            view = observe_held_rod(None, corrupted, rig.intrinsics(SIDE_CAMERA), T_cam, *rest)
        except UntrustedImageError:
            return
        T_seen = T_cam @ np.linalg.inv(T_ee_cam) @ T_ee_obj
        tilt_err, axis_err, _ = _side_view_errors(view, T_seen, 0.02)
        assert np.degrees(tilt_err) < TILT_BOUND_DEG and axis_err < POSITION_BOUND
    finally:
        rig.close()


def test_empty_jaws_in_a_noisy_image_are_nothing_held_not_an_untrusted_image(ur5):
    """A rod seen hanging well below the jaws (its axis 6 cm from the TCP: not held) in a
    noisy image is ObjectNotFoundError (a dropped rod), as in a clean one, before the
    image's trust is judged."""
    sim, rig, place = _held_rod_scene(ur5, "obj1")
    try:
        place(0.0, 0.0)
        import mujoco

        body = sim.model.body("object").id
        sim.model.body_pos[body] = [0.0, 0.0, 0.06]  # 6 cm out along the approach axis
        mujoco.mj_forward(sim.model, sim.data)
        depth = rig.depth(sim.data, SIDE_CAMERA)
        T_ee_cam, rest = _inputs(ur5, sim, rig, "obj1")
        for seed in (None, 0, 1):
            d = depth if seed is None else realistic("side", seed).apply(depth)
            with pytest.raises(ObjectNotFoundError):
                observe_held_rod(None, d, rig.intrinsics(SIDE_CAMERA), T_ee_cam, *rest)
    finally:
        rig.close()


def test_the_simulated_frames_each_have_their_own_noise_and_the_episodes_calibration(ur5):
    """``look_from_side(frames=N)``: N renders of the still arm, each with its own noise
    draw, the calibration error the episode's, averaged by ``average_depth_frames``: the
    same view as that average of N renders of an identically seeded camera."""
    sim, rig, place = _held_rod_scene(ur5, "obj2")
    config = sensor_preset("realistic").side_depth
    try:
        place(10.0, 0.0)
        twin = CameraRig(rig.model, noise={SIDE_CAMERA: DepthNoise(config, 7)})
        rig.noise = {SIDE_CAMERA: DepthNoise(config, 7)}
        T_before = rig.calibration_error(SIDE_CAMERA)
        finger_q = float(sim.finger_q[0])
        view = look_from_side(rig, sim.data, ur5, sim.q, OBJECTS["obj2"].length, None,
                              finger_q, frames=4)  # fmt: skip
        np.testing.assert_array_equal(rig.calibration_error(SIDE_CAMERA), T_before)
        renders = [twin.depth(sim.data, SIDE_CAMERA) for _ in range(4)]
        assert not np.array_equal(renders[0], renders[1])  # each frame its own noise
        T_ee_cam, rest = _inputs(ur5, sim, rig, "obj2")
        rest = (*rest[:4], None, handle_radius(finger_q))
        expected = observe_held_rod(None, average_depth_frames(renders),
                                    rig.intrinsics(SIDE_CAMERA),
                                    T_ee_cam @ twin.calibration_error(SIDE_CAMERA),
                                    *rest)  # fmt: skip
        np.testing.assert_allclose(view.T_ee_obj, expected.T_ee_obj, rtol=0, atol=1e-12)
        twin.close()
    finally:
        rig.close()


def test_a_round_handle_its_noise_misfits_is_measured_within_its_interval():
    """The torch (obj4, a 4 cm body), realistic accuracy trial 14 of seed 0: its handle's
    points misfit the cylinder by 1.2 times the depth's noise in every side view (the fit
    within 0.2 deg of the truth), which ``rod_axis.MISFIT_NOISE`` (1.5) allows: measured,
    the CoM within its interval of the simulator's truth."""
    from comgrasp_pin.experiments.trials import accuracy_trial, trial_seed

    row = accuracy_trial({"object": "obj4", "trial": 14, "method": "trial",
                          "seed": trial_seed(0, "obj4", 14), "sensors": "realistic"})  # fmt: skip
    assert not row.get("error"), row.get("error")
    z = (row["pos_esti_m"] - row["pos_real_m"]) / row["pos_std_m"]
    assert abs(z) < 3.0 and row["accuracy"] > 0.9, (z, row["accuracy"])
