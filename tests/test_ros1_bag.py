"""RGBD frames from ROS 1 bags (``perception.frames.rgbd_bag``, ``comgrasp views --bag``).

Real ROS 1 bag files, written here with rosbags' own ROS 1 Writer and the Noetic message
types: as ``rosbag record`` keeps a camera driver's topics, and as the RealSense Viewer
records a camera (its ``/device_0/sensor_N/...`` topics: the depth and colour streams each
with its own camera info, the depth's units an option of the sensor). The reference each
read is held to is the arrays written and the simulator's rod.
"""

from __future__ import annotations

import os

import numpy as np
import pytest
from _corruption import one_rod_frame
from rosbags.rosbag1 import Writer
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

from comgrasp_pin.cli import main
from comgrasp_pin.errors import CameraFileError
from comgrasp_pin.perception import detect_rod_top_down, read_rgbd_bag
from comgrasp_pin.simulation.objects import OBJECTS

ROD = ("obj2", 0.60, -0.1, 0.4)
AREA = (0.30, 0.80, -0.35, 0.35)
T0 = 1_600_000_000 * 10**9  # ns
STORE = get_typestore(Stores.ROS1_NOETIC)  # with tf2_msgs, which it leaves out
STORE.register(get_types_from_msg("geometry_msgs/TransformStamped[] transforms",
                                  "tf2_msgs/msg/TFMessage"))  # fmt: skip
RS = "/device_0/sensor_0/Depth_0"  # a RealSense Viewer recording's depth stream
RS_COLOUR = "/device_0/sensor_1/Color_0"


@pytest.fixture(scope="module")
def scene():
    """(depth (m), PinholeCamera, T_world_cam, rgb, truth (x, y, yaw))."""
    return one_rod_frame(ROD)


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
    fifo = tmp_path / "pipe.bag"  # would block a reader: refused before it is opened
    os.mkfifo(fifo)
    with pytest.raises(CameraFileError, match="FIFO"):
        read_rgbd_bag(fifo)


def _to_ros1(ros2_bag, dst, compress: str | None = None):
    """``ros2_bag`` converted to a ROS 1 bag by rosbags' own converter (rosbags-convert)."""
    from rosbags.convert import convert

    noetic = get_typestore(Stores.ROS1_NOETIC)
    convert([ros2_bag], dst, "", 2, compress, "", noetic, None, [], [], [], [])
    return dst


@pytest.mark.parametrize("compress", [None, "bz2"])
def test_a_robots_ros1_bag_gives_the_same_log_as_its_ros2_bag(tmp_path, compress):
    """Joint states and a wrist sensor's wrenches, written as a ROS 2 bag by the package and
    converted to ROS 1 (chunks plain or bz2-compressed): read back the same, sample by sample."""
    from _logs import rnea_torques, session
    from _payload import panda

    from comgrasp_pin.robot_io import read_log, write_bag
    from comgrasp_pin.robot_io.log_files import WrenchLog, write_wrench_bag
    from comgrasp_pin.robot_io.log_files.wrench_files import read_wrench_bag

    robot = panda()
    Q = np.array([[0.0, -0.3, 0.0, -2.2, 0.0, 2.0, 0.8], [0.5, -0.6, 0.3, -1.8, 1.2, 1.2, -0.6]])
    log = session(Q, rnea_torques(robot, 0.8, np.array([0.02, -0.01, 0.05])),
                  robot.joint_names)[0]  # fmt: skip
    ros2 = write_bag(log, tmp_path / "joints")
    ros1 = _to_ros1(ros2, tmp_path / "joints.bag", compress)
    for back in (read_log(ros1, robot.joint_names), read_log(ros2, robot.joint_names)):
        np.testing.assert_array_equal(back.position, log.position)
        np.testing.assert_array_equal(back.effort, log.effort)
        np.testing.assert_allclose(back.time, log.time, atol=1e-6)
    wrench = np.random.default_rng(1).normal(0, 5, (len(log.time), 6))
    wlog = WrenchLog(log.time, tuple(robot.joint_names), log.position, wrench, "ft_sensor")
    ros1 = _to_ros1(write_wrench_bag(tmp_path / "ft", wlog), tmp_path / "ft.bag", compress)
    back = read_wrench_bag(ros1, robot.joint_names)
    assert back.sensor_frame == "ft_sensor"
    np.testing.assert_array_equal(back.wrench, wrench)
    np.testing.assert_array_equal(back.position, log.position)


def _tf_static(ns: int, chain: list[tuple[str, str, np.ndarray]]):
    """A ROS 1 /tf_static TFMessage of (parent, child, T_parent_child); quaternions by
    Pinocchio."""
    import pinocchio as pin

    T = STORE.types
    stamped = []
    for parent, child, M in chain:
        q = pin.Quaternion(M[:3, :3])
        stamped.append(T["geometry_msgs/msg/TransformStamped"](
            header=_header(ns, parent), child_frame_id=child,
            transform=T["geometry_msgs/msg/Transform"](
                translation=T["geometry_msgs/msg/Vector3"](*map(float, M[:3, 3])),
                rotation=T["geometry_msgs/msg/Quaternion"](x=q.x, y=q.y, z=q.z,
                                                           w=q.w))))  # fmt: skip
    return T["tf2_msgs/msg/TFMessage"](transforms=stamped)


def test_a_wrist_cameras_ros1_bag_gives_the_side_view_with_its_pose_from_tf_static(
    tmp_path, capsys
):
    """A held rod seen by the wrist camera (a MuJoCo render at the measurement pose), recorded
    as a ROS 1 bag with the camera's mount on /tf_static (tool0 -> camera_link ->
    camera_depth_optical_frame): ``views --bag --view side --ee-frame tool0`` composes the
    camera's pose in the ee frame and measures the tilt as the library does on the render,
    within the perception contract of the truth."""
    import json

    import pinocchio as pin
    from test_perception import _wrist_frame

    from comgrasp_pin.geometry import tilt_from_level_deg
    from comgrasp_pin.perception import observe_held_rod

    T_ee_obj, T_ee_cam, camera, depth = _wrist_frame("obj2", 10.0)
    library = observe_held_rod(None, depth, camera, T_ee_cam)
    pin.seed(5)
    T_ee_link = pin.SE3.Random().homogeneous  # the mount: any pose; the chain gives T_ee_cam
    mm = np.round(np.where(np.isfinite(depth), depth, 0.0) * 1e3).astype(np.uint16)
    optical = "camera_depth_optical_frame"
    image, info = _image(T0, mm, "16UC1"), _info(T0, camera)
    image.header.frame_id = optical
    chain = [("tool0", "camera_link", T_ee_link),
             ("camera_link", optical, np.linalg.inv(T_ee_link) @ T_ee_cam)]  # fmt: skip
    bag = _write(tmp_path / "wrist.bag", {
        "/camera/depth/image_rect_raw": [(T0, image)],
        "/camera/depth/camera_info": [(T0, info)],
        "/tf_static": [(T0 - 10**9, _tf_static(T0 - 10**9, chain))],
    })  # fmt: skip
    out = tmp_path / "o"
    assert main(["views", "--bag", str(bag), "--view", "side", "--ee-frame", "tool0",
                 "--out", str(out)]) == 0, capsys.readouterr().err  # fmt: skip
    measured = json.loads((out / "wrist.bag_at_0ms_side_view.json").read_text())
    np.testing.assert_allclose(measured["T_ee_cam"], T_ee_cam, atol=1e-9)
    true_tilt = tilt_from_level_deg(np.arctan2(-T_ee_obj[2, 0], T_ee_obj[0, 0]))
    assert abs(measured["tilt_from_level_deg"] - true_tilt) < 1.0
    assert abs(measured["tilt_from_level_deg"] - tilt_from_level_deg(library.theta)) < 0.2
    assert abs(measured["grasp_offset_m"] - library.grasp_offset) < 2e-3


@pytest.mark.parametrize(
    ("image", "infos", "chosen"),
    [
        ("/camera/aligned_depth_to_color/image_raw",  # ROS drivers: the sibling
         ["/camera/aligned_depth_to_color/camera_info", "/camera/color/camera_info"],
         "/camera/aligned_depth_to_color/camera_info"),
        ("/device_0/sensor_0/Depth_0/image/data",  # a RealSense recording: beside it
         [f"{RS}/info/camera_info", f"{RS_COLOUR}/info/camera_info"], f"{RS}/info/camera_info"),
        ("/a/b/image", ["/a/x/camera_info", "/a/y/camera_info"], None),  # two as near: none
        ("/a/b/image", ["/a/x/camera_info"], "/a/x/camera_info"),
        ("/depth/image", ["/color/camera_info"], None),  # only the bag's root in common
    ],
)  # fmt: skip
def test_the_camera_info_nearest_an_image_in_the_topics_tree(image, infos, chosen):
    from types import SimpleNamespace

    from comgrasp_pin.perception.frames.bag_topics import _nearest

    found = _nearest([SimpleNamespace(topic=t) for t in infos], image)
    assert (found.topic if found else None) == chosen
