"""Perception on RGBD images (OpenCV + NumPy only; no simulator): works on real cameras too.

The top view (``top_down``, reporting a ``RodDetection``), the side view of the rod in the
jaws (``side_view``), the slip monitor, camera input, files and ROS 2 bags (``rgbd_files``,
``rgbd_bag``, ``static_tf``), the overlays (``draw``).

Layer: imports only the shared modules (``camera``, ``geometry``, ``validate``,
``errors``, ``file_checks``): no estimation, no motion, no simulator.
"""

from comgrasp_pin.perception.camera_input import camera_frame
from comgrasp_pin.perception.camera_model import CameraModel, camera_model
from comgrasp_pin.perception.depth_frames import AGREE_TOLERANCE, average_depth_frames
from comgrasp_pin.perception.draw import draw_side_view, draw_top_view
from comgrasp_pin.perception.rgbd_bag import BagFrame, read_rgbd_bag
from comgrasp_pin.perception.rgbd_files import RgbdFiles, read_camera_info, read_rgbd
from comgrasp_pin.perception.side_view import SideView, observe_held_rod
from comgrasp_pin.perception.slip import SlipMonitor, SlipVerdict
from comgrasp_pin.perception.top_down import RodDetection, detect_rod_top_down

__all__ = [
    "AGREE_TOLERANCE",
    "BagFrame",
    "CameraModel",
    "RgbdFiles",
    "RodDetection",
    "SideView",
    "SlipMonitor",
    "SlipVerdict",
    "average_depth_frames",
    "camera_frame",
    "camera_model",
    "detect_rod_top_down",
    "draw_side_view",
    "draw_top_view",
    "observe_held_rod",
    "read_camera_info",
    "read_rgbd",
    "read_rgbd_bag",
]
