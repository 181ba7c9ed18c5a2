"""Time per camera frame: MuJoCo's headless render against our perception, and its accuracy.

    python benchmarks/bench_perception.py [--frames 12] [--out benchmarks/results/perception.json]

Top view: a rod (each object in turn) at random poses on the table; side view: the rod held
in the jaws at random tilts (0-35 deg) and offsets. Reports the median time of RGB render,
depth render and perception per frame (ms), their ratio, median/worst errors against the
simulator's ground truth, and every frame's times and errors (``frames``).
"""

from __future__ import annotations

import os

os.environ.setdefault("MUJOCO_GL", "egl")

import argparse  # noqa: E402
import json  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import mujoco  # noqa: E402
import numpy as np  # noqa: E402

import comgrasp_pin as cg  # noqa: E402
from comgrasp_pin.motion.ik import solve_ik, top_down_frame
from comgrasp_pin.perception import detect_rod_top_down, observe_held_rod  # noqa: E402
from comgrasp_pin.simulation import Simulation, build_model  # noqa: E402
from comgrasp_pin.simulation.cameras import CameraRig  # noqa: E402
from comgrasp_pin.simulation.eyes import (  # noqa: E402
    arm_capsules,
    handle_radius,
    side_camera_pose,
)
from comgrasp_pin.simulation.objects import OBJECTS, add_object, pose_on_table  # noqa: E402
from comgrasp_pin.simulation.scene import random_table_pose  # noqa: E402
from comgrasp_pin.workcell import (
    Q_PARK,  # noqa: E402
    TABLE_Z,  # noqa: E402
)


def _timed(fn):
    start = time.perf_counter()
    out = fn()
    return out, 1e3 * (time.perf_counter() - start)


def bench_top(n_frames: int, rng) -> dict:
    rows, frames = [], []
    for k in range(n_frames):
        obj = OBJECTS[sorted(OBJECTS)[k % len(OBJECTS)]]
        x, y, yaw = random_table_pose(rng, obj.length)
        pose = (x, y, yaw)
        model = build_model(extras=[lambda s, o=obj, p=pose: add_object(s, o, p)])
        sim = Simulation(model)
        sim.reset_arm(Q_PARK)
        rig = CameraRig(model)
        rig.rgb(sim.data, "top_down")  # warm-up
        rgb, t_rgb = _timed(lambda: rig.rgb(sim.data, "top_down"))
        depth, t_depth = _timed(lambda: rig.depth(sim.data, "top_down"))
        det, t_perc = _timed(lambda: detect_rod_top_down(
            rgb, depth, rig.intrinsics("top_down"), rig.T_world_cam(sim.data, "top_down")))  # fmt: skip
        rig.close()
        T = pose_on_table(x, y, yaw, obj)
        rows.append((t_rgb, t_depth, t_perc, np.hypot(det.grasp.x - T[0, 3], det.grasp.y - T[1, 3]),
                     abs((det.grasp.yaw - yaw + np.pi / 2) % np.pi - np.pi / 2)))  # fmt: skip
        frames.append({"object": obj.name, "render_rgb_ms": t_rgb, "render_depth_ms": t_depth,
                       "perception_ms": t_perc, "centre_error_mm": 1e3 * rows[-1][3],
                       "yaw_error_deg": float(np.degrees(rows[-1][4]))})  # fmt: skip
    a = np.array(rows)
    return {
        "render_rgb_ms": float(np.median(a[:, 0])), "render_depth_ms": float(np.median(a[:, 1])),
        "perception_ms": float(np.median(a[:, 2])),
        "perception_over_render": float(np.median(a[:, 2]) / np.median(a[:, 0] + a[:, 1])),
        "centre_error_mm": {"median": 1e3 * float(np.median(a[:, 3])), "worst": 1e3 * float(a[:, 3].max())},
        "yaw_error_deg": {"median": float(np.degrees(np.median(a[:, 4]))), "worst": float(np.degrees(a[:, 4].max()))},
        "frames": frames,
    }  # fmt: skip


def bench_side(n_frames: int, rng) -> dict:
    robot = cg.RobotModel.ur5()
    q = solve_ik(robot, top_down_frame(0.55, 0.0, 0.45, 0.4), Q_PARK)
    rows, frames = [], []
    for name in sorted(OBJECTS):
        obj = OBJECTS[name]
        model = build_model(extras=[lambda s, o=obj: add_object(s, o, np.eye(4), parent="eelink")])
        sim = Simulation(model)
        sim.reset_arm(q, finger_q=0.045 - obj.thickness / 2)
        rig = CameraRig(model)
        body = model.body("object").id
        for _ in range(max(1, n_frames // len(OBJECTS))):
            tilt, offset = np.radians(rng.uniform(-35, 35)), rng.uniform(-0.04, 0.04)
            R = np.array(
                [[np.cos(tilt), 0, np.sin(tilt)], [0, 1, 0], [-np.sin(tilt), 0, np.cos(tilt)]]
            )
            quat = np.zeros(4)
            mujoco.mju_mat2Quat(quat, R.ravel())
            model.body_pos[body], model.body_quat[body] = -R @ [offset, 0, 0], quat
            mujoco.mj_forward(model, sim.data)
            rig.depth(sim.data, "side_camera")  # warm-up
            depth, t_depth = _timed(lambda: rig.depth(sim.data, "side_camera"))
            T_world_ee, T_ee_cam = side_camera_pose(robot, sim.q)
            inputs = (None, depth, rig.intrinsics("side_camera"), T_ee_cam, T_world_ee, TABLE_Z,
                      obj.length, arm_capsules(robot, sim.q), None, handle_radius(sim.finger_q[0]))  # fmt: skip
            view, t_perc = _timed(lambda: observe_held_rod(*inputs))
            theta_true = np.arctan2(-R[2, 0], R[0, 0])
            rows.append((t_depth, t_perc, abs(view.theta - theta_true),
                         abs(view.grasp_offset - np.sign(view.T_ee_obj[:3, 0] @ R[:, 0]) * offset)))  # fmt: skip
            frames.append({"object": name, "tilt_deg": float(np.degrees(tilt)), "offset_m": offset,
                           "render_depth_ms": t_depth, "perception_ms": t_perc,
                           "tilt_error_deg": float(np.degrees(rows[-1][2])),
                           "grasp_position_error_mm": 1e3 * rows[-1][3]})  # fmt: skip
        rig.close()
    a = np.array(rows)
    return {
        "render_depth_ms": float(np.median(a[:, 0])), "perception_ms": float(np.median(a[:, 1])),
        "perception_over_render": float(np.median(a[:, 1]) / np.median(a[:, 0])),
        "tilt_error_deg": {"median": float(np.degrees(np.median(a[:, 2]))), "worst": float(np.degrees(a[:, 2].max()))},
        "grasp_position_error_mm": {"median": 1e3 * float(np.median(a[:, 3])), "worst": 1e3 * float(a[:, 3].max())},
        "frames": frames,
    }  # fmt: skip


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=12)
    parser.add_argument("--out", default="benchmarks/results/perception.json")
    args = parser.parse_args()
    rng = np.random.default_rng(0)
    result = {"top_view": bench_top(args.frames, rng), "side_view": bench_side(args.frames, rng)}
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    Path(args.out).write_text(json.dumps(result, indent=2))
    print(json.dumps(result, indent=2))


if __name__ == "__main__":
    main()
