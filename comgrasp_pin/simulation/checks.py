"""`comgrasp check`: render the scene from every camera and prove the physics agrees.

Measures what the foundation promises: Pinocchio and MuJoCo gravity torques and ee poses
agree, the torque reading equals the model's static torque, and how fast the world steps and
renders on this machine.
"""

from __future__ import annotations

import json
import time
from pathlib import Path

import mujoco
import numpy as np
import pinocchio as pin

from comgrasp_pin.robot import RobotModel
from comgrasp_pin.simulation.cameras import CameraRig
from comgrasp_pin.simulation.sim import Simulation
from comgrasp_pin.simulation.world import ARM_JOINTS, EE_SITE, SIDE_CAMERA, TOP_CAMERA

Q_SHOWCASE = np.array([0.0, -1.9, 1.9, -1.57, -1.57, 0.0])


def agreement(robot: RobotModel, sim: Simulation, n: int = 50, seed: int = 0) -> dict:
    """Worst gravity-torque (N m), position (m) and rotation (rad) gaps over n random q."""
    m, d = sim.model, sim.data
    dofs = [m.joint(j).dofadr[0] for j in ARM_JOINTS]
    qadr = [m.joint(j).qposadr[0] for j in ARM_JOINTS]
    site = m.site(EE_SITE).id
    rng = np.random.default_rng(seed)
    worst = {"gravity_torque_Nm": 0.0, "ee_position_m": 0.0, "ee_rotation_rad": 0.0}
    for _ in range(n):
        q = robot.random_configuration(rng)
        d.qpos[qadr] = q
        d.qvel[:] = 0.0
        mujoco.mj_forward(m, d)
        T = robot.ee_pose(q)
        R_gap = d.site_xmat[site].reshape(3, 3).T @ T[:3, :3]
        gaps = {
            "gravity_torque_Nm": np.abs(d.qfrc_bias[dofs] - robot.gravity_torques(q)).max(),
            "ee_position_m": np.abs(d.site_xpos[site] - T[:3, 3]).max(),
            "ee_rotation_rad": np.linalg.norm(pin.log3(R_gap)),
        }
        worst = {k: max(worst[k], float(gaps[k])) for k in worst}
    return worst


def step_timing(sim: Simulation, seconds: float = 2.0) -> dict:
    """Wall time per physics step (servo in the loop) and the real-time factor."""
    sim.reset_arm(Q_SHOWCASE)
    n = int(seconds / sim.model.opt.timestep)
    start = time.perf_counter()
    sim.step(n)
    wall = time.perf_counter() - start
    return {"step_us": 1e6 * wall / n, "real_time_factor": seconds / wall}


def render_views(sim: Simulation, out_dir: Path) -> dict:
    """Write scene, top-down and side-camera images (PNG); return render times (ms)."""
    import cv2

    sim.reset_arm(Q_SHOWCASE, finger_q=0.02)
    rig = CameraRig(sim.model)
    times = {}
    try:
        for camera in ("scene", TOP_CAMERA, SIDE_CAMERA):
            rig.rgb(sim.data, camera)  # warm-up: the first render builds GPU-side buffers
            start = time.perf_counter()
            rgb = rig.rgb(sim.data, camera)
            mid = time.perf_counter()
            depth = rig.depth(sim.data, camera)
            end = time.perf_counter()
            times[camera] = {"rgb_ms": 1e3 * (mid - start), "depth_ms": 1e3 * (end - mid)}
            cv2.imwrite(str(out_dir / f"{camera}_rgb.png"), rgb[:, :, ::-1])
            finite = depth[np.isfinite(depth)]
            scaled = (255 * (depth - finite.min()) / max(np.ptp(finite), 1e-9)).clip(0, 255)
            cv2.imwrite(
                str(out_dir / f"{camera}_depth.png"), np.nan_to_num(scaled).astype(np.uint8)
            )
    finally:
        rig.close()
    return times


def run_checks(out_dir: Path) -> dict:
    """All checks; writes ``check.json`` and the images to ``out_dir``."""
    out_dir.mkdir(parents=True, exist_ok=True)
    robot = RobotModel.ur5()
    sim = Simulation()
    report = {
        "pinocchio_vs_mujoco_worst": agreement(robot, sim),
        "timing": step_timing(sim),
        "render": render_views(sim, out_dir),
    }
    sim.reset_arm(Q_SHOWCASE + 0.02)
    sim.q_des = Q_SHOWCASE
    sim.hold(1.0)
    gap = np.abs(sim.joint_torques() - robot.gravity_torques(sim.q)).max()
    report["torque_reading_vs_model_Nm"] = float(gap)
    (out_dir / "check.json").write_text(json.dumps(report, indent=2))
    return report
