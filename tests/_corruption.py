"""Real renders of rods, corrupted as depth cameras corrupt them, and the truth to check against.

Shared by tests/test_perception_robust.py (and handy at a prompt): every scene is a MuJoCo
render (headless EGL); the corruption is applied to the rendered depth; the truth comes from
the simulator.
"""

from __future__ import annotations

import mujoco
import numpy as np

from comgrasp_pin.config import sensor_preset
from comgrasp_pin.simulation import Simulation, build_model
from comgrasp_pin.simulation.cameras import CameraRig
from comgrasp_pin.simulation.depth_noise import DepthNoise
from comgrasp_pin.simulation.objects import OBJECTS, add_object, pose_on_table
from comgrasp_pin.simulation.world import TOP_CAMERA
from comgrasp_pin.workcell import Q_PARK

TOP_CENTRE_BOUND = 3e-3  # m
TOP_YAW_BOUND_DEG = 1.0
SIDE_TILT_BOUND_DEG = 0.5
SIDE_GRASP_BOUND = 3e-3  # m


def drop_pixels(depth: np.ndarray, share: float, rng: np.random.Generator) -> np.ndarray:
    """``depth`` with ``share`` of its pixels lost at random: half 0, half inf."""
    out = depth.copy()
    lost = rng.random(depth.shape) < share
    half = rng.random(depth.shape) < 0.5
    out[lost & half] = 0.0
    out[lost & ~half] = np.inf
    return out


def add_noise(depth: np.ndarray, std: float, rng: np.random.Generator) -> np.ndarray:
    """``depth`` with white Gaussian noise of ``std`` (m) on every finite pixel."""
    return np.where(np.isfinite(depth), depth + std * rng.standard_normal(depth.shape), depth)


def realistic(camera: str, seed: int) -> DepthNoise:
    """The realistic preset's depth errors of the "top" or "side" camera."""
    sensors = sensor_preset("realistic")
    return DepthNoise(sensors.top_depth if camera == "top" else sensors.side_depth, seed)


def corruptions(camera: str, seed: int) -> dict:
    """name -> (function depth -> corrupted depth, the calibration error T_cam_calibrated),
    for the "top" or "side" camera."""
    rng = np.random.default_rng(seed)
    noise = realistic(camera, seed)
    out = {f"drop{int(100 * s)}": (lambda d, s=s: drop_pixels(d, s, rng), np.eye(4))
           for s in (0.05, 0.15, 0.25, 0.35)}  # fmt: skip
    out["noise2mm"] = (lambda d: add_noise(d, 0.002, rng), np.eye(4))
    out["noise2mm_drop20"] = (lambda d: drop_pixels(add_noise(d, 0.002, rng), 0.2, rng), np.eye(4))
    out["realistic"] = (noise.apply, noise.T_cam_calibrated)
    return out


def table_scene(rods: list[tuple[str, float, float, float]]):
    """(sim, rig, truths) with each (name, x, y, yaw) rod lying on the table; truths are
    the (x, y, yaw) of each."""
    extras = [
        (lambda s, o=OBJECTS[n], p=(x, y, yaw), k=k: add_object(s, o, p, name=f"rod{k}"))
        for k, (n, x, y, yaw) in enumerate(rods)
    ]
    model = build_model(extras=extras)
    sim = Simulation(model)
    sim.reset_arm(Q_PARK)
    for k, (n, x, y, yaw) in enumerate(rods):
        T = pose_on_table(x, y, yaw, OBJECTS[n])
        quat = np.zeros(4)
        mujoco.mju_mat2Quat(quat, T[:3, :3].ravel())
        adr = model.joint(f"rod{k}_free").qposadr[0]
        sim.data.qpos[adr : adr + 7] = np.r_[T[:3, 3], quat]
    mujoco.mj_forward(model, sim.data)
    return sim, CameraRig(model), [(x, y, yaw) for _, x, y, yaw in rods]


def top_inputs(sim, rig):
    """(clean depth, camera intrinsics, true T_world_cam, colour image) of the top camera."""
    return (rig.depth(sim.data, TOP_CAMERA), rig.intrinsics(TOP_CAMERA),
            rig.T_world_cam(sim.data, TOP_CAMERA), rig.rgb(sim.data, TOP_CAMERA))  # fmt: skip


def one_rod_frame(rod: tuple[str, float, float, float]):
    """(depth (m), camera, T_world_cam, rgb, truth (x, y, yaw)) of one ``rod`` on the table,
    rendered by the top camera."""
    sim, rig, truths = table_scene([rod])
    depth, camera, T, rgb = top_inputs(sim, rig)
    rig.close()
    return depth, camera, T, rgb, truths[0]


def wrap_half_turn(angle: float) -> float:
    return (angle + np.pi / 2) % np.pi - np.pi / 2


def top_errors(det, truth, T_world_cam, T_cam_calibrated):
    """(centre error (m), yaw error (deg)) of a top-view detection against the rod's true
    (x, y, yaw), seen through the calibration error: the truth is where a perfect
    perception with the calibrated camera pose would put it."""
    x, y, yaw = truth
    T_world_believed = T_world_cam @ T_cam_calibrated
    T_map = T_world_believed @ np.linalg.inv(T_world_cam)
    centre = T_map[:3, :3] @ np.array([x, y, 0.0]) + T_map[:3, 3]
    axis = T_map[:3, :3] @ np.array([np.cos(yaw), np.sin(yaw), 0.0])
    err = np.hypot(det.grasp.x - centre[0], det.grasp.y - centre[1])
    yaw_err = abs(wrap_half_turn(det.grasp.yaw - np.arctan2(axis[1], axis[0])))
    return float(err), float(np.degrees(yaw_err))
