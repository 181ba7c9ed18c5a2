"""Pinhole cameras in the OpenCV convention: x right, y down, z forward (optical axis).

Pure NumPy: the same code serves a real camera's images and the simulator's. Pixel
coordinates (u, v) have their origin at the centre of the top-left pixel.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from comgrasp_pin import validate
from comgrasp_pin.errors import InvalidInputError
from comgrasp_pin.geometry import check_transform


@dataclass(frozen=True)
class PinholeCamera:
    """Intrinsics of an undistorted pinhole camera.

    Attributes:
        width, height: image size (px).
        fx, fy: focal lengths (px).
        cx, cy: principal point (px).
    """

    width: int
    height: int
    fx: float
    fy: float
    cx: float
    cy: float

    @classmethod
    def from_fovy(cls, width: int, height: int, fovy_deg: float) -> PinholeCamera:
        """Square pixels, principal point at the image centre, vertical field of view."""
        if width <= 0 or height <= 0 or not 0.0 < fovy_deg < 180.0:
            raise InvalidInputError(f"bad camera size {width}x{height} or fovy {fovy_deg} deg")
        f = 0.5 * height / np.tan(np.deg2rad(fovy_deg) / 2.0)
        return cls(width, height, f, f, (width - 1) / 2.0, (height - 1) / 2.0)

    def subsampled(self, stride: int) -> PinholeCamera:
        """The camera of the image ``image[::stride, ::stride]``: pixel (u, v) of that image
        is pixel (stride u, stride v) of the full one."""
        if stride < 1:
            raise InvalidInputError(f"stride must be >= 1, got {stride}")
        return PinholeCamera(
            -(-self.width // stride), -(-self.height // stride),
            self.fx / stride, self.fy / stride, self.cx / stride, self.cy / stride,
        )  # fmt: skip

    @property
    def K(self) -> np.ndarray:
        """(3, 3) intrinsic matrix."""
        return np.array([[self.fx, 0.0, self.cx], [0.0, self.fy, self.cy], [0.0, 0.0, 1.0]])

    def project(self, p_cam: np.ndarray) -> np.ndarray:
        """(N, 2) pixels of (N, 3) points in the camera frame (m); points need z > 0."""
        p_cam = np.atleast_2d(validate.real_array(p_cam, "p_cam"))
        z = p_cam[:, 2]
        if np.any(z <= 0):
            raise InvalidInputError("cannot project points behind the camera (z <= 0)")
        return np.c_[self.fx * p_cam[:, 0] / z + self.cx, self.fy * p_cam[:, 1] / z + self.cy]

    def backproject(self, uv: np.ndarray, depth: np.ndarray) -> np.ndarray:
        """(N, 3) points in the camera frame (m) of pixels ``uv`` (N, 2) at z-depths (N,) (m)."""
        uv = np.atleast_2d(validate.real_array(uv, "uv"))
        depth = validate.real_array(depth, "depth").reshape(-1)
        if uv.shape[0] != depth.shape[0]:
            raise InvalidInputError(f"{uv.shape[0]} pixels but {depth.shape[0]} depths")
        x = (uv[:, 0] - self.cx) / self.fx * depth
        y = (uv[:, 1] - self.cy) / self.fy * depth
        return np.c_[x, y, depth]

    def depth_to_points(self, depth: np.ndarray) -> np.ndarray:
        """(H, W, 3) camera-frame points of a (H, W) z-depth image (m)."""
        if depth.shape != (self.height, self.width):
            raise InvalidInputError(
                f"depth image {depth.shape} does not match camera {(self.height, self.width)}"
            )
        v, u = np.mgrid[0 : self.height, 0 : self.width]
        x = (u - self.cx) / self.fx * depth
        y = (v - self.cy) / self.fy * depth
        return np.stack([x, y, depth], axis=-1)


def transform_points(T_a_b: np.ndarray, p_b: np.ndarray) -> np.ndarray:
    """(N, 3) points p_a = T_a_b @ p_b for (N, 3) points ``p_b``.

    Raises:
        InvalidInputError: T_a_b not a (4, 4) rigid transform, p_b not (N, 3) or (3,).
    """
    T_a_b = check_transform(T_a_b, "T_a_b")
    p_b = np.atleast_2d(validate.real_array(p_b, "p_b"))
    if p_b.ndim != 2 or p_b.shape[1] != 3:
        raise InvalidInputError(f"points must have shape (N, 3), got {p_b.shape}")
    p_a = p_b @ T_a_b[:3, :3].T
    p_a += T_a_b[:3, 3]  # in place: an image's 300 000 points are not copied again
    return p_a
