"""An RGBD frame saved as files: the depth, a colour PNG or JPEG, a camera info file.

What a user of a depth camera saves: the depth aligned to the colour as a single-channel
16-bit PNG in the camera's units (a RealSense's millimetres, or 0.1 mm for a D405), or as
floats in metres (a 32-bit TIFF, or Dex-Net's .npy), the colour image, and the camera's
intrinsics as JSON or YAML in one of four layouts (``camera_model``): RealSense's fields
(fx, fy, ppx, ppy, width, height, model, coeffs), a ROS CameraInfo message's (width,
height, k, d, distortion_model), ROS camera_calibration's YAML (image_width, image_height,
camera_matrix, distortion_model, distortion_coefficients), or autolab_core's .intr (_fx,
_fy, _cx, _cy, _width, _height). The camera info may carry ``depth_scale`` (m per unit).
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np
import yaml

from comgrasp_pin import validate
from comgrasp_pin.errors import CameraFileError, InvalidInputError
from comgrasp_pin.perception.frames.camera_input import COLOR_ORDERS
from comgrasp_pin.perception.frames.camera_model import CameraModel, camera_model

MAX_INFO_BYTES = 1_000_000  # a camera info file is a few hundred bytes


@dataclass(frozen=True, eq=False)
class RgbdFiles:
    """An RGBD frame read from files, as the camera gave it.

    Attributes:
        rgb: (H, W, 3) uint8 colour, RGB order; None for a depth read without colour.
        depth: (H, W) uint16 depth in the camera's units (0: no depth), or float32 metres
            (0: no depth; inf: nothing in range).
        depth_scale: metres per unit of ``depth`` (1 for metres).
        camera: the intrinsics with their lens model (not yet undistorted).
    """

    rgb: np.ndarray | None
    depth: np.ndarray
    depth_scale: float
    camera: CameraModel

    @property
    def depth_m(self) -> np.ndarray:
        """(H, W) float z-depth (m), 0 where the camera gave none."""
        return self.depth * self.depth_scale


def read_camera_info(path: str | Path) -> tuple[CameraModel, float | None]:
    """(the camera's intrinsics, its depth_scale or None) from a JSON or YAML file.

    Raises:
        CameraFileError: unreadable, not JSON / YAML, not one
            of the three layouts, a missing or bad field.
    """
    path = Path(path)
    try:
        if path.stat().st_size > MAX_INFO_BYTES:
            raise CameraFileError(f"{path} is {path.stat().st_size} bytes, too large for a "
                                  "camera info file")  # fmt: skip
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise CameraFileError(f"cannot read the camera info {path}: {exc}") from None
    fields = _parse(text, path)
    if not isinstance(fields, dict):
        raise CameraFileError(f"{path} must hold a mapping of fields, got {type(fields).__name__}")
    scale = fields.get("depth_scale")
    try:
        if scale is not None:
            scale = validate.number(scale, "depth_scale (m per unit)", low=0.0, low_open=True)
        return camera_model(fields), scale
    except InvalidInputError as exc:
        raise CameraFileError(f"camera info {path}: {exc}") from None


def _parse(text: str, path: Path) -> object:
    try:
        return json.loads(text)
    except json.JSONDecodeError as json_error:
        if path.suffix.lower() == ".json":
            raise CameraFileError(f"{path} is not valid JSON: {json_error}") from None
    _no_aliases(text, path)
    try:
        return yaml.safe_load(text)
    except yaml.YAMLError as exc:
        raise CameraFileError(f"{path} is neither JSON nor YAML: {exc}") from None


def _no_aliases(text: str, path: Path) -> None:
    """A camera info has no YAML anchors or aliases; refused, they can expand without bound."""
    try:
        tokens = list(yaml.scan(text))
    except yaml.YAMLError as exc:
        raise CameraFileError(f"{path} is neither JSON nor YAML: {exc}") from None
    if any(isinstance(t, (yaml.AnchorToken, yaml.AliasToken)) for t in tokens):
        raise CameraFileError(f"{path}: YAML anchors and aliases (& and *) are not read")


def _read_image(path: Path, what: str) -> np.ndarray:
    if not path.is_file():
        raise CameraFileError(f"the {what} file {path} does not exist")
    image = cv2.imread(str(path), cv2.IMREAD_UNCHANGED)
    if image is None:
        raise CameraFileError(f"cannot read the {what} file {path} as an image (PNG or JPEG)")
    return image


def read_rgbd(
    rgb_path: str | Path | None,
    depth_path: str | Path,
    camera_info_path: str | Path,
    depth_scale: float | None = None,
    color_order: str = "rgb",
) -> RgbdFiles:
    """Read a colour image, the depth and the camera info (see the module).

    Args:
        rgb_path: 8-bit colour PNG or JPEG (grey or with alpha taken too); None: the depth
            alone (``RgbdFiles.rgb`` None).
        depth_path: the depth aligned to the colour image: a single-channel 16-bit PNG in
            the camera's units, a 32-bit float TIFF in metres, or a .npy of either.
        camera_info_path: JSON or YAML, one of the four layouts.
        depth_scale: metres per unit of the depth PNG; else the camera info's
            ``depth_scale``; one of them is needed (never guessed), and where both are
            given they must agree. A float depth is metres unless ``depth_scale`` says
            otherwise.
        color_order: the channels as stored in the colour file: "rgb" (what every image
            writer stores, OpenCV's included) or "bgr" (swapped: a BGR array saved by a
            writer that expects RGB, such as PIL or imageio).

    Raises:
        CameraFileError: unreadable files, a depth that is not one channel of 16-bit
            integers or of floats, a colour that is not 8-bit, sizes that disagree with
            each other or the camera info, no depth_scale or two that differ.
    """
    validate.choice(color_order, "color_order", COLOR_ORDERS)
    camera, info_scale = read_camera_info(camera_info_path)
    depth = _read_depth(Path(depth_path))
    if depth.dtype.kind == "f":
        scale = _float_scale(depth_scale, info_scale, Path(camera_info_path))
    else:
        scale = _depth_scale(depth_scale, info_scale, Path(camera_info_path))
    colour = None
    if rgb_path is not None:
        colour = _read_image(Path(rgb_path), "colour")
        if colour.dtype != np.uint8:
            raise CameraFileError(f"the colour file {rgb_path} must be 8-bit, got {colour.dtype}")
        colour = _as_rgb(colour, color_order)
    shape = (camera.height, camera.width)
    for what, image in (("depth", depth), ("colour", colour)):
        if image is None:
            continue
        if image.shape[:2] != shape:
            raise CameraFileError(
                f"the {what} image is {image.shape[1]} x {image.shape[0]} px, the camera info "
                f"says {camera.width} x {camera.height}: the depth must be aligned to the "
                "colour camera and both saved at its size"
            )
    return RgbdFiles(colour, depth, scale, camera)


def _read_depth(path: Path) -> np.ndarray:
    """(H, W) uint16 in the camera's units, or float32 metres (NaN and -inf lost: 0).

    From a 16-bit PNG, a 32-bit float TIFF, or a NumPy .npy of either (H, W[, 1]).
    """
    if path.suffix.lower() == ".npy":
        try:
            depth = np.load(path, allow_pickle=False)
        except (OSError, ValueError) as exc:
            raise CameraFileError(f"cannot read the depth file {path} as .npy: {exc}") from None
        if depth.ndim == 3 and depth.shape[2] == 1:  # Dex-Net's (H, W, 1)
            depth = depth[..., 0]
    else:
        depth = _read_image(path, "depth")
    if depth.ndim == 2 and depth.dtype.kind == "f":
        return float_depth(depth)
    if depth.dtype != np.uint16 or depth.ndim != 2:
        channels = 1 if depth.ndim == 2 else depth.shape[2]
        raise CameraFileError(
            f"the depth file {path} must be one channel of 16-bit integers in the camera's "
            f"units (a PNG or .npy) or of floats in metres (a TIFF or .npy), got {channels} "
            f"channel(s) of {depth.dtype}"
        )
    return depth


def float_depth(depth: np.ndarray) -> np.ndarray:
    """A float depth (m) as float32 with NaN and -inf lost (0); +inf stays.

    As REP 117 means them: no return, too near, nothing in range.
    """
    depth = depth.astype(np.float32)
    depth[np.isnan(depth) | (depth == -np.inf)] = 0.0
    return depth


def _float_scale(given: float | None, in_info: float | None, info_path: Path) -> float:
    """Metres per unit of a float depth: ``given``, else 1 (REP 118's and Dex-Net's metres).

    A camera info's depth_scale other than 1 is for integer units: refused.
    """
    if given is not None:
        return validate.number(given, "depth_scale (m per unit)", low=0.0, low_open=True)
    if in_info is not None and in_info != 1.0:
        raise CameraFileError(
            f"the depth file holds floats, metres by convention, but {info_path} says "
            f"depth_scale {in_info} (for integer units): pass the float depth's own scale "
            "(--depth-scale 1 for metres)"
        )
    return 1.0


def _depth_scale(given: float | None, in_info: float | None, info_path: Path) -> float:
    if given is not None:
        given = validate.number(given, "depth_scale (m per unit)", low=0.0, low_open=True)
    if given is None and in_info is None:
        raise CameraFileError(
            f"no depth_scale: pass it (metres per unit of the depth PNG: 0.001 for millimetres, "
            f"a RealSense D415/D435's; 0.0001 for a D405) or put it in {info_path}"
        )
    if given is not None and in_info is not None and not np.isclose(given, in_info, rtol=1e-9):
        raise CameraFileError(f"depth_scale {given} given, but {info_path} says {in_info}")
    if given is not None:
        return given
    assert in_info is not None  # refused above when both are None
    return in_info


def _as_rgb(image: np.ndarray, color_order: str) -> np.ndarray:
    """OpenCV's decoded image (BGR, BGRA or grey) as RGB, given the file's channel order."""
    if image.ndim == 2:
        return cv2.cvtColor(image, cv2.COLOR_GRAY2RGB)
    if image.shape[2] == 4:
        image = cv2.cvtColor(image, cv2.COLOR_BGRA2BGR)
    # OpenCV decodes a standard file to BGR; a file holding BGR in its RGB slots decodes to RGB.
    return image if color_order == "bgr" else cv2.cvtColor(image, cv2.COLOR_BGR2RGB)
