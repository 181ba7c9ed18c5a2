"""A still camera's depth frames averaged in time, as a RealSense's temporal filter does.

A stereo camera's depth noise, holes, dropouts and flying pixels are drawn afresh in every
frame; while nothing moves (the arm holding still for a measurement), the frames of the last
fraction of a second show the same scene. Per pixel, the values that some frames lost are
taken from the frames that have one, and the noise of the valid values falls with their
count. Works on any camera's frames (float metres, 0 or inf where a pixel was lost); NumPy
only.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from comgrasp_pin import validate
from comgrasp_pin.errors import InvalidDepthError
from comgrasp_pin.perception.frames.camera_input import metric_depth

AGREE_TOLERANCE = 0.005
"""A frame's depth this far (m) from the pixel's median over the frames is a flyer."""


def average_depth_frames(
    frames: Sequence[np.ndarray],
    tolerance: float = AGREE_TOLERANCE,
    min_valid: int = 1,
    depth_scale: float | None = None,
) -> np.ndarray:
    """(H, W) z-depth (m): per pixel, the mean of the frames' valid values near their median.

    Args:
        frames: N >= 1 depth images (H, W) of a still scene, float metres; 0 or inf where a
            pixel was lost (a camera's "no depth") or nothing was seen.
        tolerance: values farther than this (m) from the pixel's median over the frames are
            left out of its mean (a flying pixel lies between an edge's near and far side
            in one frame, elsewhere in the next).
        min_valid: a pixel valid (finite, > 0) in fewer frames than this is lost.
        depth_scale: metres per unit of the frames (the camera SDK's depth scale), for
            frames in a camera's integer units (0: no depth); None: float metres.

    Per pixel: the median m of its valid values, then the mean of the valid values within
    ``tolerance`` of m (the mean, not the median: a depth given in steps, e.g. 1 mm, is
    dithered by the noise, and the mean of several frames resolves it below a step). A pixel
    valid in no frame is inf if some frame saw nothing there (inf: a dropout in the others
    does not put a surface there), else lost (0); one valid in fewer than ``min_valid``
    frames, or whose values agree with their median in none, is lost (0). One frame: that
    frame (a copy).

    Raises:
        InvalidDepthError: no frame, frames of different shapes, not (H, W), not float
            metres (an integer image is in a camera's depth units: give depth_scale) or
            with NaN.
        InvalidInputError: a tolerance that is not finite and > 0, a ``min_valid`` < 1.
    """
    tolerance = validate.number(tolerance, "tolerance (m)", low=0.0, low_open=True)
    min_valid = validate.integer(min_valid, "min_valid", low=1)
    stack = _stack(frames, depth_scale)
    valid = np.isfinite(stack) & (stack > 0)
    count = valid.sum(axis=0)
    ordered = np.sort(np.where(valid, stack, np.inf), axis=0)  # valid values first
    low = np.take_along_axis(ordered, np.maximum(count - 1, 0)[None] // 2, axis=0)[0]
    high = np.take_along_axis(ordered, (count // 2)[None], axis=0)[0]
    median = np.where(count % 2 == 1, high, 0.5 * (low + high))
    with np.errstate(invalid="ignore"):  # inf - inf where a pixel has no valid value
        agree = valid & (np.abs(stack - median) <= tolerance)
    kept = agree.sum(axis=0)
    total = np.where(agree, stack, 0.0).sum(axis=0)
    with np.errstate(invalid="ignore", divide="ignore"):
        out = total / kept
    out[(count < min_valid) | (kept == 0)] = 0.0
    out[(count == 0) & np.any(stack == np.inf, axis=0)] = np.inf
    return out


def _stack(frames: Sequence[np.ndarray], depth_scale: float | None) -> np.ndarray:
    """(N, H, W) float stack of ``frames`` in metres, checked (see ``average_depth_frames``)."""
    if isinstance(frames, np.ndarray) and frames.ndim == 2:
        frames = [frames]
    try:
        items = list(frames)
    except TypeError:
        raise InvalidDepthError("frames must be a sequence of (H, W) depth images") from None
    if not items:
        raise InvalidDepthError("no depth frame to average")
    arrays = []
    for k, frame in enumerate(items):
        a = validate.real_array(metric_depth(frame, depth_scale, f"depth frame {k}"),
                                f"depth frame {k}")  # fmt: skip
        if a.ndim != 2 or a.shape != np.shape(items[0]):
            raise InvalidDepthError(
                f"depth frame {k} has shape {a.shape}; every frame must be the same (H, W), "
                f"frame 0 is {np.shape(items[0])}"
            )
        if np.isnan(a).any():
            raise InvalidDepthError(f"depth frame {k} contains NaN (use 0 or inf for lost)")
        arrays.append(a.astype(float, copy=False))
    return np.stack(arrays)
