"""The simulated robot's eyes: render a camera, hand the images to ``comgrasp_pin.perception``.

Only images, the robot's own joint readings and its description (T_ee_cam from the URDF)
are used, as on a real robot; no ground truth. With a realistic sensor preset the images
carry the camera's errors and the camera poses its calibration error
(``CameraRig.noise``, ``simulation.depth_noise``).
"""

from __future__ import annotations

import mujoco
import numpy as np

from comgrasp_pin.errors import ObjectNotFoundError, PerceptionError
from comgrasp_pin.geometry import invert_transform
from comgrasp_pin.perception import (
    AGREE_TOLERANCE,
    RodDetection,
    SideView,
    SlipMonitor,
    average_depth_frames,
    detect_rod_top_down,
    observe_held_rod,
)
from comgrasp_pin.robot import RobotModel
from comgrasp_pin.simulation.cameras import CameraRig
from comgrasp_pin.simulation.world import SIDE_CAMERA, TOP_CAMERA
from comgrasp_pin.workcell import GRIPPER, TABLE_Z

ARM_RADIUS = 0.075  # UR5 upper arm and forearm: about 0.06 m in radius, with a margin (m)
WRIST_RADIUS = 0.06  # UR5 wrist housings: about 0.045-0.055 m, with a margin (m)


def look_from_above(rig: CameraRig, data: mujoco.MjData) -> RodDetection:
    """Detect the rod on the table with the top-down camera. The detection needs the depth
    only where it is a clean render; a real camera's (``CameraRig.noise``) comes with the
    colour image, which helps where the depth cannot tell a thin rod from the table. It is
    rendered only then (the same frame: nothing moves while perception runs)."""
    depth = rig.depth(data, TOP_CAMERA)
    rgb = (lambda: rig.rgb(data, TOP_CAMERA)) if TOP_CAMERA in rig.noise else None
    T_world_cam = rig.T_world_cam(data, TOP_CAMERA) @ rig.calibration_error(TOP_CAMERA)
    return detect_rod_top_down(rgb, depth, rig.intrinsics(TOP_CAMERA), T_world_cam)


def side_camera_pose(robot: RobotModel, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(T_world_ee, T_ee_cam) at the arm configuration ``q``, from the robot description."""
    T_world_ee = robot.ee_pose(q)
    return T_world_ee, invert_transform(T_world_ee) @ robot.frame_pose(q, SIDE_CAMERA)


def look_from_side(
    rig: CameraRig,
    data: mujoco.MjData,
    robot: RobotModel,
    q: np.ndarray,
    rod_length: float | None = None,
    centre_hint: float | None = None,
    finger_q: float | None = None,
    stride: int = 1,
    tilt_only: bool = False,
    frames: int = 1,
    frames_tolerance: float = AGREE_TOLERANCE,
) -> SideView:
    """The held rod's pose in the ee frame, from the side camera at joint reading ``q``
    (``rod_length`` and ``centre_hint`` from the top view help when the rod leaves the
    image; see ``observe_held_rod``). The measurement needs depth only: no colour image is
    rendered. ``finger_q``: the fingers' joint
    reading (m), which gives the held handle's radius. ``stride`` > 1 measures on every
    stride-th pixel of each row and column (stride^2 times fewer points: the slip monitor's
    frames, which need the tilt only; ``tilt_only``: see ``observe_held_rod``). ``frames``
    > 1: that many frames of the still arm (each with its own noise; the calibration error
    is the episode's) averaged in time (``average_depth_frames`` with ``frames_tolerance``),
    for a camera with errors only (a clean render is the same every time)."""
    radius = None if finger_q is None else handle_radius(finger_q)
    if radius is not None and radius <= 0:
        raise ObjectNotFoundError("the jaws are closed on nothing: no rod is held")
    T_world_ee, T_ee_cam = side_camera_pose(robot, q)
    T_ee_cam = T_ee_cam @ rig.calibration_error(SIDE_CAMERA)
    camera = rig.intrinsics(SIDE_CAMERA).subsampled(stride)
    depth = rig.depth(data, SIDE_CAMERA, stride)
    if frames > 1 and SIDE_CAMERA in rig.noise:
        more = [rig.depth(data, SIDE_CAMERA, stride) for _ in range(frames - 1)]
        depth = average_depth_frames([depth, *more], frames_tolerance)
    return observe_held_rod(None, depth, camera, T_ee_cam, T_world_ee,
                            TABLE_Z, rod_length, arm_capsules(robot, q), centre_hint,
                            radius, tilt_only)  # fmt: skip


def handle_radius(finger_q: float) -> float:
    """Radius (m) of a round handle held with the fingers at ``finger_q`` (m closed each)."""
    return max(GRIPPER.open_half_gap - finger_q, 0.0)


def arm_capsules(robot: RobotModel, q: np.ndarray):
    """The arm's links as capsules in the ee frame: segments between successive joint
    origins (and on to the flange), for the side view's self-filtering. The wrist's
    segments are thinner (UR5: about 0.045 m in radius)."""
    T_ee_world = invert_transform(robot.ee_pose(q))
    points = np.vstack([robot.joint_origins(q), robot.frame_pose(q, "tool0")[None, :3, 3]])
    points = points @ T_ee_world[:3, :3].T + T_ee_world[:3, 3]
    radii = [ARM_RADIUS] * 3 + [WRIST_RADIUS] * (len(points) - 4)
    return [(a, b, r) for a, b, r in zip(points[:-1], points[1:], radii, strict=True)]


class SlipWatcher:
    """A Simulation observer sampling the tilt with the side camera every ``dt`` seconds
    once the jaws hold with ``grip_force``, on every ``stride``-th pixel; frames where the
    rod cannot be measured are counted and skipped. Implements ``procedures.cell.SlipWatch``."""

    def __init__(
        self,
        sim,
        rig: CameraRig,
        robot: RobotModel,
        dt: float,
        grip_force: float,
        rod_length: float | None,
        centre_hint: float | None,
        stride: int,
    ):
        self.sim = sim
        self.rig, self.robot, self.dt, self.grip_force = rig, robot, dt, grip_force
        self.stride = stride
        self.rod_length, self.centre_hint = rod_length, centre_hint
        self.monitor = SlipMonitor()
        self.failed_frames = 0
        self._next = -np.inf

    def __call__(self, sim, force: bool = False) -> None:
        if sim.grip_force < self.grip_force - 1e-9 or (sim.time < self._next and not force):
            return
        self._next = sim.time + self.dt
        try:
            view = look_from_side(self.rig, sim.data, self.robot, sim.q, self.rod_length,
                                  self.centre_hint, sim.finger_q[0],
                                  stride=self.stride, tilt_only=True)  # fmt: skip
        except PerceptionError:
            self.failed_frames += 1
            return
        if not self.monitor.times or sim.time > self.monitor.times[-1]:
            self.monitor.add(sim.time, view.theta)

    def sample_now(self) -> None:
        """Take a frame now, whatever the period."""
        self(self.sim, force=True)

    def slipping_or_tilted(self) -> bool:
        """True when slip was seen, or the rod is slipping at the last sample."""
        if not self.monitor.times:
            return False
        verdict = self.monitor.verdict()
        return verdict.slip_seen or verdict.slipping
