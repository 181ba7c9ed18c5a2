"""Video of an episode: the scene camera with both RGBD cameras inset, the CoM drawn on.

The recorder renders while the episode runs and keeps, with each frame, the truth the
overlay needs (the rod's pose and true CoM, the cameras' poses); the overlay is drawn when
the episode is over and its estimate known (``finish``): the estimated CoM with its
+-2 sigma interval along the rod (orange) from the moment it was measured, and the true CoM
(green), projected with each camera's intrinsics and pose. Simulation side: the procedures
never see any of it. Key frames: ``simulation.key_frames``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from comgrasp_pin.camera import PinholeCamera, transform_points
from comgrasp_pin.errors import InvalidInputError, OutputError
from comgrasp_pin.geometry import invert_transform
from comgrasp_pin.perception.draw import com_legend, draw_com, draw_legend, put_text
from comgrasp_pin.simulation.cameras import CameraRig
from comgrasp_pin.simulation.objects import ObjectState
from comgrasp_pin.simulation.sim import Simulation
from comgrasp_pin.simulation.world import SIDE_CAMERA, TOP_CAMERA

SCENE_CAMERA = "demo"
"""The main view: the table, the put-down spot and the drop box (sim/scene.xml)."""


@dataclass(frozen=True)
class FrameState:
    """What the overlay of one frame needs (truth: the simulation side's).

    Attributes:
        time: simulated time (s). caption: the announced phase.
        T_world_obj: (4, 4) the rod's true pose. p_world_com: (3,) its true CoM (m).
        T_world_cam: (4, 4) optical-frame pose of each drawn camera, by name.
    """

    time: float
    caption: str
    T_world_obj: np.ndarray
    p_world_com: np.ndarray
    T_world_cam: dict


@dataclass(frozen=True)
class ComOnRod:
    """The CoM estimate fixed in the rod: drawn where the rod is, from ``since`` on.

    Attributes:
        p_obj: (3,) the estimated CoM in the rod's (true) obj frame (m).
        std: its standard deviation along the rod's axis, obj-x (m).
        since: simulated time from which it is known (s).
        T_world_obj_measured: (4, 4) the rod's true pose when it was measured.
    """

    p_obj: np.ndarray
    std: float
    since: float
    T_world_obj_measured: np.ndarray

    def points_world(self, T_world_obj: np.ndarray) -> np.ndarray:
        """(3, 3) world points: the estimate, and its interval's ends at -2 and +2 sigma."""
        ends = self.p_obj + np.outer([0.0, -2.0, 2.0], [self.std, 0.0, 0.0])
        return transform_points(T_world_obj, ends)


def project(camera: PinholeCamera, T_world_cam: np.ndarray, p_world: np.ndarray):
    """(N, 2) pixels of (N, 3) world points, and (N,) whether each is in front of the
    camera and inside its image."""
    p_cam = transform_points(invert_transform(T_world_cam), p_world)
    front = p_cam[:, 2] > 1e-3
    uv = np.full((len(p_cam), 2), np.nan)
    if front.any():
        uv[front] = camera.project(p_cam[front])
    inside = front & (uv[:, 0] >= 0) & (uv[:, 0] <= camera.width - 1)
    inside &= (uv[:, 1] >= 0) & (uv[:, 1] <= camera.height - 1)
    return uv, inside


class EpisodeRecorder:
    """An observer of a Simulation that renders a composite frame every 1/fps seconds.

    Frames: the "demo" camera (width x height) with the top-down and side views inset at
    ``inset`` of that size on the right; rendered without shadows (four times cheaper on a software
    renderer). ``caption`` is set by the cell (the announced phase); ``finish`` draws the
    overlay and the captions.
    """

    def __init__(self, sim: Simulation, truth: Callable[[], ObjectState], fps: float = 10.0,
                 width: int = 640, height: int = 480, inset: float = 0.4):  # fmt: skip
        self.fps = fps
        self.caption = ""
        self.frames: list[np.ndarray] = []  # raw composites (BGR), no overlay
        self.states: list[FrameState] = []
        self.estimate: ComOnRod | None = None
        self.phases: list[tuple[float, str]] = []
        self._truth = truth
        self._next_t = sim.time
        self._main = CameraRig(sim.model, width, height, shadows=False)
        w, h = int(round(inset * width)), int(round(inset * height))
        self._inset = CameraRig(sim.model, w, h, shadows=False)

    def __call__(self, sim: Simulation) -> None:
        if sim.time + 1e-9 < self._next_t:
            return
        self._next_t += 1.0 / self.fps
        self.frames.append(self.compose(sim))
        truth = self._truth()
        poses = {SCENE_CAMERA: self._main.T_world_cam(sim.data, SCENE_CAMERA),
                 SIDE_CAMERA: self._inset.T_world_cam(sim.data, SIDE_CAMERA)}  # fmt: skip
        self.states.append(FrameState(sim.time, self.caption, truth.T_world_obj.copy(),
                                      truth.p_world_com.copy(), poses))  # fmt: skip

    def inset_origin(self, k: int) -> tuple[int, int]:
        """(x, y) pixel of the top-left corner of inset ``k`` (0: top camera, 1: side)."""
        return self._main.width - self._inset.width - 4, 4 + k * (self._inset.height + 4)

    def compose(self, sim: Simulation) -> np.ndarray:
        """One BGR frame of the current state, without overlay."""
        frame = self._main.rgb(sim.data, SCENE_CAMERA)[:, :, ::-1].copy()
        h, w = self._inset.height, self._inset.width
        for k, camera in enumerate((TOP_CAMERA, SIDE_CAMERA)):
            x0, y0 = self.inset_origin(k)
            frame[y0 : y0 + h, x0 : x0 + w] = self._inset.rgb(sim.data, camera)[:, :, ::-1]
            cv2.rectangle(frame, (x0, y0), (x0 + w - 1, y0 + h - 1), (255, 255, 255), 1)
        return frame

    def finish(self, estimate: ComOnRod | None, phases: list[tuple[float, str]]) -> None:
        """The episode is over: its CoM estimate (None: none was made) and its announced
        phases (time (s), announcement), for the overlay and the captions."""
        self.estimate, self.phases = estimate, list(phases)

    def overlay(self, i: int, scale: float = 1.0, captions: bool = True) -> np.ndarray:
        """Frame ``i`` resized by ``scale``, with the CoM marks (and, with ``captions``,
        the time and phase, and the legend)."""
        frame, state = self.frames[i], self.states[i]
        if scale != 1.0:
            frame = cv2.resize(frame, None, fx=scale, fy=scale, interpolation=cv2.INTER_AREA)
        else:
            frame = frame.copy()
        est = self.estimate if self.estimate and state.time >= self.estimate.since - 1e-9 else None
        points = [state.p_world_com[None]]
        if est is not None:
            points.insert(0, est.points_world(state.T_world_obj))
        p_world = np.vstack(points)
        views = ((SCENE_CAMERA, self._main, (0, 0), 1.0),
                 (SIDE_CAMERA, self._inset, self.inset_origin(1), 1.0))  # fmt: skip
        for camera, rig, origin, size in views:
            uv, ok = project(rig.intrinsics(camera), state.T_world_cam[camera], p_world)
            uv = (uv + origin) * scale
            truth_px = uv[-1] if ok[-1] else None
            est_px = uv[0] if est is not None and ok[0] else None
            bar = uv[1:3] if est is not None and ok[1:3].all() else None
            draw_com(frame, est_px, bar, truth_px, size=size * max(scale, 0.8))
        if captions:
            self._caption(frame, state, scale)
            draw_legend(frame, com_legend(self.estimate is not None), scale=0.45 * scale,
                        corner="top-left")  # fmt: skip
        return frame

    def phase_number(self, time: float) -> tuple[int, int]:
        """(k, n): the phase under way at ``time`` is the k-th (from 1) of the n announced."""
        k = sum(t <= time + 1e-9 for t, _ in self.phases)
        return k, len(self.phases)

    def _caption(self, frame: np.ndarray, state: FrameState, scale: float) -> None:
        k, n = self.phase_number(state.time)
        h = frame.shape[0]
        bar = int(round(26 * scale))
        frame[h - bar :] = (0.35 * frame[h - bar :]).astype(frame.dtype)
        text = f"t = {state.time:5.2f} s" + (f"   {k}/{n}  {state.caption}" if k else "")
        put_text(frame, text, (8 * scale, h - 8 * scale), 0.5 * scale, box=False)

    def write_video(self, path: Path) -> Path:
        """MP4 (MPEG-4 part 2, plays in VLC/ffplay/most players) of the recorded frames."""
        if not self.frames:
            raise InvalidInputError("no frames were recorded")
        h, w = self.frames[0].shape[:2]
        writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"mp4v"), self.fps, (w, h))
        if not writer.isOpened():
            raise OutputError(f"OpenCV cannot write {path}")
        for i in range(len(self.frames)):
            writer.write(self.overlay(i))
        writer.release()
        return path

    def write_strip(self, path: Path, tile_width: int = 400, title: str = "") -> Path:
        """PNG of one key frame per phase (``simulation.key_frames``), under ``title``."""
        from comgrasp_pin.simulation.key_frames import key_frame_strip

        if not self.frames:
            raise InvalidInputError("no frames were recorded")
        strip = key_frame_strip(self, tile_width, title)
        if not cv2.imwrite(str(path), strip, [cv2.IMWRITE_PNG_COMPRESSION, 9]):
            raise OutputError(f"OpenCV cannot write {path}")
        return path

    def close(self) -> None:
        self._main.close()
        self._inset.close()
