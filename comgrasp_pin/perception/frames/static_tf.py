"""A camera's pose from a bag's static transforms (``/tf_static``, tf2's TFMessage).

A camera fixed above the table, or on the wrist, is tied to the robot by static transforms
that ``robot_state_publisher`` and the camera's driver publish once, latched, and that
``ros2 bag record`` keeps on ``/tf_static``. The pose of the camera's image frame (the
images' ``header.frame_id``, REP 103's optical frame: z forward, x right, y down) in any
frame of that tree is the product of the transforms along the path between them.
"""

from __future__ import annotations

from collections import deque

import numpy as np

from comgrasp_pin.errors import CameraFileError
from comgrasp_pin.geometry import invert_transform, transform_from_quaternion

TF_STATIC = "/tf_static"
TF_MESSAGE = "tf2_msgs/msg/TFMessage"

Transforms = dict[tuple[str, str], np.ndarray]  # (parent, child): T_parent_child


def read_static_tf(reader) -> Transforms:
    """Every transform on an open bag's ``/tf_static`` (the last of each pair); {} without."""
    conns = [c for c in reader.connections if c.topic == TF_STATIC and c.msgtype == TF_MESSAGE]
    transforms: Transforms = {}
    for c, _, raw in reader.messages(connections=conns) if conns else ():  # ([]: every topic)
        for ts in reader.deserialize(raw, c.msgtype).transforms:
            t, q = ts.transform.translation, ts.transform.rotation
            pair = (ts.header.frame_id.lstrip("/"), ts.child_frame_id.lstrip("/"))
            transforms[pair] = transform_from_quaternion([t.x, t.y, t.z], [q.x, q.y, q.z, q.w])
    return transforms


def camera_pose(transforms: Transforms, target: str, camera_frame: str) -> np.ndarray:
    """(4, 4) T_target_cam: the pose of ``camera_frame`` (the images' frame) in ``target``.

    Raises:
        CameraFileError: no static transforms; a frame not among them (the frames named);
            the two not connected; a camera frame that is not an optical one (REP 103's
            ``*_optical_frame``: perception's x right, y down, z forward).
    """
    target, camera_frame = target.lstrip("/"), camera_frame.lstrip("/")
    if not transforms:
        raise CameraFileError(f"the bag has no {TF_STATIC} transforms: give the camera's pose "
                              "as a file (--T-world-cam, --T-ee-cam)")  # fmt: skip
    if not camera_frame.endswith("optical_frame"):
        raise CameraFileError(
            f"the images' frame {camera_frame!r} is not an optical frame (REP 103: "
            "'*_optical_frame', z forward, x right, y down); its pose would turn the image: "
            "give the camera's pose as a file (--T-world-cam, --T-ee-cam)"
        )
    edges: dict[str, list[tuple[str, np.ndarray]]] = {}
    for (parent, child), T in transforms.items():
        edges.setdefault(parent, []).append((child, T))
        edges.setdefault(child, []).append((parent, invert_transform(T)))
    for frame in (target, camera_frame):
        if frame not in edges:
            raise CameraFileError(f"frame {frame!r} is not in the bag's {TF_STATIC}; its frames "
                                  f"are {sorted(edges)}")  # fmt: skip
    found = {target: np.eye(4)}  # frame: T_target_frame, breadth first from the target
    todo = deque([target])
    while todo:
        frame = todo.popleft()
        for other, T_frame_other in edges[frame]:
            if other not in found:
                found[other] = found[frame] @ T_frame_other
                todo.append(other)
    if camera_frame not in found:
        raise CameraFileError(f"the bag's {TF_STATIC} does not connect {target!r} and "
                              f"{camera_frame!r}")  # fmt: skip
    return found[camera_frame]
