"""RGBD frames from ROS 1 bags (``perception.frames.rgbd_bag``, ``comgrasp views --bag``).

Real ROS 1 bag files, written here with rosbags' own ROS 1 Writer and the Noetic message
types: as ``rosbag record`` keeps a camera driver's topics, and as the RealSense Viewer
records a camera (its ``/device_0/sensor_N/...`` topics: the depth and colour streams each
with its own camera info, the depth's units an option of the sensor). The reference each
read is held to is the arrays written and the simulator's rod.
"""

from __future__ import annotations

import numpy as np
import pytest
from _corruption import table_scene, top_inputs
from rosbags.rosbag1 import Writer
from rosbags.typesys import Stores, get_typestore

from comgrasp_pin.cli import main
from comgrasp_pin.errors import CameraFileError
from comgrasp_pin.perception import detect_rod_top_down, read_rgbd_bag
from comgrasp_pin.simulation.objects import OBJECTS

ROD = ("obj2", 0.60, -0.1, 0.4)
AREA = (0.30, 0.80, -0.35, 0.35)
T0 = 1_600_000_000 * 10**9  # ns
STORE = get_typestore(Stores.ROS1_NOETIC)
RS = "/device_0/sensor_0/Depth_0"  # a RealSense Viewer recording's depth stream
RS_COLOUR = "/device_0/sensor_1/Color_0"


@pytest.fixture(scope="module")
def scene():
    """(depth (m), PinholeCamera, T_world_cam, rgb, truth (x, y, yaw))."""
    sim, rig, truths = table_scene([ROD])
    depth, camera, T, rgb = top_inputs(sim, rig)
    rig.close()
    return depth, camera, T, rgb, truths[0]


def _header(ns: int, frame: str = "camera_color_optical_frame"):
    Time = STORE.types["builtin_interfaces/msg/Time"]
    return STORE.types["std_msgs/msg/Header"](
        seq=0, stamp=Time(sec=ns // 10**9, nanosec=ns % 10**9), frame_id=frame
    )


def _image(ns: int, pixels: np.ndarray, encoding: str):
    raw = np.frombuffer(pixels.astype(pixels.dtype.newbyteorder("<")).tobytes(), np.uint8)
    return STORE.types["sensor_msgs/msg/Image"](
        header=_header(ns), height=pixels.shape[0], width=pixels.shape[1],
        encoding=encoding, is_bigendian=0, step=len(raw) // pixels.shape[0], data=raw,
    )  # fmt: skip


def _info(ns: int, camera, fx_scale: float = 1.0):
    K = camera.K * np.array([[fx_scale, 1, 1], [1, fx_scale, 1], [1, 1, 1]])
    return STORE.types["sensor_msgs/msg/CameraInfo"](
        header=_header(ns), height=camera.height, width=camera.width,
        distortion_model="plumb_bob", D=np.zeros(5), K=K.ravel().astype(float),
        R=np.eye(3).ravel(), P=np.c_[K, np.zeros(3)].ravel().astype(float),
        binning_x=0, binning_y=0,
        roi=STORE.types["sensor_msgs/msg/RegionOfInterest"](
            x_offset=0, y_offset=0, height=0, width=0, do_rectify=False),
    )  # fmt: skip


def _write(path, topics: dict):
    """A ROS 1 bag of ``topics``: {name: [(receive ns, message)]}, written as received."""
    with Writer(path) as writer:
        conns = {name: writer.add_connection(name, msgs[0][1].__msgtype__, typestore=STORE)
                 for name, msgs in topics.items()}  # fmt: skip
        for name, ns, msg in sorted(((n, t, m) for n, ms in topics.items() for t, m in ms),
                                    key=lambda x: x[1]):  # fmt: skip
            writer.write(conns[name], ns, STORE.serialize_ros1(msg, msg.__msgtype__))
    return path


def test_a_rosbag_record_of_aligned_topics_gives_the_frame_and_its_rod(scene, tmp_path):
    depth, camera, T, rgb, truth = scene
    mm = np.round(np.where(np.isfinite(depth), depth, 0.0) * 1e3).astype(np.uint16)
    ns = [T0 + k * 33_333_333 for k in range(3)]
    bag = _write(tmp_path / "rec.bag", {
        "/camera/aligned_depth_to_color/image_raw": [(t, _image(t, mm, "16UC1")) for t in ns],
        "/camera/color/image_raw": [(t + 10**6, _image(t + 10**6, rgb, "rgb8")) for t in ns],
        "/camera/aligned_depth_to_color/camera_info": [(t, _info(t, camera)) for t in ns],
        "/camera/color/camera_info": [(t, _info(t, camera)) for t in ns],  # the same camera
    })  # fmt: skip
    frame = read_rgbd_bag(bag, at=0.07)
    assert frame.info_topic == "/camera/aligned_depth_to_color/camera_info"
    assert frame.time_s == pytest.approx(0.0666667, abs=1e-6)
    np.testing.assert_array_equal(frame.files.depth, mm)
    np.testing.assert_array_equal(frame.files.rgb, rgb)
    np.testing.assert_allclose(frame.files.camera.K, camera.K)
    det = detect_rod_top_down(frame.files.rgb, frame.files.depth, frame.files.camera, T, AREA,
                              depth_scale=frame.files.depth_scale)  # fmt: skip
    assert np.hypot(det.grasp.x - truth[0], det.grasp.y - truth[1]) < 3e-3
    assert abs(det.length - OBJECTS["obj2"].length) < 3e-3


def _realsense_viewer(scene, units: float) -> dict:
    """A RealSense Viewer recording's topics: the depth in ``units`` (m per count), its own
    camera info under ``info/``, the colour stream with a camera of its own (10 % longer
    focal length: not registered to the depth)."""
    depth, camera, _, rgb, _ = scene
    counts = np.round(np.where(np.isfinite(depth), depth, 0.0) / units).astype(np.uint16)
    Float32 = STORE.types["std_msgs/msg/Float32"]
    return {
        f"{RS}/image/data": [(T0, _image(T0, counts, "mono16"))],
        f"{RS}/info/camera_info": [(T0, _info(T0, camera))],
        "/device_0/sensor_0/option/Depth_Units/value": [(T0, Float32(data=units))],
        f"{RS_COLOUR}/image/data": [(T0, _image(T0, rgb, "rgb8"))],
        f"{RS_COLOUR}/info/camera_info": [(T0, _info(T0, camera, fx_scale=1.1))],
    }


def test_a_realsense_viewer_recording_reads_its_depth_units_and_refuses_its_colour(
    scene, tmp_path, capsys
):
    """A D405's 0.1 mm counts are read as such; the colour camera is not the depth's, so the
    colour is refused (by name, with the way out), and the depth alone measures the rod."""
    depth, camera, T, _, truth = scene
    bag = _write(tmp_path / "viewer.bag", _realsense_viewer(scene, units=1e-4))
    with pytest.raises(CameraFileError, match="not registered to the colour.*--no-rgb"):
        read_rgbd_bag(bag)
    frame = read_rgbd_bag(bag, colour=False)
    assert frame.info_topic == f"{RS}/info/camera_info"
    assert frame.files.depth_scale == pytest.approx(1e-4)
    metres = frame.files.depth * frame.files.depth_scale
    seen = np.isfinite(depth)
    assert np.abs(metres[seen] - depth[seen]).max() < 6e-5  # half a count
    det = detect_rod_top_down(None, frame.files.depth, frame.files.camera, T, AREA,
                              depth_scale=frame.files.depth_scale)  # fmt: skip
    assert np.hypot(det.grasp.x - truth[0], det.grasp.y - truth[1]) < 3e-3
    # On the command line: the colour's refusal is exit 2 with the words, --no-rgb measures
    assert main(["views", "--bag", str(bag), "--out", str(tmp_path / "o")]) == 2
    assert "not registered" in capsys.readouterr().err
    assert main(["views", "--bag", str(bag), "--no-rgb", "--out", str(tmp_path / "o")]) == 0


def test_a_file_named_bag_that_is_not_one_is_refused(tmp_path, capsys):
    fake = tmp_path / "notes.bag"
    fake.write_text("these are not messages\n")
    with pytest.raises(CameraFileError, match="not a ROS 1 bag"):
        read_rgbd_bag(fake)
    assert main(["views", "--bag", str(fake), "--out", str(tmp_path / "o")]) == 2
    assert "not a ROS 1 bag" in capsys.readouterr().err
    with pytest.raises(CameraFileError, match="not found"):
        read_rgbd_bag(tmp_path / "missing.bag")
