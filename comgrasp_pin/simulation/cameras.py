"""Rendering the world's RGBD cameras, headless (``MUJOCO_GL=egl``).

This is the one place where MuJoCo's camera frame (x right, y up, looking along -z) is
converted to the optical frame used by all perception code (x right, y down, z forward).
"""

from __future__ import annotations

import mujoco
import numpy as np

from comgrasp_pin.camera import PinholeCamera

# R_mujococam_optical: flip y and z.
_R_MJ_OPTICAL = np.diag([1.0, -1.0, -1.0])


class CameraRig:
    """Renders RGB, metric depth and ground-truth segmentation of the model's cameras.

    One offscreen context per rig; keep one rig per simulation and reuse it.
    """

    def __init__(self, model: mujoco.MjModel, width: int = 640, height: int = 480):
        self.model = model
        self.width = width
        self.height = height
        self._renderer = mujoco.Renderer(model, height, width)

    def close(self) -> None:
        self._renderer.close()

    def intrinsics(self, camera: str) -> PinholeCamera:
        """Pinhole intrinsics of ``camera`` at the rig's image size."""
        fovy = float(self.model.camera(camera).fovy[0])
        return PinholeCamera.from_fovy(self.width, self.height, fovy)

    def T_world_cam(self, data: mujoco.MjData, camera: str) -> np.ndarray:
        """(4, 4) pose of the camera's optical frame in the world."""
        cam = self.model.camera(camera).id
        T = np.eye(4)
        T[:3, :3] = data.cam_xmat[cam].reshape(3, 3) @ _R_MJ_OPTICAL
        T[:3, 3] = data.cam_xpos[cam]
        return T

    def _render(self, data: mujoco.MjData, camera: str, depth=False, segmentation=False):
        r = self._renderer
        r.disable_depth_rendering()
        r.disable_segmentation_rendering()
        if depth:
            r.enable_depth_rendering()
        if segmentation:
            r.enable_segmentation_rendering()
        r.update_scene(data, camera)
        image = r.render().copy()
        r.disable_depth_rendering()
        r.disable_segmentation_rendering()
        return image

    def rgb(self, data: mujoco.MjData, camera: str) -> np.ndarray:
        """(H, W, 3) uint8 RGB image."""
        return self._render(data, camera)

    def depth(self, data: mujoco.MjData, camera: str) -> np.ndarray:
        """(H, W) float z-depth along the optical axis (m); ``inf`` where nothing is seen."""
        depth = self._render(data, camera, depth=True).astype(float)
        depth[depth >= self.model.vis.map.zfar * self.model.stat.extent * 0.999] = np.inf
        return depth

    def segmentation(self, data: mujoco.MjData, camera: str) -> np.ndarray:
        """(H, W) int geom id per pixel, -1 for background (ground truth: tests only)."""
        seg = self._render(data, camera, segmentation=True)
        ids = seg[:, :, 0].astype(int)
        ids[seg[:, :, 1] != int(mujoco.mjtObj.mjOBJ_GEOM)] = -1
        return ids
