"""A Rerun recording of an episode (``comgrasp demo --rerun FILE.rrd``; the ``rerun`` extra).

On the ``sim_time`` timeline (simulated seconds): RGB and depth of the top and side cameras
with their poses and intrinsics, the depth back-projected into a coloured point cloud in
the world frame, the rod's true CoM, the joint torque sensor's readings (one series per
joint), and, once the episode is over (``finish``), its phases as a text log, the CoM
estimate with its +-2 sigma interval along the rod and the single-pose CoM line, carried
with the rod. Simulation side: it reads the truth, and the procedures never see it.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np

from comgrasp_pin.camera import PinholeCamera, transform_points
from comgrasp_pin.errors import MissingExtraError
from comgrasp_pin.geometry import invert_transform
from comgrasp_pin.procedures.measurement import TrialMeasurement
from comgrasp_pin.simulation.cameras import CameraRig
from comgrasp_pin.simulation.objects import ObjectState
from comgrasp_pin.simulation.recorder import ComOnRod
from comgrasp_pin.simulation.sim import Simulation
from comgrasp_pin.simulation.world import ARM_JOINTS, SIDE_CAMERA, TOP_CAMERA

INSTALL = "pip install 'comgrasp_pin[rerun]' (or: pip install 'rerun-sdk>=0.23')"
_ORANGE, _GREEN = (255, 140, 0), (0, 220, 0)


def import_rerun():
    """The ``rerun`` module; MissingExtraError (saying how to install it) without it."""
    try:
        import rerun
    except ImportError as exc:
        raise MissingExtraError(
            f"--rerun needs rerun-sdk, which is not installed: {INSTALL}"
        ) from exc
    return rerun


def cloud_world(camera: PinholeCamera, T_world_cam: np.ndarray, depth: np.ndarray,
                rgb: np.ndarray, stride: int = 1) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """The depth image back-projected into the world: (N, 3) points (m) and their (N, 3)
    RGB colours, every ``stride``-th pixel of each row and column, pixels without depth
    (0 or inf) left out."""
    seen = (np.isfinite(depth) & (depth > 0))[::stride, ::stride]
    p_cam = camera.depth_to_points(np.where(np.isfinite(depth), depth, 0.0))[::stride, ::stride]
    return transform_points(T_world_cam, p_cam[seen]), rgb[::stride, ::stride][seen]


class RerunLog:
    """A Simulation observer writing a Rerun recording to ``path``.

    Cameras every 1/``fps`` s at ``width`` x ``height`` (no shadows; RGB as JPEG, depth in
    mm), the torques every 1/``torque_rate`` s; ``stride``: every stride-th pixel of each
    row and column of a depth image goes into the cloud.
    """

    def __init__(self, sim: Simulation, path: Path, truth: Callable[[], ObjectState],
                 fps: float = 4.0, torque_rate: float = 50.0, width: int = 320,
                 height: int = 240, stride: int = 4):  # fmt: skip
        self.rr = rr = import_rerun()
        Path(path).parent.mkdir(parents=True, exist_ok=True)
        self.rec = rr.RecordingStream("comgrasp_demo")
        self.rec.save(str(path))
        self._truth, self._stride = truth, stride
        self._dt_cam, self._dt_tau = 1.0 / fps, 1.0 / torque_rate
        self._next_cam = self._next_tau = sim.time
        self._rig = CameraRig(sim.model, width, height, shadows=False)
        self.rod_poses: list[tuple[float, np.ndarray]] = []  # (time, T_world_obj) logged
        self.rec.log("world", rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)
        for name in ARM_JOINTS:
            self.rec.log(f"joint_torques/{name}", rr.SeriesLines(names=f"{name} (N m)"),
                         static=True)  # fmt: skip

    def __call__(self, sim: Simulation) -> None:
        rr, rec, t = self.rr, self.rec, sim.time
        if t + 1e-9 >= self._next_tau:
            self._next_tau += self._dt_tau
            rec.set_time("sim_time", duration=t)
            for name, tau in zip(ARM_JOINTS, sim.tau_measured, strict=True):
                rec.log(f"joint_torques/{name}", rr.Scalars(float(tau)))
        if t + 1e-9 < self._next_cam:
            return
        self._next_cam += self._dt_cam
        rec.set_time("sim_time", duration=t)
        for camera in (TOP_CAMERA, SIDE_CAMERA):
            self._log_camera(sim, camera)
        truth = self._truth()
        self.rod_poses.append((t, truth.T_world_obj.copy()))
        rec.log("world/com/truth", rr.Points3D(truth.p_world_com, colors=_GREEN, radii=0.008,
                                               labels="true CoM"))  # fmt: skip

    def _log_camera(self, sim: Simulation, camera: str) -> None:
        rr, rec, rig = self.rr, self.rec, self._rig
        K, T = rig.intrinsics(camera), rig.T_world_cam(sim.data, camera)
        rgb, depth = rig.rgb(sim.data, camera), rig.depth(sim.data, camera)
        path = f"world/cameras/{camera}"
        rec.log(path, rr.Transform3D(translation=T[:3, 3], mat3x3=T[:3, :3]))
        rec.log(path, rr.Pinhole(image_from_camera=K.K, resolution=[K.width, K.height]))
        rec.log(f"{path}/rgb", rr.Image(rgb).compress(jpeg_quality=85))
        seen = np.isfinite(depth) & (depth > 0) & (depth < 65.0)
        depth_mm = np.where(seen, np.round(1e3 * depth), 0).astype(np.uint16)
        rec.log(f"{path}/depth", rr.DepthImage(depth_mm, meter=1000.0))
        p_world, colours = cloud_world(K, T, depth, rgb, self._stride)
        rec.log(f"world/points/{camera}", rr.Points3D(p_world, colors=colours, radii=0.002))

    def finish(self, estimate: ComOnRod | None, phases: list[tuple[float, str]],
               trial: TrialMeasurement | None) -> None:  # fmt: skip
        """The episode is over: log its phases, and its estimate from when it was known."""
        rr, rec = self.rr, self.rec
        for t, caption in phases:
            rec.set_time("sim_time", duration=t)
            rec.log("phases", rr.TextLog(caption))
        if estimate is None:
            return
        line_obj = None
        if trial is not None and trial.estimate_line.unobservable_ee is not None:
            # The single-pose CoM line at the first measurement pose, fixed in the rod.
            u_ee, c_ee = trial.estimate_line.unobservable_ee, trial.estimate_line.com_ee
            ends_ee = np.c_[np.outer([-0.3, 0.3], u_ee) + c_ee, np.ones(2)]
            T_obj_ee = invert_transform(estimate.T_world_obj_measured) @ trial.T_world_ee
            line_obj = (ends_ee @ T_obj_ee.T)[:, :3]
        for t, T_world_obj in self.rod_poses:
            if t < estimate.since - 1e-9:
                continue
            rec.set_time("sim_time", duration=t)
            p = estimate.points_world(T_world_obj)
            rec.log("world/com/estimate", rr.Points3D(p[0], colors=_ORANGE, radii=0.008,
                                                      labels="CoM estimate"))  # fmt: skip
            rec.log("world/com/interval", rr.LineStrips3D([p[1:]], colors=_ORANGE,
                                                          radii=0.003))  # fmt: skip
            if line_obj is not None:
                line = line_obj @ T_world_obj[:3, :3].T + T_world_obj[:3, 3]
                rec.log("world/com/line", rr.LineStrips3D([line], colors=(255, 200, 120),
                                                          radii=0.0015))  # fmt: skip

    def close(self) -> None:
        self._rig.close()
        self.rec.flush()
        self.rec.disconnect()
