"""Video of an episode: the scene camera with both RGBD cameras inset, and a key-frame strip."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np

from comgrasp_pin.errors import InvalidInputError, OutputError
from comgrasp_pin.simulation.cameras import CameraRig
from comgrasp_pin.simulation.sim import Simulation
from comgrasp_pin.simulation.world import SIDE_CAMERA, TOP_CAMERA


class EpisodeRecorder:
    """An observer of a Simulation that renders a composite frame every 1/fps seconds.

    Frames: the "scene" camera (width x height) with the top-down and side views inset at a
    third of that size, and ``caption`` (set by the episode code) written on top.
    """

    def __init__(self, sim: Simulation, fps: float = 10.0, width: int = 640, height: int = 480):
        self.fps = fps
        self.caption = ""
        self.frames: list[np.ndarray] = []
        self._next_t = sim.time
        self._main = CameraRig(sim.model, width, height)
        self._inset = CameraRig(sim.model, width // 3, height // 3)

    def __call__(self, sim: Simulation) -> None:
        if sim.time + 1e-9 < self._next_t:
            return
        self._next_t += 1.0 / self.fps
        self.frames.append(self.compose(sim))

    def compose(self, sim: Simulation) -> np.ndarray:
        """One BGR frame of the current state."""
        frame = self._main.rgb(sim.data, "scene")[:, :, ::-1].copy()
        h, w = self._inset.height, self._inset.width
        for k, camera in enumerate((TOP_CAMERA, SIDE_CAMERA)):
            inset = self._inset.rgb(sim.data, camera)[:, :, ::-1]
            x0 = frame.shape[1] - w - 4
            y0 = 4 + k * (h + 4)
            frame[y0 : y0 + h, x0 : x0 + w] = inset
            cv2.rectangle(frame, (x0, y0), (x0 + w - 1, y0 + h - 1), (255, 255, 255), 1)
        text = f"t = {sim.time:5.2f} s  {self.caption}"
        cv2.putText(
            frame, text, (8, 22), cv2.FONT_HERSHEY_SIMPLEX, 0.55, (255, 255, 255), 1, cv2.LINE_AA
        )
        return frame

    def write_video(self, path: Path) -> Path:
        """MP4 (MPEG-4 part 2, plays in VLC/ffplay/most players) of the recorded frames."""
        if not self.frames:
            raise InvalidInputError("no frames were recorded")
        h, w = self.frames[0].shape[:2]
        writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"mp4v"), self.fps, (w, h))
        if not writer.isOpened():
            raise OutputError(f"OpenCV cannot write {path}")
        for frame in self.frames:
            writer.write(frame)
        writer.release()
        return path

    def write_strip(self, path: Path, n: int = 6, width: int = 1500) -> Path:
        """PNG of ``n`` evenly spaced frames side by side (for a README or a report)."""
        if not self.frames:
            raise InvalidInputError("no frames were recorded")
        idx = np.linspace(0, len(self.frames) - 1, n).round().astype(int)
        strip = np.concatenate([self.frames[i] for i in idx], axis=1)
        scale = width / strip.shape[1]
        strip = cv2.resize(strip, None, fx=scale, fy=scale, interpolation=cv2.INTER_AREA)
        cv2.imwrite(str(path), strip)
        return path

    def close(self) -> None:
        self._main.close()
        self._inset.close()
