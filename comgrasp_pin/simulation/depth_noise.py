"""A rendered depth image as an active-stereo RGBD camera (RealSense class) gives it.

``DepthNoise`` applies ``DepthNoiseConfig`` to each render: axial noise growing with the
square of the depth (patchy, as stereo matching windows make it), a depth-scale error,
holes and flying pixels at depth edges, scattered dropouts (0 or inf), and 1 mm steps. It
also holds the camera's extrinsic calibration error, fixed for the episode. Only the
simulation uses it (``CameraRig.depth``); perception sees the corrupted images and the
calibrated, slightly wrong, camera pose, never the truth.
"""

from __future__ import annotations

import cv2
import numpy as np

from comgrasp_pin.config import DepthNoiseConfig

_FAR = 100.0  # stands in for "no return" in the edge filters (m)
_KERNEL = np.ones((3, 3), np.uint8)


def _rotation_about(axis: np.ndarray, angle: float) -> np.ndarray:
    rvec = (angle * axis / np.linalg.norm(axis)).reshape(3, 1)
    return cv2.Rodrigues(rvec)[0]


class DepthNoise:
    """One camera's depth errors, seeded once per episode.

    Attributes:
        config: the error model.
        scale: the depth's scale factor in this episode (1 + N(0, scale_std)).
        T_cam_calibrated: (4, 4) the camera frame the robot's calibration gives, in the true
            camera frame: ``T_world_cam_true @ T_cam_calibrated`` is what the robot believes.
    """

    def __init__(self, config: DepthNoiseConfig, seed: int | tuple[int, ...] | None = None):
        self.config = config
        self._rng = np.random.default_rng(seed)
        c, rng = config, self._rng
        self.scale = 1.0 + c.scale_std * float(rng.standard_normal())
        self.T_cam_calibrated = np.eye(4)
        if c.extrinsic_turn_deg > 0:
            R = _rotation_about(rng.standard_normal(3), np.radians(c.extrinsic_turn_deg))
            self.T_cam_calibrated[:3, :3] = R
        if c.extrinsic_shift > 0:
            direction = rng.standard_normal(3)
            self.T_cam_calibrated[:3, 3] = c.extrinsic_shift * direction / np.linalg.norm(direction)

    def apply(self, depth: np.ndarray, stride: int = 1) -> np.ndarray:
        """(H, W) corrupted copy of the rendered z-depth (m, inf = no return); lost pixels
        are 0 or inf.

        ``stride`` > 1: ``depth`` holds every stride-th pixel of each row and column of the
        camera's image (``CameraRig.depth`` renders only them), and the errors are drawn for
        these pixels alone, at the camera's scales: the noise's correlation
        (``noise_corr_px``) is ``stride`` times shorter in this image's pixels, and so is the
        edge band, where a pixel beside a depth step lies in the band with probability
        ``edge_band_px / stride`` when that is below 1 (the step can fall anywhere among the
        ``stride`` camera pixels between two of these).
        """
        c = self.config
        finite = np.isfinite(depth) & (depth > 0)
        far = np.where(finite, depth, _FAR).astype(np.float32)
        near_side, far_side = cv2.erode(far, _KERNEL), cv2.dilate(far, _KERNEL)  # float32
        edge = np.subtract(far_side, near_side, dtype=float) > c.edge_jump
        band = -(-c.edge_band_px // stride)  # in this image's pixels, rounded up
        if band > 1:
            size = 2 * band - 1
            edge = cv2.dilate(edge.astype(np.uint8), np.ones((size, size), np.uint8)) > 0
        white = self._white(depth.shape, stride)
        u, mix = self._rng.random(depth.shape), self._rng.random(depth.shape)
        dropped = ~edge & (self._rng.random(depth.shape) < c.dropout_prob)
        if c.edge_band_px < stride:  # a band narrower than this image's pixel
            edge &= self._rng.random(depth.shape) < c.edge_band_px / stride
        out = np.where(finite, depth * self.scale, np.inf)
        if white is not None:
            out += self._axial_noise(white, np.where(finite, depth, 0.0))
        lost = edge & (u < c.edge_hole_prob)
        flying = edge & ~lost & (u < c.edge_hole_prob + c.flying_prob) & (far_side < _FAR)
        near, span = near_side[flying].astype(float), far_side[flying].astype(float)
        out[flying] = self.scale * (near + mix[flying] * (span - near))
        out[lost | (dropped & (mix < 0.5))] = 0.0
        out[dropped & (mix >= 0.5)] = np.inf
        if c.quantum > 0:
            valid = np.isfinite(out) & (out > 0)
            steps = np.round(out / c.quantum)
            steps *= c.quantum
            np.copyto(out, steps, where=valid)
        return out

    def _white(self, shape: tuple[int, ...], stride: int) -> np.ndarray | None:
        """(H, W) float32 unit noise, correlated over ``noise_corr_px`` camera pixels (a
        Gaussian blur's sigma), on every ``stride``-th camera pixel of each row and column;
        None without axial noise.

        On the sampled pixels the blurred field's neighbours are ``stride`` camera pixels
        apart: a three-tap kernel (a, 1, a) along rows and columns gives them the camera's
        correlation at that lag (``_lag_correlation``; 2a / (1 + 2a^2) = rho), and the next
        ones about its value two lags away; above rho = 0.5 the blur's sigma divided by
        ``stride`` does.
        """
        c = self.config
        if c.focal_px <= 0 or c.baseline <= 0:
            return None
        white: np.ndarray = self._rng.standard_normal(shape).astype(np.float32)
        if c.noise_corr_px <= 0:
            return white
        rho = _lag_correlation(c.noise_corr_px, stride) if stride > 1 else 1.0
        if rho > 0.5:
            blurred = cv2.GaussianBlur(white, (0, 0), c.noise_corr_px / stride)
        else:
            a = (1.0 - np.sqrt(1.0 - 2.0 * rho**2)) / (2.0 * rho) if rho > 0 else 0.0
            taps = np.array([a, 1.0, a], np.float32)
            blurred = cv2.sepFilter2D(white, -1, taps, taps, borderType=cv2.BORDER_REFLECT_101)
        return blurred / max(float(blurred.std()), 1e-12)

    def _axial_noise(self, white: np.ndarray, depth: np.ndarray) -> np.ndarray:
        """(H, W) noise of RMS depth^2 * subpixel / (focal_px * baseline) (m), from the unit
        noise ``white`` (``_white``)."""
        noise = white.astype(float)
        noise *= self.config.axial_std(1.0)
        noise *= depth
        noise *= depth
        return noise


def _lag_correlation(sigma_px: float, lag: int) -> float:
    """The correlation of white noise blurred by OpenCV's Gaussian of ``sigma_px`` between
    pixels ``lag`` apart along a row (its kernel's autocorrelation)."""
    size = int(round(sigma_px * 8 + 1)) | 1  # the kernel size GaussianBlur takes for float32
    g = cv2.getGaussianKernel(size, sigma_px, cv2.CV_64F).ravel()
    if lag >= size:
        return 0.0
    return float(g[lag:] @ g[: size - lag] / (g @ g))
