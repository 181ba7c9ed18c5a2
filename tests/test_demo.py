"""The demo a person watches: CoM marks where the cameras see the points, one key frame per
phase, a printout in one tilt convention, the Rerun recording and its missing extra."""

import re
import sys

import cv2
import numpy as np
import pytest

from comgrasp_pin.cli import main
from comgrasp_pin.geometry import tilt_difference_deg, tilt_from_level_deg
from comgrasp_pin.perception.draw import ESTIMATE, TRUTH
from comgrasp_pin.procedures import phases as ph
from comgrasp_pin.simulation import Simulation
from comgrasp_pin.simulation.key_frames import key_frames
from comgrasp_pin.simulation.objects import ObjectState
from comgrasp_pin.simulation.recorder import SCENE_CAMERA, ComOnRod, EpisodeRecorder

Q_DOWN = np.array([0.0, -1.9, 1.9, -1.57, -1.57, 0.0])


def _mujoco_pixel(sim: Simulation, camera: str, width: int, height: int, p_world) -> np.ndarray:
    """(u, v) of a world point from MuJoCo's own camera data (x right, y up, looking along
    -z; vertical field of view fovy), without the package's optical-frame conversion."""
    cam = sim.model.camera(camera)
    R = sim.data.cam_xmat[cam.id].reshape(3, 3)
    p = R.T @ (np.asarray(p_world) - sim.data.cam_xpos[cam.id])
    f = 0.5 * height / np.tan(np.radians(cam.fovy[0]) / 2)
    return np.array([(width - 1) / 2 + f * p[0] / -p[2], (height - 1) / 2 - f * p[1] / -p[2]])


def _centroid(mask: np.ndarray) -> np.ndarray:
    v, u = np.nonzero(mask)
    return np.array([u.mean(), v.mean()])


def _colour(img: np.ndarray, bgr, tol: int = 40) -> np.ndarray:
    return np.all(np.abs(img.astype(int) - np.array(bgr)) < tol, axis=-1)


def test_tilt_is_one_convention_from_level():
    # The same axis read as 0.11 deg and as 179.99 deg, or as -67 and 113 deg: one tilt.
    assert tilt_from_level_deg(np.radians(179.99)) == pytest.approx(0.01, abs=1e-9)
    assert tilt_from_level_deg(np.radians(-67.0)) == pytest.approx(67.0)
    assert tilt_from_level_deg(np.radians(113.0)) == pytest.approx(67.0)
    assert tilt_from_level_deg(np.radians(90.0)) == pytest.approx(90.0)
    assert tilt_difference_deg(np.radians(0.11), np.radians(179.99)) == pytest.approx(0.12)
    assert tilt_difference_deg(np.radians(-67.0), np.radians(113.0)) == pytest.approx(0.0)
    angles = np.radians(np.linspace(-400, 400, 81))
    assert all(0.0 <= tilt_from_level_deg(a) <= 90.0 for a in angles)


def test_the_overlay_marks_the_points_where_the_camera_sees_them():
    sim = Simulation()
    sim.reset_arm(Q_DOWN, finger_q=0.02)
    # A "rod" frame on the table, turned about z; the truth and the estimate 20 cm apart
    # along its axis, the estimate's sigma 2 cm.
    c, s = np.cos(0.6), np.sin(0.6)
    T_world_obj = np.array([[c, -s, 0, 0.55], [s, c, 0, 0.05], [0, 0, 1, 0.02], [0, 0, 0, 1.0]])
    p_true = (T_world_obj @ [-0.1, 0, 0, 1])[:3]
    truth = ObjectState(T_world_obj, p_true, np.array([-0.1, 0, 0]), 0.5)
    recorder = EpisodeRecorder(sim, lambda: truth)
    try:
        recorder(sim)
        estimate = ComOnRod(np.array([0.1, 0.0, 0.0]), 0.02, 0.0, T_world_obj)
        recorder.finish(estimate, [(0.0, f"{ph.TRIAL_GRASP}: test")])
        img = recorder.overlay(0, captions=False)
    finally:
        recorder.close()
    h, w = img.shape[:2]
    inset_x = recorder.inset_origin(0)[0]
    main = np.zeros((h, w), bool)
    main[:, : inset_x - 2] = True  # the main view, left of the insets
    expected = [
        _mujoco_pixel(sim, SCENE_CAMERA, w, h, (T_world_obj @ [x, 0, 0, 1])[:3])
        for x in (0.1, 0.06, 0.14, -0.1)
    ]  # estimate, its -2 and +2 sigma, truth
    ring = _colour(img, TRUTH) & main
    np.testing.assert_allclose(_centroid(ring), expected[3], atol=1.0)
    orange = _colour(img, ESTIMATE) & main
    u, v = np.nonzero(orange.T)
    pts = np.c_[u, v]
    near = np.linalg.norm(pts - expected[0], axis=1) < 8  # the dot (the bar crosses it)
    np.testing.assert_allclose(pts[near].mean(axis=0), expected[0], atol=1.0)
    # The bar spans +-2 sigma: its orange pixels reach both ends, and no further.
    for end in expected[1:3]:
        assert np.min(np.linalg.norm(pts - end, axis=1)) < 2.0
    span = np.linalg.norm(expected[2] - expected[1])
    assert np.max(np.linalg.norm(pts - expected[0], axis=1)) < span / 2 + 9  # + end ticks


def test_one_key_frame_per_phase_inside_it():
    times = np.arange(100) * 0.1  # 10 frames a second
    phases = [(0.0, f"{ph.EMPTY_ARM}: x"), (2.01, f"{ph.TRIAL_GRASP}: between two frames"),
              (2.05, f"{ph.CAREFUL_LIFT}: y"), (5.0, f"{ph.MEASURING} 1: z"),
              (8.0, f"{ph.DROP}: w")]  # fmt: skip
    picks = key_frames(times, phases, end=10.0)
    assert [k for _, k, _, _ in picks] == [1, 3, 4, 5]  # the 40 ms phase has no frame
    bounds = {1: (0.0, 2.01), 3: (2.05, 5.0), 4: (5.0, 8.0), 5: (8.0, 10.0)}
    for i, k, t, _ in picks:
        assert times[i] == t and bounds[k][0] <= t < bounds[k][1]
    at = {k: t for _, k, t, _ in picks}
    assert at[1] == pytest.approx(1.2)  # 60 % into the empty arm's torques
    assert at[3] == pytest.approx(3.2)  # 40 % into the careful lift: lifting
    assert at[4] == pytest.approx(6.5)  # the middle of a measurement
    assert at[5] == pytest.approx(8.2)  # just after the drop: the rod let go


def test_the_strip_has_two_rows_of_legible_tiles(tmp_path):
    sim = Simulation()
    sim.reset_arm(Q_DOWN, finger_q=0.02)
    truth = ObjectState(np.eye(4), np.array([0.55, 0.0, 0.02]), np.zeros(3), 0.5)
    recorder = EpisodeRecorder(sim, lambda: truth, fps=10.0)
    sim.observers.append(recorder)
    announced = []
    try:
        for k, name in enumerate((ph.EMPTY_ARM, ph.TRIAL_GRASP, ph.CAREFUL_LIFT)):
            announced.append((sim.time, f"{name}: step {k}"))
            recorder.caption = announced[-1][1]
            sim.hold(0.3)
        recorder.finish(None, announced)
        path = recorder.write_strip(tmp_path / "strip.png", title="test")
        video = recorder.write_video(tmp_path / "v.mp4")
    finally:
        recorder.close()
    strip = cv2.imread(str(path))
    assert strip.shape[1] == 2 * 400  # 3 tiles: 2 columns, 2 rows, 400 px each
    assert strip.shape[0] > 2 * 300
    frames = cv2.VideoCapture(str(video))
    n = int(frames.get(cv2.CAP_PROP_FRAME_COUNT))
    frames.release()
    assert n == len(recorder.frames) >= 9


def test_rerun_without_the_package_says_how_to_install_it(tmp_path, capsys, monkeypatch):
    monkeypatch.setitem(sys.modules, "rerun", None)  # as if rerun-sdk were not installed
    code = main(["demo", "--out", str(tmp_path), "--rerun", str(tmp_path / "a.rrd")])
    err = capsys.readouterr().err
    assert code == 2 and "pip install" in err and "rerun" in err and "Traceback" not in err
    assert not any(tmp_path.iterdir())  # refused before the episode ran


def test_rerun_needs_an_rrd_file(tmp_path, capsys):
    with pytest.raises(SystemExit) as exit_:
        main(["demo", "--out", str(tmp_path), "--rerun", str(tmp_path / "a.txt")])
    assert exit_.value.code == 2 and "must name a .rrd file" in capsys.readouterr().err


def test_the_point_cloud_of_the_top_camera_lies_on_the_table():
    from comgrasp_pin.simulation.cameras import CameraRig
    from comgrasp_pin.simulation.rerun_log import cloud_world
    from comgrasp_pin.workcell import PICK_AREA, TABLE_Z

    sim = Simulation()
    sim.reset_arm(Q_DOWN, finger_q=0.02)
    rig = CameraRig(sim.model, 320, 240)
    try:
        depth, rgb = rig.depth(sim.data, "top_down"), rig.rgb(sim.data, "top_down")
        T = rig.T_world_cam(sim.data, "top_down")
        p_world, colours = cloud_world(rig.intrinsics("top_down"), T, depth, rgb, stride=2)
    finally:
        rig.close()
    assert p_world.shape == colours.shape and len(p_world) > 0.9 * 160 * 120
    x0, x1, y0, y1 = PICK_AREA
    inner = (p_world[:, 0] > x0 + 0.03) & (p_world[:, 0] < x1 - 0.03)
    inner &= (p_world[:, 1] > y0 + 0.03) & (p_world[:, 1] < y1 - 0.03)
    assert inner.sum() > 1000
    z = p_world[inner, 2]
    assert np.mean(np.abs(z - TABLE_Z) < 2e-3) > 0.85  # the table top (the rest: the arm)
    assert z.min() > TABLE_Z - 2e-3  # from above, nothing below the table top is seen


class _Recorded:
    """A stand-in for one of rerun's archetypes: keeps what it was made with."""

    def __init__(self, *args, **kwargs):
        self.args, self.kwargs = args, kwargs

    def compress(self, **kwargs):
        self.compressed = kwargs
        return self


class _RecordingStream:
    """A stand-in for ``rerun.RecordingStream``: every call kept, in order."""

    def __init__(self, name):
        self.name, self.calls, self.time = name, [], None

    def save(self, path):
        self.calls.append(("save", path))

    def set_time(self, timeline, duration):
        self.time = (timeline, duration)

    def log(self, entity, archetype, static=False):
        self.calls.append(("log", entity, archetype, None if static else self.time))

    def flush(self):
        self.calls.append(("flush",))

    def disconnect(self):
        self.calls.append(("disconnect",))


def _fake_rerun():
    """A ``rerun`` module whose archetypes record their arguments (rerun-sdk is not installed
    by the test extra: see the test below)."""
    import types

    module = types.ModuleType("rerun")
    module.RecordingStream = _RecordingStream
    module.ViewCoordinates = types.SimpleNamespace(RIGHT_HAND_Z_UP="RIGHT_HAND_Z_UP")
    for name in ("SeriesLines", "Scalars", "Transform3D", "Pinhole", "Image", "DepthImage",
                 "Points3D", "TextLog", "LineStrips3D"):  # fmt: skip
        setattr(module, name, type(name, (_Recorded,), {}))
    return module


def test_a_rerun_recording_has_the_cameras_clouds_com_and_torques(tmp_path, monkeypatch):
    """What RerunLog logs, and when: against a stand-in ``rerun`` module that records each
    call (``_fake_rerun``).

    The real rerun-sdk is not in the ``test`` extra, so CI (``pip install ".[test,ray,franka]"``)
    would skip a test that needs it, as it always did: its wheel is 170 MB (rerun-sdk 0.41,
    manylinux x86_64), too much for every CI run. This test runs everywhere instead: the
    entities, timeline, torques (the sensor's own samples), clouds (``cloud_world`` of each
    camera's depth) and the estimate's points are checked call by call. The SDK's own
    encoding of them into a .rrd file is not tested here (``pip install '.[rerun]'`` and
    ``comgrasp demo --rerun FILE.rrd`` for that).
    """
    from comgrasp_pin.simulation.rerun_log import RerunLog
    from comgrasp_pin.simulation.world import ARM_JOINTS

    monkeypatch.setitem(sys.modules, "rerun", _fake_rerun())
    sim = Simulation()
    sim.reset_arm(Q_DOWN, finger_q=0.02)
    truth = ObjectState(np.eye(4), np.array([0.55, 0.0, 0.02]), np.zeros(3), 0.5)
    seen = {}  # the sensor's samples at each time, read beside the recording
    sim.observers.append(lambda s: seen.__setitem__(s.time, s.tau_measured.copy()))
    path = tmp_path / "ep.rrd"
    log = RerunLog(sim, path, lambda: truth)
    sim.observers.append(log)
    estimate = ComOnRod(np.array([0.01, 0.0, 0.0]), 0.005, 0.2, np.eye(4))
    try:
        sim.hold(0.6)
        log.finish(estimate, [(0.0, "trial grasp: x")], None)
    finally:
        log.close()
    calls = log.rec.calls
    assert calls[0] == ("save", str(path)) and calls[-2:] == [("flush",), ("disconnect",)]
    logs = [c[1:] for c in calls if c[0] == "log"]
    static = {entity: type(a).__name__ for entity, a, time in logs if time is None}
    assert static == {"world": "str", **{f"joint_torques/{j}": "SeriesLines" for j in ARM_JOINTS}}
    # the torques: every 1/50 s, each joint its sensor's sample at that time
    elbow = ARM_JOINTS.index("elbow_joint")
    torques = [(tt[1], a.args[0]) for e, a, tt in logs if e == "joint_torques/elbow_joint" and tt]
    assert len(torques) == pytest.approx(0.6 * 50, abs=1)
    assert all(value == pytest.approx(seen[t][elbow]) for t, value in torques)
    # the cameras: 4 frames a second, each its pose, intrinsics, images and cloud
    frames = sorted({tt[1] for e, a, tt in logs if e == "world/cameras/top_down/rgb"})
    np.testing.assert_allclose(frames, [0.0, 0.25, 0.5], atol=0.003)  # from the first step
    for camera in ("top_down", "side_camera"):
        kinds = [type(a).__name__ for e, a, tt in logs if e.startswith(f"world/cameras/{camera}")]
        assert kinds == ["Transform3D", "Pinhole", "Image", "DepthImage"] * 3, kinds
        clouds = [a for e, a, tt in logs if e == f"world/points/{camera}"]
        assert len(clouds) == 3 and all(len(c.args[0]) > 1000 for c in clouds)
        assert all(c.args[0].shape == c.kwargs["colors"].shape for c in clouds)
    top_cloud = next(a.args[0] for e, a, tt in logs if e == "world/points/top_down")
    assert np.median(top_cloud[:, 2]) < 0.1  # the table top, seen from above
    truths = [a.args[0] for e, a, tt in logs if e == "world/com/truth"]
    assert len(truths) == 3 and all(np.array_equal(p, truth.p_world_com) for p in truths)
    # after the episode: the phases on the timeline, the estimate from 0.2 s on (two frames)
    assert [(a.args[0], tt[1]) for e, a, tt in logs if e == "phases"] == [("trial grasp: x", 0.0)]
    estimates = [(a.args[0], tt[1]) for e, a, tt in logs if e == "world/com/estimate"]
    assert [t for _, t in estimates] == frames[1:]
    assert all(np.allclose(p, [0.01, 0.0, 0.0]) for p, _ in estimates)  # the rod stays put
    intervals = [a.args[0][0] for e, a, tt in logs if e == "world/com/interval"]
    assert all(np.allclose(s, [[0.0, 0.0, 0.0], [0.02, 0.0, 0.0]]) for s in intervals)


@pytest.mark.slow
def test_the_readme_demo_shows_every_phase_and_says_what_happened():
    from comgrasp_pin.cli.demo import TILT, summary
    from comgrasp_pin.experiments.trials import episode_config
    from comgrasp_pin.simulation.episode import run_episode

    # The README's demo: obj1, seed 1001 (docs/results/regrasp.csv: obj1, trial 1).
    result = run_episode("obj1", 1001, "regrasp", config=episode_config())
    kinds = [ph.phase_of(c) for _, c in result.phases]
    assert kinds == [ph.EMPTY_ARM, ph.TRIAL_GRASP, ph.CAREFUL_LIFT, ph.MEASURING, ph.MEASURING,
                     ph.PUT_DOWN, ph.REGRASP, ph.CARRY, ph.DROP]  # fmt: skip
    times = [t for t, _ in result.phases]
    assert times == sorted(times) and times[-1] < result.sim_s
    lines = summary(result)
    text = "\n".join(lines)
    assert re.search(r"trial grasps +1 \(no retry\)", text)
    assert re.search(r"put-down and regrasp +yes: CoM 43 mm from the jaws", text)
    tilt = next(line for line in lines if TILT in line)
    numbers = re.findall(r"[-\d.]+", tilt.split(TILT)[1])  # estimate, truth, difference
    est, true, diff = (float(x) for x in numbers)
    assert (
        0.0 <= est <= 90.0
        and 0.0 <= true <= 90.0
        and diff == pytest.approx(abs(est - true), abs=0.011)
    ), tilt
    assert result.success and "delivered to the drop box" in lines[0]


@pytest.mark.slow
def test_the_side_view_marks_the_true_com_where_the_wrist_camera_sees_it():
    from comgrasp_pin.config import EpisodeConfig
    from comgrasp_pin.simulation.episode import measure_and_score
    from comgrasp_pin.simulation.scene import Scene, World
    from comgrasp_pin.simulation.views import com_marks_px
    from comgrasp_pin.simulation.world import SIDE_CAMERA

    world = World(Scene.sample("obj1", 1001), EpisodeConfig(), 1001)
    try:
        trial, score = measure_and_score(world)
        data, rig = world.sim.data, world.rig
        truth = world.truth()
        est_px, bar_px, truth_px = com_marks_px(rig, data, SIDE_CAMERA, trial,
                                                world.robot.ee_pose(world.sim.q),
                                                truth.p_world_com)  # fmt: skip
        expected = _mujoco_pixel(world.sim, SIDE_CAMERA, rig.width, rig.height,
                                 truth.p_world_com)  # fmt: skip
        # The estimate, seen along the rod: where the true rod frame puts pos_esti.
        p_est = (truth.T_world_obj @ [score.pos_esti, 0, 0, 1])[:3]
        expected_est = _mujoco_pixel(world.sim, SIDE_CAMERA, rig.width, rig.height, p_est)
    finally:
        world.close()
    np.testing.assert_allclose(truth_px, expected, atol=1e-6)
    # The robot's belief (its side view and kinematics) against the truth's frame: within
    # the side view's millimetre, a few pixels at 0.3 m.
    np.testing.assert_allclose(est_px, expected_est, atol=4.0)
    assert np.all(np.isfinite(bar_px))
