"""Frames as cameras deliver them (issue 27, item 1): integer depth with depth_scale, K or a
RealSense's or ROS's intrinsics with their lens model, RGB or BGR, and RGBD files read back
through ``read_rgbd`` and ``comgrasp views --rgb --depth --camera-info``.

Real renders of the project's top camera, saved as a camera would save them (uint16 PNG
depth, colour PNG / JPEG, camera info JSON / YAML); the references are the float-metre
path and the simulator's truth (3 mm, 1 deg). The lens distortion is applied with OpenCV's
``undistortPoints`` (the inverse map), an independent computation of the one perception
undoes (``initUndistortRectifyMap``).
"""

from __future__ import annotations

import json
from pathlib import Path

import cv2
import numpy as np
import pytest
import yaml
from _corruption import corruptions, table_scene, top_errors, top_inputs

from comgrasp_pin.cli import main
from comgrasp_pin.errors import CameraFileError, InvalidDepthError, InvalidInputError
from comgrasp_pin.perception import average_depth_frames, detect_rod_top_down
from comgrasp_pin.perception.frames.camera_model import camera_model
from comgrasp_pin.perception.frames.rgbd_files import read_camera_info, read_rgbd
from comgrasp_pin.simulation.objects import OBJECTS

ROD = ("obj2", 0.68, -0.2, 0.6)  # off the image's centre, where a lens distorts
CENTRE_BOUND, YAW_BOUND_DEG = 3e-3, 1.0  # the perception contract
PLUMB_BOB = np.array([-0.25, 0.08, 0.001, -0.001, 0.0])  # a wide lens's barrel
FLASHLIGHT = (Path(__file__).resolve().parents[2] / "shared" / "realdata" / "rgbd"
              / "overhead_primesense_flashlight")  # fmt: skip


@pytest.fixture(scope="module")
def scene():
    """(depth (m), PinholeCamera, T_world_cam, rgb, truth (x, y, yaw), float-path detection)."""
    sim, rig, truths = table_scene([ROD])
    depth, camera, T, rgb = top_inputs(sim, rig)
    rig.close()
    return depth, camera, T, rgb, truths[0], detect_rod_top_down(rgb, depth, camera, T)


def _errors(det, truth, T):
    return top_errors(det, truth, T, np.eye(4))


def _calibration_yaml(camera, D=(), model="plumb_bob") -> dict:
    """ROS camera_calibration's layout."""
    return {"image_width": camera.width, "image_height": camera.height,
            "camera_name": "top", "distortion_model": model,
            "camera_matrix": {"rows": 3, "cols": 3, "data": camera.K.ravel().tolist()},
            "distortion_coefficients": {"rows": 1, "cols": len(D), "data": list(D)}}  # fmt: skip


def _save(tmp_path, depth_units, rgb, info: dict, suffix=".yaml", colour=".png"):
    """Files as a camera's user saves them; the colour with OpenCV (a BGR array)."""
    paths = tmp_path / f"rgb{colour}", tmp_path / "depth.png", tmp_path / f"info{suffix}"
    if rgb is not None:
        cv2.imwrite(str(paths[0]), np.ascontiguousarray(rgb[..., ::-1]))
    assert cv2.imwrite(str(paths[1]), depth_units)
    text = yaml.safe_dump(info) if suffix == ".yaml" else json.dumps(info)
    paths[2].write_text(text)
    return paths


def test_millimetres_from_files_measure_as_float_metres(scene, tmp_path):
    depth, camera, T, rgb, truth, float_det = scene
    mm = np.round(depth * 1e3).astype(np.uint16)
    files = read_rgbd(*_save(tmp_path, mm, rgb, _calibration_yaml(camera)), depth_scale=1e-3)
    assert files.depth.dtype == np.uint16 and (files.rgb == rgb).all()  # RGB back
    det = detect_rod_top_down(files.rgb, files.depth, files.camera, T,
                              depth_scale=files.depth_scale)  # fmt: skip
    shift = np.hypot(det.grasp.x - float_det.grasp.x, det.grasp.y - float_det.grasp.y)
    assert shift < 2e-4 and abs(det.length - float_det.length) < 5e-4
    centre, yaw_deg = _errors(det, truth, T)
    assert centre < CENTRE_BOUND and yaw_deg < YAW_BOUND_DEG
    assert abs(det.length - OBJECTS["obj2"].length) < 3e-3


def test_a_d405s_tenth_millimetres_with_realsense_intrinsics(scene, tmp_path):
    depth, camera, T, rgb, truth, float_det = scene
    units = np.round(depth * 1e4).astype(np.uint16)  # 0.1 mm: 6.5 m at most
    info = {"fx": camera.fx, "fy": camera.fy, "ppx": camera.cx, "ppy": camera.cy,
            "width": camera.width, "height": camera.height, "model": "distortion.brown_conrady",
            "coeffs": [0, 0, 0, 0, 0], "depth_scale": 1e-4}  # fmt: skip
    files = read_rgbd(*_save(tmp_path, units, rgb, info, suffix=".json", colour=".jpg"))
    assert files.depth_scale == 1e-4
    det = detect_rod_top_down(files.rgb, files.depth, files.camera, T, depth_scale=1e-4)
    assert np.hypot(det.grasp.x - float_det.grasp.x, det.grasp.y - float_det.grasp.y) < 2e-4
    # Read as millimetres (the scale guessed), the table is ten times farther: not measured.
    with pytest.raises(CameraFileError, match="says 0.0001"):
        read_rgbd(*_save(tmp_path, units, rgb, info, suffix=".json"), depth_scale=1e-3)


def test_an_integer_image_without_depth_scale_is_refused_never_guessed(scene, tmp_path):
    depth, camera, T, rgb, *_ = scene
    mm = np.round(depth * 1e3).astype(np.uint16)
    with pytest.raises(InvalidDepthError, match="pass depth_scale"):
        detect_rod_top_down(rgb, mm, camera.K, T)
    with pytest.raises(CameraFileError, match="no depth_scale: pass it"):
        read_rgbd(*_save(tmp_path, mm, rgb, _calibration_yaml(camera)))
    frames = average_depth_frames([mm, mm], depth_scale=1e-3)
    np.testing.assert_array_equal(frames, mm * 1e-3)
    with pytest.raises(InvalidDepthError, match="depth_scale"):
        average_depth_frames([mm, mm])


def _distorted(image: np.ndarray, camera, D, nearest: bool) -> np.ndarray:
    """What a lens with plumb_bob ``D`` shows: each distorted pixel sees the ray that
    ``cv2.undistortPoints`` gives it."""
    v, u = np.mgrid[0 : camera.height, 0 : camera.width].astype(np.float32)
    pixels = np.stack([u.ravel(), v.ravel()], axis=-1)[:, None]
    src = cv2.undistortPoints(pixels, camera.K, D, P=camera.K).reshape(*u.shape, 2)
    flags = cv2.INTER_NEAREST if nearest else cv2.INTER_LINEAR
    return cv2.remap(image, src[..., 0], src[..., 1], flags, borderMode=cv2.BORDER_CONSTANT)


def test_a_distorted_image_is_undistorted_by_the_camera_infos_model(scene):
    depth, camera, T, rgb, truth, _ = scene
    depth_d = _distorted(depth, camera, PLUMB_BOB, nearest=True)
    rgb_d = _distorted(rgb, camera, PLUMB_BOB, nearest=False)
    info = {
        "width": camera.width,
        "height": camera.height,
        "k": camera.K.ravel().tolist(),
        "d": PLUMB_BOB.tolist(),
        "distortion_model": "plumb_bob",
    }  # a CameraInfo's fields
    with_d = _errors(detect_rod_top_down(rgb_d, depth_d, info, T), truth, T)
    without_d = _errors(detect_rod_top_down(rgb_d, depth_d, camera, T), truth, T)
    assert with_d[0] < CENTRE_BOUND and with_d[1] < YAW_BOUND_DEG, with_d
    assert without_d[0] > 2 * with_d[0] and without_d[0] > CENTRE_BOUND, (with_d, without_d)


def test_intrinsics_in_every_layout_are_the_same_camera(scene):
    camera = scene[1]
    fields = {"width": 640, "height": 480, "K": camera.K.ravel().tolist(), "D": [],
              "distortion_model": ""}  # ROS 1's names  # fmt: skip
    realsense = {"fx": camera.fx, "fy": camera.fy, "ppx": camera.cx, "ppy": camera.cy,
                 "width": 640, "height": 480}  # fmt: skip
    for layout in (fields, realsense, _calibration_yaml(camera), camera.K, camera):
        model = camera_model(layout, (480, 640))
        assert model.pinhole == camera and not model.distorted
    with pytest.raises(InvalidInputError, match="camera intrinsics not understood"):
        camera_model({"fx": 600.0, "width": 640})
    with pytest.raises(InvalidInputError, match="takes 4 coefficients"):
        camera_model({**fields, "D": [0.1, 0, 0, 0, 0], "distortion_model": "equidistant"})
    with pytest.raises(InvalidInputError, match="not one OpenCV undistorts"):
        camera_model({**fields, "D": [0.1, 0, 0, 0, 0], "distortion_model": "ftheta"})


def test_colour_order_bgr_reads_the_rgb_colour_and_gives_its_detection(tmp_path):
    """What ``--bgr`` (``color_order="bgr"``) is for: a colour file holding BGR in its RGB
    channels (a BGR array saved by PIL), read with it, is the RGB file's colour pixel for
    pixel, and a 1 cm rod in a D415's noise is measured from it as from the RGB colour, to
    the bit, from the files and from arrays. (A mix-up is not asked to change the mask: the
    top view uses the colour only where the depth alone fails, and the depth measures this
    rod.)"""
    x, y, yaw = 0.52, 0.08, -0.4
    sim, rig, truths = table_scene([("obj3", x, y, yaw)])
    depth, camera, T, rgb = top_inputs(sim, rig)
    rig.close()
    corrupt, T_cal = corruptions("top", 7)["realistic"]
    noisy = corrupt(depth)
    units = np.round(np.where(np.isfinite(noisy), noisy, 0) * 1e4).astype(np.uint16)  # 0.1 mm
    info = {**_calibration_yaml(camera), "depth_scale": 1e-4}
    rgb_file, depth_file, info_file = _save(tmp_path, units, rgb, info)
    bgr_file = tmp_path / "bgr_in_rgb.png"
    cv2.imwrite(str(bgr_file), rgb)  # OpenCV writes the array's channels reversed: BGR in RGB
    right = read_rgbd(rgb_file, depth_file, info_file)
    said = read_rgbd(bgr_file, depth_file, info_file, color_order="bgr")
    np.testing.assert_array_equal(said.rgb, right.rgb)
    np.testing.assert_array_equal(right.rgb, rgb)
    mixed = read_rgbd(bgr_file, depth_file, info_file)  # BGR taken for RGB: other colours
    assert (mixed.rgb != rgb).any(axis=-1).mean() > 0.5
    dets = [detect_rod_top_down(f.rgb, f.depth, f.camera, T @ T_cal, depth_scale=f.depth_scale)
            for f in (right, said)]  # fmt: skip
    bgr = np.ascontiguousarray(said.rgb[..., ::-1])
    dets.append(detect_rod_top_down(bgr, right.depth, right.camera, T @ T_cal,
                                    depth_scale=1e-4, color_order="bgr"))  # fmt: skip
    for det in dets[1:]:
        assert det.grasp == dets[0].grasp and det.length == dets[0].length
        assert (det.mask == dets[0].mask).all()
    centre, yaw_deg = top_errors(dets[0], truths[0], T, T_cal)
    assert centre < CENTRE_BOUND and yaw_deg < YAW_BOUND_DEG


def _cli(tmp_path, paths, *extra) -> int:
    rgb, depth, info = paths
    return main(["views", "--rgb", str(rgb), "--depth", str(depth), "--camera-info", str(info),
                 "--out", str(tmp_path / "out"), *extra])  # fmt: skip


def test_comgrasp_views_on_files_with_the_cameras_pose(scene, tmp_path, capsys):
    depth, camera, T, rgb, truth, float_det = scene
    paths = _save(tmp_path, np.round(depth * 1e3).astype(np.uint16), rgb,
                  {**_calibration_yaml(camera), "depth_scale": 0.001})  # fmt: skip
    pose = tmp_path / "T_world_cam.json"
    pose.write_text(json.dumps({"T_world_cam": T.tolist()}))
    assert _cli(tmp_path, paths, "--T-world-cam", str(pose), "--pick-area",
                "0.30,0.80,-0.35,0.35") == 0  # fmt: skip
    measured = json.loads((tmp_path / "out" / "depth_top_view.json").read_text())
    assert measured["frame"] == "world"
    x, y, _ = measured["centre_m"]
    assert np.hypot(x - float_det.grasp.x, y - float_det.grasp.y) < 2e-4
    assert abs(measured["length_m"] - float_det.length) < 5e-4
    drawn = cv2.imread(str(tmp_path / "out" / "depth_top_view.png"))
    # The overlay leaves the table's far corner as it was: in the file's colours (no swap).
    np.testing.assert_array_equal(drawn[-3:, -3:], rgb[-3:, -3:, ::-1])
    # A file holding BGR in its RGB channels, said with --bgr, draws the same picture.
    cv2.imwrite(str(paths[0]), rgb)
    assert _cli(tmp_path, paths, "--T-world-cam", str(pose), "--pick-area",
                "0.30,0.80,-0.35,0.35", "--bgr") == 0  # fmt: skip
    np.testing.assert_array_equal(cv2.imread(str(tmp_path / "out" / "depth_top_view.png")), drawn)


def test_comgrasp_views_on_files_finds_the_table_without_a_pose(scene, tmp_path):
    depth, camera, T, rgb, truth, _ = scene
    paths = _save(tmp_path, np.round(depth * 1e3).astype(np.uint16), rgb,
                  _calibration_yaml(camera))  # fmt: skip
    # The table frame: origin below the camera, x to the image's right, y to its top.
    assert _cli(tmp_path, paths, "--depth-scale", "0.001",
                "--pick-area=-0.1,0.4,-0.35,0.2") == 0  # fmt: skip
    measured = json.loads((tmp_path / "out" / "depth_top_view.json").read_text())
    assert measured["frame"] == "table"
    # The table frame's centre, put in the world with the true camera pose: the truth.
    T_world_table = T @ np.linalg.inv(np.array(measured["T_table_cam"]))
    centre = T_world_table[:3, :3] @ measured["centre_m"] + T_world_table[:3, 3]
    assert np.hypot(centre[0] - truth[0], centre[1] - truth[1]) < CENTRE_BOUND
    assert abs(measured["length_m"] - OBJECTS["obj2"].length) < 3e-3
    assert abs(centre[2] - OBJECTS["obj2"].rest_height) < 4e-3  # the handle's axis


@pytest.mark.parametrize("bad", ["8-bit depth", "size", "missing k", "unreadable", "no scale"])
def test_bad_files_end_with_exit_2_and_say_what_is_wrong(scene, tmp_path, capsys, bad):
    depth, camera, T, rgb, *_ = scene
    mm = np.round(depth * 1e3).astype(np.uint16)
    info = {"width": 640, "height": 480, "k": camera.K.ravel().tolist(), "depth_scale": 0.001}
    expected = {
        "8-bit depth": "one channel of 16-bit integers",
        "size": "the camera info says 320",
        "missing k": "camera intrinsics not understood",
        "unreadable": "cannot read the colour file",
        "no scale": "no depth_scale",
    }[bad]
    if bad == "size":
        info["width"] = 320
    if bad == "missing k":
        del info["k"]
    if bad == "no scale":
        del info["depth_scale"]
    paths = _save(tmp_path, (mm // 8).astype(np.uint8) if bad == "8-bit depth" else mm, rgb, info,
                  suffix=".json")  # fmt: skip
    if bad == "unreadable":
        paths[0].write_bytes(b"not an image")
    assert _cli(tmp_path, paths) == 2
    err = capsys.readouterr().err
    assert expected in err and "Traceback" not in err, err
    assert not (tmp_path / "out").exists()  # nothing written


def test_camera_info_files_in_ros_layouts(scene, tmp_path):
    camera = scene[1]
    ros2_echo = ("header:\n  frame_id: camera_color_optical_frame\nheight: 480\nwidth: 640\n"
                 "distortion_model: rational_polynomial\nd: [0.1, -0.05, 0.0, 0.0, 0.01, 0.0, "
                 f"0.0, 0.0]\nk: {camera.K.ravel().tolist()}\n")  # fmt: skip
    path = tmp_path / "camera_info.yaml"
    path.write_text(ros2_echo)
    model, scale = read_camera_info(path)
    assert model.distortion_model == "rational_polynomial" and model.distorted
    assert model.pinhole == camera and scale is None
    path.write_text("a: &x [1, 2]\nb: *x\n")
    with pytest.raises(CameraFileError, match="anchors"):
        read_camera_info(path)


def _views(tmp_path, *args) -> int:
    return main(["views", *map(str, args), "--out", str(tmp_path / "out")])


def _palette_index(image: np.ndarray) -> np.ndarray:
    """(H, W) index of each BGR pixel in OpenCV's TURBO colour map; -1: not one of its."""
    turbo = cv2.applyColorMap(np.arange(256, dtype=np.uint8)[:, None], cv2.COLORMAP_TURBO)
    key = lambda a: (a[..., 0].astype(int) << 16) | (a[..., 1].astype(int) << 8) | a[..., 2]  # noqa: E731
    lookup = {k: i for i, k in reversed(list(enumerate(key(turbo[:, 0]))))}
    return np.vectorize(lambda k: lookup.get(k, -1))(key(image))


def test_depth_alone_top_view_measures_as_with_colour_and_draws_on_the_depth(scene, tmp_path):
    """``comgrasp views`` without --rgb: the same rod as with it, drawn on the depth in
    TURBO colours (near warmer), the lost pixels black, the JSON saying no colour."""
    depth, camera, T, rgb, truth, _ = scene
    mm = np.round(depth * 1e3).astype(np.uint16)
    mm[440:452, 600:612] = 0  # a hole in the table, outside the pick area
    info = {**_calibration_yaml(camera), "depth_scale": 1e-3}
    rgb_file, depth_file, info_file = _save(tmp_path, mm, rgb, info)
    pose = tmp_path / "T_world_cam.json"
    pose.write_text(json.dumps({"T_world_cam": T.tolist()}))
    where = ["--depth", depth_file, "--camera-info", info_file, "--T-world-cam", pose,
             "--pick-area", "0.30,0.80,-0.35,0.35"]  # fmt: skip
    out = tmp_path / "out" / "depth_top_view"
    assert _views(tmp_path, "--rgb", rgb_file, *where) == 0
    with_colour = json.loads(out.with_suffix(".json").read_text())
    drawn_on_colour = cv2.imread(str(out.with_suffix(".png")))
    assert with_colour["colour"] == str(rgb_file)
    assert _views(tmp_path, *where) == 0
    alone = json.loads(out.with_suffix(".json").read_text())
    assert alone["colour"] is False and alone["camera"]["color_order_in_file"] is None
    np.testing.assert_allclose(alone["centre_m"], with_colour["centre_m"], atol=2e-4)
    assert abs(alone["yaw_deg"] - with_colour["yaw_deg"]) < 0.2
    assert abs(alone["length_m"] - with_colour["length_m"]) < 5e-4
    assert abs(alone["length_m"] - OBJECTS["obj2"].length) < 3e-3
    drawn = cv2.imread(str(out.with_suffix(".png")))
    assert (drawn[440:452, 600:612] == 0).all()  # no depth: black
    index = _palette_index(drawn)
    assert (index[60:200, 240:440] >= 0).all()  # the table, away from the marks: TURBO
    rod = (depth < np.median(depth) - 0.01) & (index >= 0)
    table = (np.abs(depth - np.median(depth)) < 1e-3) & (index >= 0)
    assert rod.sum() > 200 and np.median(index[rod]) > np.median(index[table]) + 20
    assert np.abs(drawn.astype(int) - drawn_on_colour).mean() > 20  # not the colour image


def test_the_side_view_runs_on_the_depth_alone(tmp_path, capsys):
    """A held rod seen by the wrist camera (a MuJoCo render at the measurement pose, saved in
    0.1 mm units), without a colour image: the command measures the tilt and the grasp
    offset as the library does on the float depth, within the perception contract of the
    truth, and draws on the depth. (Given only T_ee_cam, as here, the side view cannot tell
    the arm from what lies beyond the rod at most poses and refuses: the simulation passes
    the arm's capsules, which a file does not carry.)"""
    from test_perception import _wrist_frame

    from comgrasp_pin.geometry import tilt_from_level_deg
    from comgrasp_pin.perception import observe_held_rod

    T_ee_obj, T_ee_cam, camera, depth = _wrist_frame("obj2", 10.0)
    library = observe_held_rod(None, depth, camera, T_ee_cam)
    units = np.where(np.isfinite(depth), np.round(depth * 1e4), 0).astype(np.uint16)
    info = {**_calibration_yaml(camera), "depth_scale": 1e-4}
    _, depth_file, info_file = _save(tmp_path, units, None, info)
    pose = tmp_path / "T_ee_cam.json"
    pose.write_text(json.dumps({"T_ee_cam": T_ee_cam.tolist()}))
    assert _views(tmp_path, "--view", "side", "--depth", depth_file, "--camera-info", info_file,
                  "--T-ee-cam", pose) == 0, capsys.readouterr().err  # fmt: skip
    measured = json.loads((tmp_path / "out" / "depth_side_view.json").read_text())
    assert measured["colour"] is False
    true_tilt = tilt_from_level_deg(np.arctan2(-T_ee_obj[2, 0], T_ee_obj[0, 0]))
    assert abs(measured["tilt_from_level_deg"] - true_tilt) < 1.0
    assert abs(measured["tilt_from_level_deg"] - tilt_from_level_deg(library.theta)) < 0.2
    assert abs(measured["grasp_offset_m"] - library.grasp_offset) < 1e-3
    drawn = cv2.imread(str(tmp_path / "out" / "depth_side_view.png"))
    assert drawn.shape[:2] == depth.shape
    lost = units == 0
    assert (drawn[lost] == 0).all(axis=-1).mean() > 0.9  # no depth: black


@pytest.mark.skipif(
    not FLASHLIGHT.is_dir(), reason=f"the real data is not here: {FLASHLIGHT} (../shared/realdata)"
)
def test_a_real_flashlight_is_measured_from_the_depth_alone(tmp_path, capsys):
    """A structured-light camera's real frame (millimetres), no colour and no pose: the
    table's plane fitted, the flashlight (about 20 cm; its dataset mask gives 19-21 cm)
    measured."""
    assert _views(tmp_path, "--depth", FLASHLIGHT / "depth_0_mm.png", "--camera-info",
                  FLASHLIGHT / "primesense_camera_info.yaml") == 0  # fmt: skip
    measured = json.loads((tmp_path / "out" / "depth_0_mm_top_view.json").read_text())
    assert measured["frame"] == "table" and measured["colour"] is False
    assert 0.17 < measured["length_m"] < 0.23, measured["length_m"]
    drawn = cv2.imread(str(tmp_path / "out" / "depth_0_mm_top_view.png"))
    assert drawn.shape == (480, 640, 3)


def test_outputs_are_named_after_the_whole_depth_file_name(scene, tmp_path):
    depth, camera, T, rgb, *_ = scene
    mm = np.round(depth * 1e3).astype(np.uint16)
    paths = _save(tmp_path, mm, rgb, {**_calibration_yaml(camera), "depth_scale": 0.001})
    dotted = tmp_path / "frame.001.png"  # a recorder's numbered frame
    paths[1].rename(dotted)
    pose = tmp_path / "T_world_cam.json"
    pose.write_text(json.dumps({"T_world_cam": T.tolist()}))
    assert _cli(tmp_path, (paths[0], dotted, paths[2]), "--T-world-cam", str(pose),
                "--pick-area", "0.30,0.80,-0.35,0.35") == 0  # fmt: skip
    written = sorted(p.name for p in (tmp_path / "out").iterdir())
    assert written == ["frame.001_top_view.json", "frame.001_top_view.png"]


def test_dex_nets_own_files_float_metres_npy_intr_and_tf(scene, tmp_path):
    """A frame as Dex-Net and GQ-CNN ship theirs: depth as an (H, W, 1) float .npy in
    metres, autolab_core's .intr (JSON of _fx, _fy, _cx, _cy, _width, _height) and .tf
    (from and to frames, translation, rotation rows); also a 32-bit float TIFF. Each gives
    the float path's detection; a camera info's mm scale with a float depth is refused."""
    depth, camera, T, rgb, truth, float_det = scene
    metres = np.where(np.isfinite(depth), depth, np.nan).astype(np.float32)  # NaN: no return
    np.save(tmp_path / "depth_0.npy", metres[..., None])
    assert cv2.imwrite(str(tmp_path / "depth_0.tif"), metres)
    intr = {
        "_cy": camera.cy,
        "_cx": camera.cx,
        "_fy": camera.fy,
        "_height": camera.height,
        "_fx": camera.fx,
        "_width": camera.width,
        "_skew": 0.0,
        "_K": 0,
        "_frame": "top",
    }
    (tmp_path / "top.intr").write_text(json.dumps(intr))
    rows = "\n".join(" ".join(f"{v:.17g}" for v in row) for row in (T[:3, 3], *T[:3, :3]))
    (tmp_path / "top.tf").write_text(f"top\nworld\n{rows}\n")
    cv2.imwrite(str(tmp_path / "rgb.png"), rgb[..., ::-1])
    for name in ("depth_0.npy", "depth_0.tif"):
        files = read_rgbd(tmp_path / "rgb.png", tmp_path / name, tmp_path / "top.intr")
        assert files.depth.dtype == np.float32 and files.depth_scale == 1.0
        assert (files.depth[~np.isfinite(metres)] == 0).all()
        assert _cli(tmp_path, (tmp_path / "rgb.png", tmp_path / name, tmp_path / "top.intr"),
                    "--T-world-cam", str(tmp_path / "top.tf"), "--pick-area",
                    "0.30,0.80,-0.35,0.35") == 0  # fmt: skip
        measured = json.loads((tmp_path / "out" / "depth_0_top_view.json").read_text())
        np.testing.assert_allclose(measured["T_world_cam"], T, atol=1e-12)
        x, y, _ = measured["centre_m"]
        assert np.hypot(x - float_det.grasp.x, y - float_det.grasp.y) < 2e-4
        assert abs(measured["length_m"] - float_det.length) < 5e-4
    info = tmp_path / "mm.yaml"
    info.write_text(yaml.safe_dump({**_calibration_yaml(camera), "depth_scale": 0.001}))
    with pytest.raises(CameraFileError, match="holds floats, metres by convention"):
        read_rgbd(None, tmp_path / "depth_0.npy", info)
    assert read_rgbd(None, tmp_path / "depth_0.npy", info, depth_scale=1.0).depth_scale == 1.0
    skewed = tmp_path / "skew.intr"
    skewed.write_text(json.dumps({**intr, "_skew": 0.5}))
    with pytest.raises(CameraFileError, match=r"K must be \[\[fx, 0, cx\]"):
        read_rgbd(None, tmp_path / "depth_0.npy", skewed)
