"""A real camera's intrinsics as its driver gives them, and its images undistorted.

Perception measures in undistorted pinhole images (``PinholeCamera``). A camera's
intrinsics arrive as a 3x3 K, as a RealSense ``rs2_intrinsics`` (fx, fy, ppx, ppy, width,
height, model, coeffs) or as a ROS ``sensor_msgs/CameraInfo`` (width, height, k, d,
distortion_model; ROS 1's K and D too) or its camera_calibration YAML (image_width,
image_height, camera_matrix, distortion_model, distortion_coefficients). Where the lens
model has non-zero coefficients, the images are undistorted with OpenCV onto the same K:
colour bilinearly, depth with the nearest pixel (no depth blended across an edge; a z-depth
stays the same where its pixel moves), pixels that see nothing of the lens' image lost (0).
The rectification R and projection P of a stereo pair are not used.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import cv2
import numpy as np

from comgrasp_pin import validate
from comgrasp_pin.camera import PinholeCamera
from comgrasp_pin.errors import CameraFileError, InvalidInputError

# The lens models OpenCV undistorts, by name (ROS's, RealSense's), and their coefficients.
OPENCV_MODELS = {"plumb_bob": (4, 5, 8, 12, 14), "rational_polynomial": (8,),
                 "brown_conrady": (5,), "inverse_brown_conrady": (5,),
                 "equidistant": (4,), "kannala_brandt4": (4,)}  # fmt: skip
FISHEYE = ("equidistant", "kannala_brandt4")
YAML_MODELS = ("none", *OPENCV_MODELS)  # the models a camera_calibration YAML may name
REALSENSE = ("fx", "fy", "ppx", "ppy", "width", "height")
CAMERA_INFO = ("k", "width", "height")
CALIBRATION_YAML = ("camera_matrix", "image_width", "image_height")
AUTOLAB = ("_fx", "_fy", "_cx", "_cy", "_width", "_height")  # autolab_core's .intr (Dex-Net)
_ATTRIBUTES = (*REALSENSE, "model", "coeffs", "k", "d", "K", "D", "distortion_model")


@dataclass(frozen=True, eq=False)
class CameraModel:
    """Intrinsics with a lens model, in the OpenCV convention (x right, y down, z forward).

    Attributes:
        width, height: image size (px).
        K: (3, 3) intrinsic matrix (px), no skew.
        distortion_model: the lens model's name (ROS's or RealSense's; "none" for none).
        D: (n,) its coefficients (OpenCV's order: k1, k2, p1, p2[, k3, ...]; k1..k4 for
            equidistant). All zero (or empty): a pinhole camera.
    """

    width: int
    height: int
    K: np.ndarray
    distortion_model: str = "none"
    D: np.ndarray = field(default_factory=lambda: np.zeros(0))

    def __post_init__(self) -> None:
        validate.integer(self.width, "width (px)", low=1)
        validate.integer(self.height, "height (px)", low=1)
        K = validate.finite_array(self.K, "K", (3, 3))
        if K[0, 1] != 0 or K[1, 0] != 0 or K[2].tolist() != [0, 0, 1] or min(K[0, 0], K[1, 1]) <= 0:
            raise InvalidInputError(
                f"K must be [[fx, 0, cx], [0, fy, cy], [0, 0, 1]] with fx, fy > 0, got {K.tolist()}"
            )
        D = validate.real_array(self.D, "D (distortion coefficients)").reshape(-1)
        if not np.all(np.isfinite(D)):
            raise InvalidInputError(f"D (distortion coefficients) must be finite, got {D}")
        name = str(self.distortion_model).strip().lower().removeprefix("distortion.")
        if np.any(D != 0):
            if name not in OPENCV_MODELS:
                raise InvalidInputError(
                    f"distortion model {self.distortion_model!r} with non-zero coefficients is "
                    f"not one OpenCV undistorts; valid: {', '.join(OPENCV_MODELS)} (or all "
                    "coefficients 0)"
                )
            if len(D) not in OPENCV_MODELS[name]:
                raise InvalidInputError(
                    f"the {name} model takes {' or '.join(map(str, OPENCV_MODELS[name]))} "
                    f"coefficients, got {len(D)}"
                )
        object.__setattr__(self, "K", K)
        object.__setattr__(self, "D", D)
        object.__setattr__(self, "distortion_model", name or "none")

    @property
    def distorted(self) -> bool:
        """Whether the images need undistorting (some coefficient is not 0)."""
        return bool(np.any(self.D != 0))

    @property
    def pinhole(self) -> PinholeCamera:
        """The camera of the undistorted images."""
        K = self.K
        return PinholeCamera(self.width, self.height, K[0, 0], K[1, 1], K[0, 2], K[1, 2])

    def undistortion_maps(self) -> tuple[np.ndarray, np.ndarray]:
        """(map_x, map_y), (H, W) float32: the source pixel of each undistorted pixel."""
        size = (self.width, self.height)
        if self.distortion_model in FISHEYE:
            return cv2.fisheye.initUndistortRectifyMap(self.K, self.D[:4], np.eye(3), self.K,
                                                       size, cv2.CV_32FC1)  # fmt: skip
        if self.distortion_model == "inverse_brown_conrady":
            # RealSense's inverse model maps distorted pixels to undistorted ones: the source
            # of an undistorted pixel is that map's inverse, which undistortPoints solves.
            v, u = np.mgrid[0 : self.height, 0 : self.width].astype(np.float32)
            uv = np.stack([u.ravel(), v.ravel()], axis=-1)[:, None]
            src = cv2.undistortPoints(uv, self.K, self.D, P=self.K)
            src = src.reshape(self.height, self.width, 2)
            return src[..., 0].astype(np.float32), src[..., 1].astype(np.float32)
        return cv2.initUndistortRectifyMap(self.K, self.D, None, self.K, size, cv2.CV_32FC1)

    def undistort(self, image: np.ndarray, nearest: bool = False) -> np.ndarray:
        """``image`` (H, W[, C]) undistorted onto K.

        Bilinear, or ``nearest`` (for depth); pixels outside the lens' image are 0 (a depth
        camera's "no depth").
        """
        if not self.distorted:
            return image
        map_x, map_y = self.undistortion_maps()
        flags = cv2.INTER_NEAREST if nearest else cv2.INTER_LINEAR
        return cv2.remap(image, map_x, map_y, flags, borderMode=cv2.BORDER_CONSTANT, borderValue=0)


def camera_model(camera: object, image_shape: tuple[int, ...] | None = None) -> CameraModel:
    """``camera`` as a ``CameraModel``, from any of the forms cameras come in.

    Args:
        camera: a CameraModel or PinholeCamera; a (3, 3) K (then ``image_shape`` gives the
            size); a mapping or an object (``pyrealsense2.intrinsics``, a ROS CameraInfo
            message) with the fields of a RealSense (fx, fy, ppx, ppy, width, height[, model,
            coeffs]), of a CameraInfo (width, height, k or K[, d or D, distortion_model]) or
            of a camera_calibration YAML (image_width, image_height, camera_matrix{data}[,
            distortion_model, distortion_coefficients{data}]) or of autolab_core's .intr
            (_fx, _fy, _cx, _cy, _width, _height[, _skew]; Dex-Net's, GQ-CNN's cameras).
        image_shape: (H, W, ...) of the images, for a bare K.

    Raises:
        InvalidInputError: a form not listed, a missing field (named), a bad value.
    """
    if isinstance(camera, CameraModel):
        return camera
    if isinstance(camera, PinholeCamera):
        return CameraModel(camera.width, camera.height, camera.K)
    if isinstance(camera, (np.ndarray, list, tuple)):
        K = validate.real_array(camera, "camera (K)")
        if K.shape != (3, 3) or image_shape is None:
            raise InvalidInputError(
                f"camera as an array must be a (3, 3) K with the image's size known, got "
                f"shape {K.shape}"
            )
        return CameraModel(int(image_shape[1]), int(image_shape[0]), K)
    fields = _fields(camera)
    if all(k in fields for k in REALSENSE):
        return _from_realsense(fields)
    if all(k in fields for k in CALIBRATION_YAML):
        return _from_calibration_yaml(fields)
    if all(k in fields for k in AUTOLAB):  # a pinhole; a skewed pixel grid is refused (K)
        f = fields
        rows = [[f["_fx"], f.get("_skew", 0.0), f["_cx"]], [0.0, f["_fy"], f["_cy"]], [0, 0, 1]]
        return CameraModel(_int(f, "_width"), _int(f, "_height"),
                           validate.real_array(rows, "_fx, _fy, _cx, _cy, _skew"))  # fmt: skip
    lower = {k.lower(): v for k, v in fields.items()}
    if all(k in lower for k in CAMERA_INFO):
        return CameraModel(
            _int(lower, "width"), _int(lower, "height"), _matrix(lower, "k", 9).reshape(3, 3),
            str(lower.get("distortion_model") or "none"), _matrix(lower, "d", None, default=()),
        )  # fmt: skip
    raise InvalidInputError(
        "camera intrinsics not understood: give a PinholeCamera, a (3, 3) K, or the fields of "
        f"a RealSense ({', '.join(REALSENSE)}[, model, coeffs]), a ROS CameraInfo "
        f"({', '.join(CAMERA_INFO)}[, d, distortion_model]), a camera_calibration YAML "
        f"({', '.join(CALIBRATION_YAML)}[, distortion_model, distortion_coefficients]) or "
        f"autolab_core's .intr ({', '.join(AUTOLAB)}); got "
        f"{type(camera).__name__} with fields {sorted(fields)}"
    )


def _fields(camera: object) -> dict:
    if isinstance(camera, Mapping):
        return dict(camera)
    return {k: getattr(camera, k) for k in _ATTRIBUTES if hasattr(camera, k)}


def _from_realsense(f: dict) -> CameraModel:
    """From ``rs2_intrinsics``' fields; its coefficients are OpenCV's order (k1 k2 p1 p2 k3)."""
    K = [[f["fx"], 0.0, f["ppx"]], [0.0, f["fy"], f["ppy"]], [0.0, 0.0, 1.0]]
    coeffs = _matrix(f, "coeffs", None, default=())
    model = str(f.get("model", "none"))
    if np.any(coeffs != 0) and "model" not in f:
        raise InvalidInputError("RealSense intrinsics with non-zero coeffs need their model")
    if model.removeprefix("distortion.") in FISHEYE:
        coeffs = coeffs[:4]  # rs2_intrinsics has 5 slots; the fisheye model uses 4
    return CameraModel(_int(f, "width"), _int(f, "height"), validate.real_array(K, "fx, fy, ppx, "
                       "ppy"), model, coeffs)  # fmt: skip


def _from_calibration_yaml(f: dict) -> CameraModel:
    """From ROS camera_calibration's YAML, read as ROS's ``camera_calibration_parsers`` does.

    K is ``camera_matrix.data`` (row-major 3x3), D ``distortion_coefficients.data`` (rows x
    cols numbers), the size ``image_width`` x ``image_height``. The model is
    ``distortion_model``, or ``camera_model`` (older drivers' name for it; both given must
    agree). Without either, ROS's ``readCalibrationYml`` (ros-perception/image_common,
    camera_calibration_parsers/src/parse_yml.cpp) sets ``distortion_models::PLUMB_BOB``
    "for backwards compatibility" and warns "did not specify distortion model, assuming
    plumb bob"; here that is taken where D has plumb_bob's 5 coefficients (or all are 0: no
    distortion), and any other count is refused rather than guessed.

    Raises:
        CameraFileError: the two keys disagree, a model not in the valid list, no model
            with a count of coefficients other than 5.
    """
    D = _matrix(f, "distortion_coefficients", None, default=())
    names = {k: str(f[k]).strip().lower() for k in ("distortion_model", "camera_model")
             if f.get(k) is not None and str(f[k]).strip()}  # fmt: skip
    valid = ", ".join(YAML_MODELS)
    if len(set(names.values())) > 1:
        raise CameraFileError(
            f"distortion_model {f['distortion_model']!r} and camera_model {f['camera_model']!r} "
            f"disagree: give one lens model, one of {valid}"
        )
    if names:
        model = next(iter(names.values()))
        if model not in YAML_MODELS:
            key = next(iter(names))
            raise CameraFileError(f"{key} {f[key]!r} is not a lens model read here; valid: {valid}")
    elif len(D) == 5:
        model = "plumb_bob"  # as ROS's camera_calibration_parsers assumes
    elif np.any(D != 0):
        raise CameraFileError(
            f"no distortion_model and {len(D)} distortion coefficients: ROS assumes plumb_bob, "
            f"which has 5 here; name the model (distortion_model: one of {valid})"
        )
    else:
        model = "none"
    K = _matrix(f, "camera_matrix", 9).reshape(3, 3)
    return CameraModel(_int(f, "image_width"), _int(f, "image_height"), K, model, D)


def _int(f: dict, key: str) -> int:
    value = f[key]
    if isinstance(value, float) and value.is_integer():
        value = int(value)
    return validate.integer(value, key, low=1)


def _matrix(f: dict, key: str, size: int | None, default=None) -> np.ndarray:
    """Field ``key`` as a flat float array: a list, or a YAML matrix {rows, cols, data}."""
    value = f.get(key, default)
    if value is None:
        if default is None:
            raise InvalidInputError(f"the camera info has no {key}")
        value = default
    if isinstance(value, Mapping):
        if "data" not in value:
            raise InvalidInputError(f"{key} must have a data list (rows, cols, data)")
        rows, cols = value.get("rows"), value.get("cols")
        value = value["data"]
        if rows is not None and cols is not None and np.size(value) != rows * cols:
            raise InvalidInputError(
                f"{key} says rows x cols = {rows} x {cols} but its data has {np.size(value)} "
                "numbers"
            )
    a = validate.real_array(value, key).reshape(-1)
    if size is not None and a.size != size:
        raise InvalidInputError(f"{key} must have {size} numbers (row-major), got {a.size}")
    return a
