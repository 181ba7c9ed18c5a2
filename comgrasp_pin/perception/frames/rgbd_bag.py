"""An RGBD frame from a ROS bag, as camera drivers record it (REP 118).

Read with ``rosbags``: a ROS 2 bag (its folder, .db3 or .mcap) or a ROS 1 ``.bag`` file
(``rosbag record``'s, or a RealSense Viewer recording's):

- the depth: ``sensor_msgs/msg/Image`` in ``16UC1`` (or ``mono16``), millimetres, 0 for
  none (a RealSense recording's own ``Depth_Units`` where it holds them), or ``32FC1``,
  metres (NaN, no return, and -Inf, too near, are lost pixels (0); +Inf, nothing in
  range, is inf); or a ``CompressedImage`` of ``compressedDepth`` of 16UC1;
- the colour, optional: ``Image`` (rgb8, bgr8, rgba8, bgra8, mono8) or ``CompressedImage``
  (JPEG, PNG), registered to the depth (the depth aligned to the colour camera: a
  RealSense's ``aligned_depth_to_color``), both at the camera info's size; a colour
  topic whose own camera info differs from the depth's is not registered: refused;
- the camera info: ``sensor_msgs/msg/CameraInfo`` (``k``, ``d``, ``distortion_model``;
  ROS 1's ``K``, ``D``).

Which topic is which: ``bag_topics``. The frame: the depth image received nearest ``at`` s
after the depth topic's first, the colour nearest it by stamp (within MAX_SKEW), the
camera info received nearest it, and the static transforms (``static_tf``) that give the
camera's pose.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from comgrasp_pin import validate
from comgrasp_pin.errors import CameraFileError, ComGraspError
from comgrasp_pin.file_checks import ros_bag
from comgrasp_pin.perception.frames.bag_topics import DEPTH, BagTopics
from comgrasp_pin.perception.frames.camera_model import camera_model
from comgrasp_pin.perception.frames.rgbd_files import RgbdFiles, float_depth
from comgrasp_pin.perception.frames.static_tf import Transforms, read_static_tf

MAX_SKEW = 0.05  # s: the colour image's stamp at most this far from the depth's
REP118_MM = 0.001  # m per unit of a 16UC1 depth (REP 118)
COLOUR = {"rgb8": 3, "bgr8": 3, "rgba8": 4, "bgra8": 4, "mono8": 1}  # encoding: channels
_COMPRESSED_DEPTH_HEADER = 12  # bytes before the PNG (image_transport's ConfigHeader)


@dataclass(frozen=True, eq=False)
class BagFrame:
    """An RGBD frame read from a bag, and where it came from.

    Attributes:
        files: the frame (``RgbdFiles``): a 16UC1 depth in millimetres (``depth_scale``
            0.001, or a RealSense recording's ``Depth_Units``), a 32FC1 depth as float32
            metres (``depth_scale`` 1).
        depth_topic, rgb_topic, info_topic: the topics read (``rgb_topic`` None: no colour).
        time_s: the depth image's receive time, s after the depth topic's first.
        skew_s: the colour's header stamp less the depth's (s; 0 without colour).
        frame_id: the depth image's frame (its ``header.frame_id``).
        transforms: the bag's ``/tf_static`` (``static_tf.camera_pose``); {} without.
    """

    files: RgbdFiles
    depth_topic: str
    rgb_topic: str | None
    info_topic: str
    time_s: float
    skew_s: float
    frame_id: str
    transforms: Transforms


def read_rgbd_bag(
    path: str | Path,
    at: float = 0.0,
    depth_topic: str | None = None,
    rgb_topic: str | None = None,
    info_topic: str | None = None,
    colour: bool = True,
    depth_scale: float | None = None,
) -> BagFrame:
    """The RGBD frame at ``at`` s into the bag's depth topic (see the module).

    ``colour`` False: the depth alone, whatever the bag holds. ``depth_scale``: metres per
    unit of the depth, where the driver does not follow REP 118 (a D405's 0.1 mm in
    16UC1); else 0.001 for 16UC1, 1 for 32FC1.

    Raises:
        CameraFileError: the bag cannot be read; a topic missing, of another type, or
            several and none named (listed); an encoding that is neither depth nor colour;
            no colour image within MAX_SKEW of the depth; sizes that disagree (the depth not
            aligned to the colour); a binned or cropped camera info.
    """
    at = validate.number(at, "at (s)", low=0.0)
    from rosbags.highlevel import AnyReader

    bag = ros_bag(path, CameraFileError)
    try:
        with AnyReader([bag]) as reader:
            topics = BagTopics(reader, bag)
            depth_conn = topics.depth(depth_topic)
            rgb_conn = topics.colour(rgb_topic) if colour else None
            info_conn = topics.info(info_topic, depth_conn)
            units = topics.depth_units(depth_conn)
            times = _receive_times(reader, depth_conn)
            if at > (span := (times[-1] - times[0]) / 1e9) + 0.5:
                raise CameraFileError(f"at = {at:g} s is past the depth topic "
                                      f"{depth_conn.topic!r}: it spans {span:.2f} s")  # fmt: skip
            t_depth, depth_msg = _received_nearest(reader, depth_conn, times[0] + round(at * 1e9),
                                                   times)  # fmt: skip
            rgb, skew = None, 0.0
            if rgb_conn is not None:
                rgb_msg, skew = _paired(reader, rgb_conn, t_depth, _stamp(depth_msg), bag)
                rgb = _colour(rgb_msg, rgb_conn.topic)
            info = _received_nearest(reader, info_conn, t_depth)[1]
            own = None if rgb_conn is None else topics.info_near(rgb_conn)
            if own is not None and own.topic != info_conn.topic:
                _check_registered(_received_nearest(reader, own, t_depth)[1], own.topic, info,
                                  info_conn.topic)  # fmt: skip
            transforms = read_static_tf(reader)
    except CameraFileError:
        raise
    except Exception as exc:  # rosbags raises its own error types for broken bags
        raise CameraFileError(f"cannot read the bag {bag}: {type(exc).__name__}: {exc}") from None
    depth, scale = _depth(depth_msg, depth_conn.topic)
    if units is not None and depth.dtype.kind == "u":
        scale = validate.number(units, f"{depth_conn.topic}'s Depth_Units (m per unit)",
                                low=0.0, low_open=True)  # fmt: skip
    if depth_scale is not None:
        scale = validate.number(depth_scale, "depth_scale (m per unit)", low=0.0, low_open=True)
    camera = _camera(info, info_conn.topic)
    for what, image in (("depth", depth), ("colour", rgb)):
        if image is not None and image.shape[:2] != (camera.height, camera.width):
            raise CameraFileError(
                f"the {what} image is {image.shape[1]} x {image.shape[0]} px, the camera info "
                f"({info_conn.topic}) says {camera.width} x {camera.height}: record the depth "
                "aligned to the colour camera with that camera's info (a RealSense's "
                "aligned_depth_to_color topics)"
            )
    return BagFrame(RgbdFiles(rgb, depth, scale, camera), depth_conn.topic,
                    None if rgb_conn is None else rgb_conn.topic, info_conn.topic,
                    (t_depth - times[0]) / 1e9, skew, depth_msg.header.frame_id,
                    transforms)  # fmt: skip


def _check_registered(own, own_topic: str, info, info_topic: str) -> None:
    """Refuse a colour image whose own camera info ``own`` differs from the depth's."""
    sizes = (own.width, own.height) == (info.width, info.height)
    if not (sizes and np.allclose(_field(own, "k"), _field(info, "k"), rtol=1e-6, atol=1e-9)):
        raise CameraFileError(
            f"the colour image's camera ({own_topic}: {own.width} x {own.height} px, fx "
            f"{_field(own, 'k')[0]:.1f}) is not the depth's ({info_topic}: {info.width} x "
            f"{info.height} px, fx {_field(info, 'k')[0]:.1f}): the depth is not registered to "
            "the colour. Record the depth aligned to the colour camera (a RealSense's "
            "aligned_depth_to_color), name the topics (--rgb-topic, --camera-info-topic), or "
            "measure from the depth alone (--no-rgb)"
        )


def _field(msg, name: str) -> list[float]:
    """A CameraInfo's ``k`` or ``d`` (ROS 2), or ``K`` or ``D`` (ROS 1), as floats."""
    values = getattr(msg, name) if hasattr(msg, name) else getattr(msg, name.upper())
    return [float(v) for v in values]


def _receive_times(reader, conn) -> list[int]:
    """The topic's messages' receive times (ns), in order; CameraFileError for none."""
    times = [t for _, t, _ in reader.messages(connections=[conn])]
    if not times:
        raise CameraFileError(f"topic {conn.topic!r} has no messages")
    return times


def _received_nearest(reader, conn, t_ns: int, times: list[int] | None = None) -> tuple:
    """(receive time (ns), message) received nearest ``t_ns``; ``times``: the topic's, if read."""
    times_ns = np.array(_receive_times(reader, conn) if times is None else times, np.int64)
    k = int(np.argmin(np.abs(times_ns - t_ns)))
    for i, (c, t, raw) in enumerate(reader.messages(connections=[conn])):
        if i == k:
            return t, reader.deserialize(raw, c.msgtype)
    raise CameraFileError(f"topic {conn.topic!r} changed while read")  # pragma: no cover


def _stamp(msg) -> int:
    return int(msg.header.stamp.sec) * 10**9 + int(msg.header.stamp.nanosec)


def _paired(reader, conn, t_ns: int, stamp_ns: int, bag: Path):
    """(the colour message nearest the depth's stamp ``stamp_ns``, its skew (s)).

    Among those received within a second of the depth (``t_ns``).
    """
    near = [(c, raw) for c, t, raw in reader.messages(connections=[conn])
            if abs(t - t_ns) <= 10**9]  # fmt: skip
    msgs = [reader.deserialize(raw, c.msgtype) for c, raw in near]
    if msgs:
        skews = [(_stamp(m) - stamp_ns) / 1e9 for m in msgs]
        k = int(np.argmin(np.abs(skews)))
        if abs(skews[k]) <= MAX_SKEW:
            return msgs[k], skews[k]
    raise CameraFileError(
        f"bag {bag}: no colour image on {conn.topic!r} within {1e3 * MAX_SKEW:.0f} ms of the "
        "depth image's stamp: give another time (--at), or measure from the depth alone "
        "(--no-rgb)"
    )


def _pixels(msg, dtype: str, channels: int, topic: str) -> np.ndarray:
    """(H, W[, C]) the Image message's pixels in native byte order."""
    dt = np.dtype(dtype).newbyteorder(">" if msg.is_bigendian else "<")
    row = msg.width * channels * dt.itemsize
    data = np.asarray(msg.data, dtype=np.uint8)
    if msg.step < row or len(data) < msg.step * msg.height:
        raise CameraFileError(f"{topic}: a {msg.width} x {msg.height} px {msg.encoding} "
                              f"image holds {len(data)} bytes, step {msg.step}")  # fmt: skip
    rows = data[: msg.step * msg.height].reshape(msg.height, msg.step)[:, :row]
    image = np.ascontiguousarray(rows).view(dt).astype(dt.newbyteorder("="))
    return image.reshape(msg.height, msg.width, channels).squeeze(axis=2) if channels == 1 \
        else image.reshape(msg.height, msg.width, channels)  # fmt: skip


def _depth(msg, topic: str) -> tuple[np.ndarray, float]:
    """(the depth, m per unit): uint16 mm, or float32 m with NaN and -Inf lost (0)."""
    if not hasattr(msg, "encoding"):  # compressedDepth: a ConfigHeader, then a 16-bit PNG
        if not msg.format.lower().startswith(("16uc1", "mono16")):
            raise CameraFileError(f"{topic}: compressedDepth of {msg.format!r} is not read "
                                  "(only 16UC1's); record the raw depth topic")  # fmt: skip
        png = np.asarray(msg.data, dtype=np.uint8)[_COMPRESSED_DEPTH_HEADER:]
        depth = cv2.imdecode(png, cv2.IMREAD_UNCHANGED)
        if depth is None or depth.dtype != np.uint16 or depth.ndim != 2:
            raise CameraFileError(f"{topic}: its compressedDepth does not decode to a 16-bit PNG")
        return depth, REP118_MM
    depth = _pixels(msg, DEPTH[msg.encoding], 1, topic)
    if depth.dtype.kind == "u":
        return depth, REP118_MM
    return float_depth(depth), 1.0


def _colour(msg, topic: str) -> np.ndarray:
    """(H, W, 3) uint8 RGB."""
    if not hasattr(msg, "encoding"):  # image_transport's JPEG or PNG: decoded as BGR
        image = cv2.imdecode(np.asarray(msg.data, dtype=np.uint8), cv2.IMREAD_COLOR)
        if image is None:
            raise CameraFileError(f"{topic}: its {msg.format!r} image does not decode")
        return cv2.cvtColor(image, cv2.COLOR_BGR2RGB)
    if msg.encoding not in COLOUR:
        raise CameraFileError(f"{topic}: encoding {msg.encoding!r} is not read; valid colour "
                              f"encodings are {sorted(COLOUR)}")  # fmt: skip
    image = _pixels(msg, "u1", COLOUR[msg.encoding], topic)
    code = {"bgr8": cv2.COLOR_BGR2RGB, "rgba8": cv2.COLOR_RGBA2RGB,
            "bgra8": cv2.COLOR_BGRA2RGB, "mono8": cv2.COLOR_GRAY2RGB}.get(msg.encoding)  # fmt: skip
    return image if code is None else cv2.cvtColor(image, code)


def _camera(msg, topic: str):
    """The CameraInfo's intrinsics and lens model (``camera_model``)."""
    roi = msg.roi
    if max(msg.binning_x, msg.binning_y) > 1 or (roi.width and roi.height):
        raise CameraFileError(f"{topic}: a binned or cropped camera info (binning, roi) is not "
                              "read; record the full-size images")  # fmt: skip
    fields = {"width": int(msg.width), "height": int(msg.height), "k": _field(msg, "k"),
              "d": _field(msg, "d"), "distortion_model": msg.distortion_model}  # fmt: skip
    try:
        return camera_model(fields)
    except ComGraspError as exc:  # a zero focal length, a bad lens model: said as the bag's
        raise CameraFileError(f"{topic}: {exc}") from None
