"""RGBD frames from ROS 2 bags (``perception.frames.rgbd_bag``, ``comgrasp views --bag``).

The bags are real ones, written here with rosbags' own Writer and the ROS 2 Humble message
types, as a camera driver records them (REP 118: 16UC1 millimetres, 32FC1 metres with NaN
and Inf; image_transport's compressed colour and compressedDepth). The reference each read is
held to is independent of the reader: the arrays written, and the same frame through the
files path (``read_rgbd`` of PNGs) and the float path (``detect_rod_top_down`` on the
render).
"""

from __future__ import annotations

import json
import struct
from pathlib import Path

import cv2
import numpy as np
import pytest
from _corruption import one_rod_frame
from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.typesys import Stores, get_typestore

from comgrasp_pin.cli import main
from comgrasp_pin.errors import CameraFileError
from comgrasp_pin.perception import detect_rod_top_down
from comgrasp_pin.perception.frames.rgbd_bag import read_rgbd_bag
from comgrasp_pin.perception.frames.rgbd_files import read_rgbd
from comgrasp_pin.simulation.objects import OBJECTS

ROD = ("obj2", 0.60, -0.1, 0.4)
AREA = (0.30, 0.80, -0.35, 0.35)
T0 = 1_700_000_000 * 10**9  # ns
STORE = get_typestore(Stores.ROS2_HUMBLE)


@pytest.fixture(scope="module")
def scene():
    """(depth (m), PinholeCamera, T_world_cam, rgb, truth (x, y, yaw))."""
    return one_rod_frame(ROD)


def _header(ns: int, frame: str = "camera_color_optical_frame"):
    Time = STORE.types["builtin_interfaces/msg/Time"]
    return STORE.types["std_msgs/msg/Header"](
        stamp=Time(sec=ns // 10**9, nanosec=ns % 10**9), frame_id=frame
    )


def _image(ns: int, pixels: np.ndarray, encoding: str, big_endian: bool = False):
    h, w = pixels.shape[:2]
    data = pixels.astype(pixels.dtype.newbyteorder(">" if big_endian else "<"))
    raw = np.frombuffer(data.tobytes(), dtype=np.uint8)
    return STORE.types["sensor_msgs/msg/Image"](
        header=_header(ns), height=h, width=w, encoding=encoding, is_bigendian=int(big_endian),
        step=len(raw) // h, data=raw,
    )  # fmt: skip


def _compressed(ns: int, data: bytes, fmt: str):
    return STORE.types["sensor_msgs/msg/CompressedImage"](
        header=_header(ns), format=fmt, data=np.frombuffer(data, dtype=np.uint8)
    )


def _info(ns: int, camera):
    T = STORE.types
    return T["sensor_msgs/msg/CameraInfo"](
        header=_header(ns), height=camera.height, width=camera.width,
        distortion_model="plumb_bob", d=np.zeros(5), k=camera.K.ravel().astype(float),
        r=np.eye(3).ravel(), p=np.c_[camera.K, np.zeros(3)].ravel().astype(float),
        binning_x=0, binning_y=0,
        roi=T["sensor_msgs/msg/RegionOfInterest"](x_offset=0, y_offset=0, height=0, width=0,
                                                   do_rectify=False),
    )  # fmt: skip


def _write(path, topics: dict, storage=StoragePlugin.SQLITE3):
    """A bag of ``topics``: {name: [(receive ns, message)]}, each written as received."""
    with Writer(path, version=9, storage_plugin=storage) as writer:
        conns = {name: writer.add_connection(name, msgs[0][1].__msgtype__, typestore=STORE)
                 for name, msgs in topics.items()}  # fmt: skip
        for name, ns, msg in sorted(((n, t, m) for n, ms in topics.items() for t, m in ms),
                                    key=lambda x: x[1]):  # fmt: skip
            writer.write(conns[name], ns, STORE.serialize_cdr(msg, msg.__msgtype__))
    return path


def _realsense(scene, frames=3, period_ns=33_333_333, skew_ns=4_000_000, **kinds):
    """A RealSense's aligned topics: 16UC1 depth, rgb8 colour, the colour camera's info."""
    depth, camera, _, rgb, _ = scene
    mm = np.round(np.where(np.isfinite(depth), depth, 0.0) * 1e3).astype(np.uint16)
    ns = [T0 + k * period_ns for k in range(frames)]
    return {
        "/camera/aligned_depth_to_color/image_raw": [(t, _image(t, mm, "16UC1")) for t in ns],
        "/camera/color/image_raw": [(t + skew_ns, _image(t + skew_ns, rgb, "rgb8")) for t in ns],
        "/camera/aligned_depth_to_color/camera_info": [(t, _info(t, camera)) for t in ns],
        **kinds,
    }


def test_a_realsense_bag_gives_the_frame_written_and_its_rod(scene, tmp_path):
    depth, camera, T, rgb, truth = scene
    bag = _write(tmp_path / "rs", _realsense(scene))
    frame = read_rgbd_bag(bag, at=0.04)  # the second frame, 33 ms after the first
    assert frame.depth_topic == "/camera/aligned_depth_to_color/image_raw"
    assert frame.rgb_topic == "/camera/color/image_raw"
    assert frame.info_topic == "/camera/aligned_depth_to_color/camera_info"
    assert frame.time_s == pytest.approx(0.0333333, abs=1e-6)
    assert frame.skew_s == pytest.approx(0.004)
    files = frame.files
    mm = np.round(np.where(np.isfinite(depth), depth, 0.0) * 1e3).astype(np.uint16)
    np.testing.assert_array_equal(files.depth, mm)
    np.testing.assert_array_equal(files.rgb, rgb)
    assert files.depth_scale == 0.001
    np.testing.assert_allclose(files.camera.K, camera.K)
    det = detect_rod_top_down(files.rgb, files.depth, files.camera, T, AREA,
                              depth_scale=files.depth_scale)  # fmt: skip
    assert np.hypot(det.grasp.x - truth[0], det.grasp.y - truth[1]) < 3e-3
    assert abs(det.length - OBJECTS["obj2"].length) < 3e-3


def test_rep118_float_metres_with_nan_and_inf_big_endian_bgr_in_mcap(scene, tmp_path):
    depth, camera, T, rgb, truth = scene
    metres = np.where(np.isfinite(depth), depth, np.inf).astype(np.float32)
    metres[100:110, 200:260] = np.nan  # no measurement (REP 117)
    metres[300:305, 50:60] = -np.inf  # too near
    topics = {
        "/cam/depth/image": [(T0, _image(T0, metres, "32FC1", big_endian=True))],
        "/cam/color/image": [(T0, _image(T0, rgb[..., ::-1].copy(), "bgr8"))],
        "/cam/depth/camera_info": [(T0, _info(T0, camera))],
    }
    frame = read_rgbd_bag(_write(tmp_path / "f", topics, StoragePlugin.MCAP))
    got = frame.files.depth
    assert got.dtype == np.float32 and frame.files.depth_scale == 1.0
    assert (got[100:110, 200:260] == 0).all() and (got[300:305, 50:60] == 0).all()
    kept = np.isfinite(metres)
    np.testing.assert_array_equal(got[kept], metres[kept])
    assert np.isposinf(got[np.isposinf(metres)]).all()
    np.testing.assert_array_equal(frame.files.rgb, rgb)
    det = detect_rod_top_down(frame.files.rgb, got.astype(float), camera, T, AREA)
    assert np.hypot(det.grasp.x - truth[0], det.grasp.y - truth[1]) < 3e-3


def test_image_transport_compressed_colour_and_compressed_depth(scene, tmp_path):
    depth, camera, T, rgb, truth = scene
    mm = np.round(np.where(np.isfinite(depth), depth, 0.0) * 1e3).astype(np.uint16)
    png = cv2.imencode(".png", mm)[1].tobytes()
    header = struct.pack("<iff", 0, 0.0, 0.0)  # image_transport's ConfigHeader (12 bytes)
    jpeg = cv2.imencode(".jpg", rgb[..., ::-1], [cv2.IMWRITE_JPEG_QUALITY, 95])[1].tobytes()
    topics = {
        "/cam/depth/image_raw/compressedDepth":
            [(T0, _compressed(T0, header + png, "16UC1; compressedDepth png"))],
        "/cam/color/image_raw/compressed":
            [(T0, _compressed(T0, jpeg, "rgb8; jpeg compressed bgr8"))],
        "/cam/camera_info": [(T0, _info(T0, camera))],
    }  # fmt: skip
    frame = read_rgbd_bag(_write(tmp_path / "c", topics))
    np.testing.assert_array_equal(frame.files.depth, mm)
    assert np.abs(frame.files.rgb.astype(int) - rgb).mean() < 3  # JPEG, in RGB order
    assert frame.info_topic == "/cam/camera_info"  # no sibling: the only one


def test_comgrasp_views_on_a_bag_measures_as_on_the_same_files(scene, tmp_path, capsys):
    depth, camera, T, rgb, truth = scene
    bag = _write(tmp_path / "rs", _realsense(scene))
    pose = tmp_path / "T_world_cam.json"
    pose.write_text(json.dumps({"T_world_cam": T.tolist()}))
    where = ["--T-world-cam", str(pose), "--pick-area", ",".join(map(str, AREA))]
    assert main(["views", "--bag", str(bag), "--out", str(tmp_path / "o"), *where]) == 0
    from_bag = json.loads((tmp_path / "o" / "rs_at_0ms_top_view.json").read_text())
    assert from_bag["bag"]["rgb_topic"] == "/camera/color/image_raw"
    # The same frame saved as files, read by the files path.
    mm = np.round(np.where(np.isfinite(depth), depth, 0.0) * 1e3).astype(np.uint16)
    cv2.imwrite(str(tmp_path / "depth.png"), mm)
    cv2.imwrite(str(tmp_path / "rgb.png"), rgb[..., ::-1])
    info = {"width": camera.width, "height": camera.height, "k": camera.K.ravel().tolist(),
            "d": [0.0] * 5, "distortion_model": "plumb_bob", "depth_scale": 0.001}  # fmt: skip
    (tmp_path / "info.json").write_text(json.dumps(info))
    assert main(["views", "--rgb", str(tmp_path / "rgb.png"), "--depth",
                 str(tmp_path / "depth.png"), "--camera-info", str(tmp_path / "info.json"),
                 "--out", str(tmp_path / "o"), *where]) == 0  # fmt: skip
    from_files = json.loads((tmp_path / "o" / "depth_top_view.json").read_text())
    for key in ("centre_m", "yaw_rad", "length_m", "handle_height_m", "table_z_m"):
        assert from_bag[key] == from_files[key], key
    x, y, _ = from_bag["centre_m"]
    assert np.hypot(x - truth[0], y - truth[1]) < 3e-3
    assert (tmp_path / "o" / "rs_at_0ms_top_view.png").is_file()


def test_what_the_bag_cannot_give_is_said(scene, tmp_path, capsys):
    depth, camera, T, rgb, _ = scene
    mm = np.round(np.where(np.isfinite(depth), depth, 0.0) * 1e3).astype(np.uint16)
    two = _write(tmp_path / "two", _realsense(scene, **{
        "/camera/depth/image_rect_raw": [(T0, _image(T0, mm, "16UC1"))]}))  # fmt: skip
    with pytest.raises(CameraFileError, match=r"2 depth image topics .*--depth-topic"):
        read_rgbd_bag(two)
    named = read_rgbd_bag(two, depth_topic="/camera/aligned_depth_to_color/image_raw")
    assert named.rgb_topic == "/camera/color/image_raw"
    late = _write(tmp_path / "late", _realsense(scene, skew_ns=80_000_000))
    with pytest.raises(CameraFileError, match="within 50 ms.*--no-rgb"):
        read_rgbd_bag(late)
    assert read_rgbd_bag(late, colour=False).files.rgb is None
    with pytest.raises(CameraFileError, match="past the depth topic"):
        read_rgbd_bag(late, at=5.0)
    small = {"/cam/color/image_raw": [(T0, _image(T0, rgb[::2, ::2].copy(), "rgb8"))]}
    unaligned = _write(tmp_path / "u", _realsense(scene, frames=1, skew_ns=0, **small))
    with pytest.raises(CameraFileError, match="2 colour image topics"):
        read_rgbd_bag(unaligned)
    with pytest.raises(CameraFileError, match="aligned to the colour camera"):
        read_rgbd_bag(unaligned, rgb_topic="/cam/color/image_raw")
    bayer = {"/camera/color/image_raw": [(T0, _image(T0, rgb[..., 0].copy(), "bayer_rggb8"))]}
    with pytest.raises(CameraFileError, match="bayer_rggb8.*valid colour encodings"):
        read_rgbd_bag(_write(tmp_path / "b", _realsense(scene, frames=1, skew_ns=0, **bayer)))
    cut = _image(T0, mm, "16UC1")
    cut.data = cut.data[: len(cut.data) // 2]  # a damaged message: half its pixels
    damaged = _write(tmp_path / "d", _realsense(scene, frames=1, skew_ns=0, **{
        "/camera/aligned_depth_to_color/image_raw": [(T0, cut)]}))  # fmt: skip
    with pytest.raises(CameraFileError, match=r"640 x 480 px 16UC1 image holds 307200 bytes"):
        read_rgbd_bag(damaged)
    # On the command line: exit 2, the message, no traceback.
    assert main(["views", "--bag", str(two), "--out", str(tmp_path / "o")]) == 2
    assert "--depth-topic" in capsys.readouterr().err
    assert main(["views", "--bag", str(two), "--depth", "d.png", "--out", str(tmp_path)]) == 2
    assert "drop --depth" in capsys.readouterr().err
    assert main(["views", "--bag", str(tmp_path / "none"), "--out", str(tmp_path)]) == 2
    assert "bag not found" in capsys.readouterr().err


FLASHLIGHT = (Path(__file__).resolve().parents[2] / "shared" / "realdata" / "rgbd"
              / "overhead_primesense_flashlight")  # fmt: skip


@pytest.mark.skipif(not FLASHLIGHT.is_dir(), reason="needs ../shared/realdata (not in the repo)")
def test_a_real_primesense_frame_as_a_bag_measures_as_its_files(tmp_path):
    """The shared real frame (a PrimeSense's millimetres and colour) recorded as a driver
    would publish it: the bag's answer is the files' answer, in both frames."""
    files = read_rgbd(FLASHLIGHT / "color_0.png", FLASHLIGHT / "depth_0_mm.png",
                      FLASHLIGHT / "primesense_camera_info.yaml", depth_scale=0.001)  # fmt: skip
    topics = {
        "/camera/depth_registered/image_raw": [(T0, _image(T0, files.depth, "16UC1"))],
        "/camera/rgb/image_raw": [(T0, _image(T0, files.rgb, "rgb8"))],
        "/camera/depth_registered/camera_info": [(T0, _info(T0, files.camera))],
    }
    frame = read_rgbd_bag(_write(tmp_path / "ps", topics))
    np.testing.assert_array_equal(frame.files.depth, files.depth)
    out = tmp_path / "o"
    world = ["--T-world-cam", str(FLASHLIGHT / "T_world_cam.txt"),
             "--pick-area", "0.26,0.56,-0.2,0.15"]  # fmt: skip
    for where in ([], world):
        assert main(["views", "--bag", str(tmp_path / "ps"), "--out", str(out), *where]) == 0
        assert main(["views", "--rgb", str(FLASHLIGHT / "color_0.png"), "--depth",
                     str(FLASHLIGHT / "depth_0_mm.png"), "--camera-info",
                     str(FLASHLIGHT / "primesense_camera_info.yaml"), "--depth-scale", "0.001",
                     "--out", str(out), *where]) == 0  # fmt: skip
        bag = json.loads((out / "ps_at_0ms_top_view.json").read_text())
        own = json.loads((out / "depth_0_mm_top_view.json").read_text())
        assert bag["frame"] == own["frame"] == ("world" if where else "table")
        for key in ("centre_m", "yaw_rad", "length_m", "handle_height_m", "pick_area_m"):
            assert bag[key] == own[key], key
        assert 0.17 < bag["length_m"] < 0.23, bag["length_m"]


def _tf_static(ns: int, chain: list[tuple[str, str, np.ndarray]]):
    """A /tf_static TFMessage of (parent, child, T_parent_child); quaternions by Pinocchio."""
    import pinocchio as pin

    T = STORE.types
    stamped = []
    for parent, child, M in chain:
        q = pin.Quaternion(M[:3, :3])
        rotation = T["geometry_msgs/msg/Quaternion"](x=q.x, y=q.y, z=q.z, w=q.w)
        stamped.append(T["geometry_msgs/msg/TransformStamped"](
            header=_header(ns, parent), child_frame_id=child,
            transform=T["geometry_msgs/msg/Transform"](
                translation=T["geometry_msgs/msg/Vector3"](*map(float, M[:3, 3])),
                rotation=rotation)))  # fmt: skip
    return T["tf2_msgs/msg/TFMessage"](transforms=stamped)


def test_the_cameras_pose_from_the_bags_static_transforms(scene, tmp_path, capsys):
    """world -> base_link -> camera_link -> camera_color_optical_frame on /tf_static (one
    edge written child to parent): the pose composed equals the camera's true pose, and
    ``--world-frame`` measures as ``--T-world-cam`` does."""
    import pinocchio as pin

    depth, camera, T, rgb, truth = scene
    pin.seed(3)
    T_world_base, T_base_link = pin.SE3.Random().homogeneous, pin.SE3.Random().homogeneous
    T_link_optical = np.linalg.inv(T_world_base @ T_base_link) @ T
    chain = [("world", "base_link", T_world_base),
             ("camera_link", "base_link", np.linalg.inv(T_base_link)),  # written backwards
             ("camera_link", "camera_color_optical_frame", T_link_optical)]  # fmt: skip
    tf = {"/tf_static": [(T0 - 10**9, _tf_static(T0 - 10**9, chain))]}
    bag = _write(tmp_path / "rs", _realsense(scene, **tf))
    frame = read_rgbd_bag(bag)
    assert frame.frame_id == "camera_color_optical_frame"
    from comgrasp_pin.perception.frames.static_tf import camera_pose

    np.testing.assert_allclose(camera_pose(frame.transforms, "world", frame.frame_id), T,
                               atol=1e-12)  # fmt: skip
    out = tmp_path / "o"
    area = ["--pick-area", ",".join(map(str, AREA))]
    assert main(["views", "--bag", str(bag), "--world-frame", "world", "--out", str(out),
                 *area]) == 0  # fmt: skip
    by_tf = json.loads((out / "rs_at_0ms_top_view.json").read_text())
    pose = tmp_path / "T.json"
    pose.write_text(json.dumps({"T_world_cam": T.tolist()}))
    assert main(["views", "--bag", str(bag), "--T-world-cam", str(pose), "--out", str(out),
                 *area]) == 0  # fmt: skip
    by_file = json.loads((out / "rs_at_0ms_top_view.json").read_text())
    # The composed pose equals T to 1e-12; a pixel on a threshold may still fall the other
    # way (one pixel moves the centre by about 1 um), so: the same rod to 10 um.
    for key in ("centre_m", "yaw_rad", "length_m"):
        np.testing.assert_allclose(by_tf[key], by_file[key], atol=1e-5)
    x, y, _ = by_tf["centre_m"]
    assert np.hypot(x - truth[0], y - truth[1]) < 3e-3
    capsys.readouterr()
    # What the transforms cannot give is said: an unknown frame, no link, no /tf_static.
    twice = ["--world-frame", "world", "--T-world-cam", str(pose)]
    side = ["--ee-frame", "tool0", "--view", "side"]
    for extra, words in ((["--world-frame", "map"], "'map' is not in the bag's /tf_static"),
                         (twice, "once"), (side, "'tool0' is not in")):  # fmt: skip
        assert main(["views", "--bag", str(bag), "--out", str(out), *area, *extra]) == 2
        assert words in capsys.readouterr().err
    apart = [("world", "base_link", T_world_base), ("camera_link", "camera_color_optical_frame",
                                                    T_link_optical)]  # fmt: skip
    with pytest.raises(CameraFileError, match="does not connect 'world'"):
        camera_pose(read_rgbd_bag(_write(tmp_path / "a", _realsense(scene, **{
            "/tf_static": [(T0, _tf_static(T0, apart))]}))).transforms, "world",
            "camera_color_optical_frame")  # fmt: skip
    with pytest.raises(CameraFileError, match="no /tf_static"):
        camera_pose(read_rgbd_bag(_write(tmp_path / "n", _realsense(scene))).transforms,
                    "world", "camera_color_optical_frame")  # fmt: skip
    with pytest.raises(CameraFileError, match="not an optical frame"):
        camera_pose(frame.transforms, "world", "camera_link")
