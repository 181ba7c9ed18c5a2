"""`comgrasp views`: both camera views of one trial grasp, with what perception found drawn on.

The side view also shows the trial's CoM estimate with its +-2 sigma interval along the
rod, where the robot believes it is (its side view and kinematics), and the true CoM from
the simulator, each projected with the camera's intrinsics and pose; every overlay has a
legend.
"""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np

from comgrasp_pin.camera import transform_points
from comgrasp_pin.config import EpisodeConfig
from comgrasp_pin.perception import draw_side_view, draw_top_view
from comgrasp_pin.procedures.measurement import TrialMeasurement
from comgrasp_pin.simulation.cameras import CameraRig
from comgrasp_pin.simulation.episode import measure_and_score
from comgrasp_pin.simulation.eyes import look_from_above
from comgrasp_pin.simulation.recorder import project
from comgrasp_pin.simulation.scene import Scene, World
from comgrasp_pin.simulation.world import SIDE_CAMERA, TOP_CAMERA


def com_marks_px(rig: CameraRig, data, camera: str, trial: TrialMeasurement,
                 T_world_ee: np.ndarray, p_world_true: np.ndarray) -> tuple:  # fmt: skip
    """Pixels in ``camera`` of the trial's CoM estimate, its +-2 sigma interval's ends along
    the perceived rod (the robot's belief, carried by the ee at ``T_world_ee``) and the true
    CoM ``p_world_true`` (3,): (estimate (2,), interval (2, 2), truth (2,)), each None when
    outside the image."""
    x, s = trial.x_com_obj, trial.x_com_std
    p_obj = np.array([[x, 0.0, 0.0], [x - 2 * s, 0.0, 0.0], [x + 2 * s, 0.0, 0.0]])
    p_world = transform_points(T_world_ee @ trial.T_ee_obj, p_obj)
    uv, ok = project(rig.intrinsics(camera), rig.T_world_cam(data, camera),
                     np.vstack([p_world, p_world_true]))  # fmt: skip
    return (uv[0] if ok[0] else None, uv[1:3] if ok[1:3].all() else None,
            uv[3] if ok[3] else None)  # fmt: skip


def save_camera_views(out_dir: Path, obj: str = "obj2", seed: int = 0) -> list[Path]:
    """Top view of the rod on the table (mask outline, rectangle, axis, grasp point) and side
    view of it held after the trial grasp (outline, rectangle, axis, TCP, tilt, the CoM
    estimate and the truth), as PNGs."""
    out_dir.mkdir(parents=True, exist_ok=True)
    world = World(Scene.sample(obj, seed), EpisodeConfig(), seed)
    try:
        detection = look_from_above(world.rig, world.sim.data)
        top = draw_top_view(world.rig.rgb(world.sim.data, TOP_CAMERA), detection,
                            detection.axis_px.mean(axis=0))  # fmt: skip
        trial, _ = measure_and_score(world)
        T_world_ee, truth = world.robot.ee_pose(world.sim.q), world.truth()
        marks = com_marks_px(world.rig, world.sim.data, SIDE_CAMERA, trial, T_world_ee,
                             truth.p_world_com)  # fmt: skip
        side = draw_side_view(world.rig.rgb(world.sim.data, SIDE_CAMERA), trial.side_view,
                              *marks)  # fmt: skip
    finally:
        world.close()
    paths = [
        out_dir / f"{obj}_seed{seed}_top_view.png",
        out_dir / f"{obj}_seed{seed}_side_view.png",
    ]
    cv2.imwrite(str(paths[0]), top)
    cv2.imwrite(str(paths[1]), side)
    return paths
