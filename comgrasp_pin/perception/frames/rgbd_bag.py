"""An RGBD frame from a ROS 2 bag, as camera drivers record it (REP 118).

Read with ``rosbags`` (the bag's folder, .db3 or .mcap):

- the depth: ``sensor_msgs/msg/Image`` in ``16UC1`` (or ``mono16``), millimetres, 0 for
  none, or ``32FC1``, metres (NaN, no return, and -Inf, too near, are lost pixels (0); +Inf,
  nothing in range, is inf); or a ``CompressedImage`` of ``compressedDepth`` of 16UC1;
- the colour, optional: ``Image`` (rgb8, bgr8, rgba8, bgra8, mono8) or ``CompressedImage``
  (JPEG, PNG), registered to the depth (the depth aligned to the colour camera: a
  RealSense's ``aligned_depth_to_color``), both at the camera info's size;
- the camera info: ``sensor_msgs/msg/CameraInfo`` (``k``, ``d``, ``distortion_model``).

Topics are named, or found by type: the depth is the image topic whose first message holds
depth, the colour the other image topic, the camera info the depth topic's sibling
``camera_info``, else the bag's only one; several of a kind, none named: listed, refused.
The frame: the depth image received nearest ``at`` s after the depth topic's first, the
colour nearest it by stamp (within MAX_SKEW), the camera info received nearest it, and the
static transforms (``static_tf``) that give the camera's pose.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from comgrasp_pin import validate
from comgrasp_pin.errors import CameraFileError, ComGraspError
from comgrasp_pin.file_checks import bag_folder
from comgrasp_pin.perception.frames.camera_model import camera_model
from comgrasp_pin.perception.frames.rgbd_files import RgbdFiles, float_depth
from comgrasp_pin.perception.frames.static_tf import Transforms, read_static_tf

IMAGE = "sensor_msgs/msg/Image"
COMPRESSED = "sensor_msgs/msg/CompressedImage"
CAMERA_INFO = "sensor_msgs/msg/CameraInfo"
MAX_SKEW = 0.05  # s: the colour image's stamp at most this far from the depth's
REP118_MM = 0.001  # m per unit of a 16UC1 depth (REP 118)
DEPTH = {"16UC1": "u2", "mono16": "u2", "32FC1": "f4"}  # encoding: its pixels' type
COLOUR = {"rgb8": 3, "bgr8": 3, "rgba8": 4, "bgra8": 4, "mono8": 1}  # encoding: channels
_COMPRESSED_DEPTH_HEADER = 12  # bytes before the PNG (image_transport's ConfigHeader)


@dataclass(frozen=True, eq=False)
class BagFrame:
    """An RGBD frame read from a bag, and where it came from.

    Attributes:
        files: the frame (``RgbdFiles``): a 16UC1 depth in millimetres (``depth_scale``
            0.001), a 32FC1 depth as float32 metres (``depth_scale`` 1).
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

    bag = bag_folder(path, CameraFileError)
    try:
        with AnyReader([bag]) as reader:
            topics = _Topics(reader, bag)
            depth_conn = topics.depth(depth_topic)
            rgb_conn = topics.colour(rgb_topic) if colour else None
            info_conn = topics.info(info_topic, depth_conn)
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
            transforms = read_static_tf(reader)
    except CameraFileError:
        raise
    except Exception as exc:  # rosbags raises its own error types for broken bags
        raise CameraFileError(f"cannot read the bag {bag}: {type(exc).__name__}: {exc}") from None
    depth, scale = _depth(depth_msg, depth_conn.topic)
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


class _Topics:
    """The bag's image and camera-info topics, named or found by type."""

    def __init__(self, reader, bag: Path):
        self.reader, self.bag = reader, bag
        self.images = [c for c in reader.connections if c.msgtype in (IMAGE, COMPRESSED)]
        self._holds_depth = {c.topic: _is_depth(self._first(c)) for c in self.images}

    def _first(self, conn):
        for c, _, raw in self.reader.messages(connections=[conn]):
            return self.reader.deserialize(raw, c.msgtype)
        return None

    def _named(self, topic: str, types: tuple[str, ...]):
        conns = [c for c in self.reader.connections if c.topic == topic]
        if not conns:
            raise CameraFileError(f"bag {self.bag} has no topic {topic!r}; {self._listing()}")
        if conns[0].msgtype not in types:
            raise CameraFileError(f"topic {topic!r} is {conns[0].msgtype}, not {types}")
        return conns[0]

    def _listing(self) -> str:
        topics = {f"{c.topic} ({c.msgtype})" for c in self.reader.connections}
        return f"its topics are {sorted(topics)}"

    def _only(self, found: list, what: str, option: str):
        if len(found) == 1:
            return found[0]
        names = sorted(c.topic for c in found)
        raise CameraFileError(f"bag {self.bag} has {len(found)} {what} topics {names}: name one "
                              f"({option})" if found else f"bag {self.bag} has no {what} topic; "
                              f"{self._listing()}")  # fmt: skip

    def depth(self, topic: str | None):
        if topic is not None:
            conn = self._named(topic, (IMAGE, COMPRESSED))
            if not self._holds_depth[conn.topic]:
                raise CameraFileError(f"topic {topic!r} holds no depth image (16UC1, 32FC1, "
                                      "compressedDepth)")  # fmt: skip
            return conn
        found = [c for c in self.images if self._holds_depth[c.topic]]
        return self._only(found, "depth image", "--depth-topic, depth_topic=")

    def colour(self, topic: str | None):
        if topic is not None:
            return self._named(topic, (IMAGE, COMPRESSED))
        found = [c for c in self.images if not self._holds_depth[c.topic]]
        return None if not found else self._only(found, "colour image", "--rgb-topic, rgb_topic=")

    def info(self, topic: str | None, depth):
        if topic is not None:
            return self._named(topic, (CAMERA_INFO,))
        found = [c for c in self.reader.connections if c.msgtype == CAMERA_INFO]
        sibling = depth.topic.rsplit("/", 1)[0] + "/camera_info"
        beside = [c for c in found if c.topic == sibling]
        return beside[0] if beside else self._only(found, "camera info",
                                                   "--camera-info-topic, info_topic=")  # fmt: skip


def _is_depth(msg) -> bool:
    if msg is None or hasattr(msg, "encoding"):  # (None: a topic without messages)
        return msg is not None and msg.encoding in DEPTH
    return "compresseddepth" in msg.format.lower()


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
    fields = {"width": int(msg.width), "height": int(msg.height), "k": list(map(float, msg.k)),
              "d": list(map(float, msg.d)), "distortion_model": msg.distortion_model}  # fmt: skip
    try:
        return camera_model(fields)
    except ComGraspError as exc:  # a zero focal length, a bad lens model: said as the bag's
        raise CameraFileError(f"{topic}: {exc}") from None
