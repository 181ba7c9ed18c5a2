"""Key frames of an episode: one per announced phase, in two rows, each captioned.

A phase's key frame is taken at a fixed fraction of its duration, where it shows what the
phase does (the jaws closed at the end of the trial grasp, the rod just let go at the
start of the drop); a phase shorter than a frame's period has none.
"""

from __future__ import annotations

import cv2
import numpy as np

from comgrasp_pin.perception.draw import com_legend, draw_legend, put_text
from comgrasp_pin.procedures import phases as ph

_AT = {ph.EMPTY_ARM: 0.6, ph.TRIAL_GRASP: 0.8, ph.CAREFUL_LIFT: 0.4, ph.LIFT: 0.5,
       ph.MEASURING: 0.5, ph.PUT_BACK: 0.5, ph.PUT_DOWN: 0.5, ph.REGRASP: 0.8, ph.CARRY: 0.5,
       ph.DROP: 0.1, ph.BASELINE_GRASP: 0.8}  # fmt: skip
"""Where in each phase (0: its start, 1: its end) its key frame is taken."""

_BAR = 52  # caption bar under a tile (px)
_HEADER = 56  # legend bar above the rows (px)


def key_frames(times: np.ndarray, phases: list[tuple[float, str]], end: float) -> list:
    """(frame index, phase number from 1, time (s), announcement) of each phase's key frame.

    ``times``: (n,) the frames' simulated times (s), increasing; ``phases``: (start time
    (s), announcement) in order; ``end``: when the last phase ends (s).
    """
    out = []
    for k, (t0, caption) in enumerate(phases):
        t1 = phases[k + 1][0] if k + 1 < len(phases) else end
        inside = np.flatnonzero((times >= t0 - 1e-9) & (times < t1 - 1e-9))
        if inside.size == 0:
            continue
        target = t0 + _AT.get(ph.phase_of(caption), 0.5) * (t1 - t0)
        i = int(inside[np.argmin(np.abs(times[inside] - target))])
        out.append((i, k + 1, float(times[i]), caption))
    return out


def _tile(frame: np.ndarray, number: int, time: float, caption: str) -> np.ndarray:
    h, w = frame.shape[:2]
    bar = np.zeros((_BAR, w, 3), np.uint8)
    phase, _, detail = caption.partition(":")
    put_text(bar, f"{number}. {phase.strip()}", (8, 21), 0.6, box=False)
    stamp = f"t = {time:.1f} s"
    put_text(bar, stamp, (w - 10 - cv2.getTextSize(stamp, cv2.FONT_HERSHEY_SIMPLEX, 0.55,
             1)[0][0], 21), 0.55, box=False)  # fmt: skip
    put_text(bar, detail.strip(), (8, 44), 0.5, (200, 200, 200), box=False)
    return np.vstack([frame, bar])


def key_frame_strip(recorder, tile_width: int = 400, title: str = "") -> np.ndarray:
    """BGR image: the key frames of ``recorder`` (an ``EpisodeRecorder`` after ``finish``),
    ``tile_width`` px each, in two rows, under a legend bar with ``title``."""
    times = np.array([s.time for s in recorder.states])
    picks = key_frames(times, recorder.phases, recorder.states[-1].time)
    if not picks:  # nothing was announced: the last frame
        picks = [(len(times) - 1, 1, float(times[-1]), recorder.states[-1].caption)]
    scale = tile_width / recorder.frames[0].shape[1]
    tiles = [_tile(recorder.overlay(i, scale, captions=False), k, t, c) for i, k, t, c in picks]
    cols = -(-len(tiles) // 2) if len(tiles) > 1 else 1
    blank = np.zeros_like(tiles[0])
    tiles += [blank] * (2 * cols - len(tiles)) if len(tiles) > 1 else []
    rows = [np.hstack(tiles[r * cols : (r + 1) * cols]) for r in range(len(tiles) // cols)]
    grid = np.vstack(rows)
    header = np.zeros((_HEADER, grid.shape[1], 3), np.uint8)
    legend = com_legend(recorder.estimate is not None)
    put_text(header, title, (8, 34), 0.6, box=False)
    text = "insets: top camera, side camera on the wrist"
    x = grid.shape[1] - 10 - cv2.getTextSize(text, cv2.FONT_HERSHEY_SIMPLEX, 0.5, 1)[0][0]
    put_text(header, text, (x, 34), 0.5, (200, 200, 200), box=False)
    strip = np.vstack([header, grid])
    middle = strip[:_HEADER, grid.shape[1] // 2 - 120 :]  # a view: drawn into the strip
    draw_legend(middle, legend, corner="top-left", scale=0.5)
    return strip
