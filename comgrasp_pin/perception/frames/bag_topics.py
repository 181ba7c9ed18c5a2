"""Which of a bag's topics hold the depth, the colour and the camera info (``rgbd_bag``).

Named, or found by type: the depth is the image topic whose first message holds depth, the
colour the other image topic; the camera info of an image is the one nearest it in the
topics' tree (its sibling ``camera_info`` as ROS drivers publish it, or a RealSense
recording's ``.../Depth_0/info/camera_info`` beside ``.../Depth_0/image/data``), else the
bag's only one. Several of a kind and none named: listed, refused.
"""

from __future__ import annotations

from pathlib import Path

from comgrasp_pin.errors import CameraFileError

IMAGE = "sensor_msgs/msg/Image"
COMPRESSED = "sensor_msgs/msg/CompressedImage"
CAMERA_INFO = "sensor_msgs/msg/CameraInfo"
DEPTH = {"16UC1": "u2", "mono16": "u2", "32FC1": "f4"}  # a depth image's encoding: its pixels
DEPTH_UNITS = "option/Depth_Units/value"  # a RealSense recording's depth scale (m per unit)


class BagTopics:
    """The bag's image and camera-info topics, named or found by type (see the module)."""

    def __init__(self, reader, bag: Path):
        self.reader, self.bag = reader, bag
        self.images = [c for c in reader.connections if c.msgtype in (IMAGE, COMPRESSED)]
        self.infos = [c for c in reader.connections if c.msgtype == CAMERA_INFO]
        self._holds_depth = {c.topic: _is_depth(self.first(c)) for c in self.images}

    def first(self, conn):
        """The topic's first message, or None for a topic without messages."""
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
        """The depth image's topic: ``topic``, or the only one that holds depth."""
        if topic is not None:
            conn = self._named(topic, (IMAGE, COMPRESSED))
            if not self._holds_depth[conn.topic]:
                raise CameraFileError(f"topic {topic!r} holds no depth image (16UC1, 32FC1, "
                                      "compressedDepth)")  # fmt: skip
            return conn
        found = [c for c in self.images if self._holds_depth[c.topic]]
        return self._only(found, "depth image", "--depth-topic, depth_topic=")

    def colour(self, topic: str | None):
        """The colour image's topic: ``topic``, the only other image topic, or None."""
        if topic is not None:
            return self._named(topic, (IMAGE, COMPRESSED))
        found = [c for c in self.images if not self._holds_depth[c.topic]]
        return None if not found else self._only(found, "colour image", "--rgb-topic, rgb_topic=")

    def info(self, topic: str | None, image):
        """The camera info of ``image``'s topic: ``topic``, or the nearest (see the module)."""
        if topic is not None:
            return self._named(topic, (CAMERA_INFO,))
        return self.info_near(image) or self._only(self.infos, "camera info",
                                                   "--camera-info-topic, info_topic=")  # fmt: skip

    def info_near(self, image):
        """The camera info nearest ``image``'s topic (see the module), or None."""
        return _nearest(self.infos, image.topic)

    def depth_units(self, depth) -> float | None:
        """A RealSense recording's depth scale for the ``depth`` topic's sensor (m per unit).

        Read from ``.../sensor_N/option/Depth_Units/value`` (a Float32, or its text); None
        where the bag has no such topic.
        """
        sensor = depth.topic.split("/")[:3]  # "", "device_0", "sensor_0"
        for conn in self.reader.connections:
            if conn.topic == "/".join([*sensor, DEPTH_UNITS]):
                msg = self.first(conn)
                try:
                    return float(msg.data)
                except (AttributeError, TypeError, ValueError):
                    raise CameraFileError(f"{conn.topic}: its depth units {msg!r} are not a "
                                          "number of metres") from None  # fmt: skip
        return None


def _nearest(found: list, topic: str):
    """The one topic of ``found`` nearest ``topic`` in the topics' tree, or None.

    Its sibling ``camera_info``, else the one topic under its parent, else under its
    parent's parent (``.../Depth_0/image/data`` and ``.../Depth_0/info/camera_info``).
    """
    folders = topic.split("/")[:-1]
    sibling = [c for c in found if c.topic == "/".join([*folders, "camera_info"])]
    if sibling:
        return sibling[0]
    for up in (0, 1):  # under its parent, then under its parent's parent
        prefix = "/".join(folders[: len(folders) - up]) + "/"
        if prefix == "/":  # the whole bag: no nearer than any other
            return None
        near = [c for c in found if c.topic.startswith(prefix)]
        if near:
            return near[0] if len(near) == 1 else None
    return None


def _is_depth(msg) -> bool:
    if msg is None or hasattr(msg, "encoding"):  # (None: a topic without messages)
        return msg is not None and msg.encoding in DEPTH
    return "compresseddepth" in msg.format.lower()
