"""Perception on RGBD images (OpenCV + NumPy only; no simulator): works on real cameras too.

In folders by concept: ``frames`` (what a camera gives: files, ROS bags, intrinsics,
the camera's pose), ``top_view`` (the rod on the table, reported as a ``RodDetection``),
``side_view`` (the rod held in the jaws, a ``SideView``); beside them the slip monitor
(``slip``), the overlays (``draw``) and the steps both views share (``_points``). Every
public name is listed here, in one list.

Layer: imports only the shared modules (``camera``, ``geometry``, ``validate``,
``errors``, ``file_checks``): no estimation, no motion, no simulator.
"""

from comgrasp_pin.perception.draw import draw_side_view, draw_top_view
from comgrasp_pin.perception.frames.camera_input import camera_frame
from comgrasp_pin.perception.frames.camera_model import CameraModel, camera_model
from comgrasp_pin.perception.frames.depth_frames import AGREE_TOLERANCE, average_depth_frames
from comgrasp_pin.perception.frames.rgbd_bag import BagFrame, read_rgbd_bag
from comgrasp_pin.perception.frames.rgbd_files import RgbdFiles, read_camera_info, read_rgbd
from comgrasp_pin.perception.side_view.side_view import SideView, observe_held_rod
from comgrasp_pin.perception.slip import SlipMonitor, SlipVerdict
from comgrasp_pin.perception.top_view.top_down import RodDetection, detect_rod_top_down

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
