"""Frames as cameras deliver them, made into what perception measures in.

Perception measures in float metres of z-depth, RGB colour and an undistorted pinhole
camera. A camera gives depth in its own units (a RealSense's uint16, ``depth_scale``
metres per unit: 0.001 for a D415/D435, 0.0001 for a D405), colour in the order its driver
or library uses (OpenCV's BGR, most others' RGB) and intrinsics with a lens model
(``camera_model``). ``camera_frame`` turns one into the other; a frame already in
perception's form (float depth, RGB, a ``PinholeCamera``) is handed back as it is.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import cast

import numpy as np

from comgrasp_pin import validate
from comgrasp_pin.camera import PinholeCamera
from comgrasp_pin.errors import InvalidDepthError, InvalidInputError
from comgrasp_pin.perception.frames.camera_model import camera_model

COLOR_ORDERS = ("rgb", "bgr")

Colour = np.ndarray | Callable[[], np.ndarray] | None


def metric_depth(
    depth: object, depth_scale: float | None = None, name: str = "depth"
) -> np.ndarray:
    """``depth`` in metres: ``depth * depth_scale``, or ``depth`` itself (float metres).

    Args:
        depth: (H, W) z-depth: integers in the camera's units (0: no depth), or floats.
        depth_scale: metres per unit (the camera SDK's depth scale, e.g. 0.001 for
            millimetres); required for an integer image, and applied to a float one too.
        name: the argument's name in messages.

    Raises:
        InvalidDepthError: an integer image without ``depth_scale``.
        InvalidInputError: a ``depth_scale`` that is not finite and > 0; complex, boolean,
            string or object values (with a ``depth_scale``; without, perception refuses
            them with an InvalidDepthError).
    """
    try:
        kind = np.asarray(depth).dtype.kind
    except (TypeError, ValueError):
        raise InvalidDepthError(f"the {name} image is not a numeric array") from None
    if depth_scale is None:
        if kind in "iu":
            raise InvalidDepthError(
                f"the {name} image is integers ({np.asarray(depth).dtype}): pass depth_scale, "
                "the metres per unit of the camera's depth (its SDK's depth scale: 0.001 for "
                "millimetres, as a RealSense D415/D435; 0.0001 for a D405); a float image is "
                "taken as metres"
            )
        return cast(np.ndarray, depth)  # float metres, checked by the perception that takes it
    scale = validate.number(depth_scale, "depth_scale (m per unit)", low=0.0, low_open=True)
    return validate.real_array(depth, name) * scale


def rgb_of(colour: Colour, color_order: str = "rgb") -> Colour:
    """``colour`` (H, W, 3) in RGB order, given in ``color_order`` ("rgb" or "bgr").

    None stays None; a function that takes the image (called only when the colour is
    needed) becomes one that takes it in RGB. BGR is reversed along the channels (a view).

    Raises:
        InvalidInputError: an unknown ``color_order``; a BGR image that is not (H, W, 3).
    """
    validate.choice(color_order, "color_order", COLOR_ORDERS)
    if colour is None or color_order == "rgb":
        return colour
    if callable(colour):
        fetch = colour

        def in_rgb() -> np.ndarray:
            return cast(np.ndarray, rgb_of(fetch(), "bgr"))

        return in_rgb
    image = np.asarray(colour)
    if image.ndim != 3 or image.shape[2] != 3:
        raise InvalidInputError(f"a BGR colour image must be (H, W, 3), got {image.shape}")
    return image[..., ::-1]


def camera_frame(
    rgb: Colour,
    depth: np.ndarray,
    camera: object,
    depth_scale: float | None = None,
    color_order: str = "rgb",
) -> tuple[Colour, np.ndarray, PinholeCamera]:
    """(RGB colour, float depth (m), pinhole camera) of a frame as a camera gives it.

    Args:
        rgb: (H, W, 3) colour registered to the depth (the depth aligned to it), a function
            that takes it, or None.
        depth: (H, W) z-depth; see ``metric_depth``.
        camera: the intrinsics in any form ``camera_model`` takes (K, RealSense's or ROS's
            fields, a PinholeCamera); a lens model with non-zero coefficients undistorts
            both images (depth with the nearest pixel).
        depth_scale: metres per unit of ``depth`` (see ``metric_depth``).
        color_order: "rgb" or "bgr", the order of ``rgb``'s channels.

    A frame in perception's form (a PinholeCamera, no depth_scale, RGB) is returned as it
    is, the same objects: the simulator's renders take no extra step.
    """
    colour = rgb_of(rgb, color_order)
    if type(camera) is PinholeCamera and depth_scale is None:
        return colour, metric_depth(depth), camera
    depth_m = metric_depth(depth, depth_scale)
    model = camera_model(camera, np.shape(depth_m))
    if not model.distorted:
        return colour, depth_m, model.pinhole
    shape = (model.height, model.width)
    if np.shape(depth_m) != shape:
        raise InvalidDepthError(f"depth image has shape {np.shape(depth_m)}, the camera is {shape}")
    depth_m = model.undistort(np.asarray(depth_m, dtype=float), nearest=True)
    if callable(colour):
        take = colour
        colour = lambda: model.undistort(np.ascontiguousarray(take()))  # noqa: E731
    elif colour is not None:
        image = np.ascontiguousarray(colour)
        if image.shape[:2] != shape:
            raise InvalidDepthError(f"RGB image {image.shape} does not match the camera {shape}")
        colour = model.undistort(image)
    return colour, depth_m, model.pinhole
