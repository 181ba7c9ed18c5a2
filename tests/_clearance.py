"""Clearance of the arm against the workcell: points on the arm, and their height above
whatever lies below them (table, drop box, pedestal, floor; from ``comgrasp_pin.workcell``).
Pinocchio and NumPy only."""

from __future__ import annotations

import numpy as np

from comgrasp_pin.robot import RobotModel
from comgrasp_pin.workcell import FLOOR_Z, GRIPPER, OBSTACLES


def link_points(robot: RobotModel, q: np.ndarray) -> dict[str, np.ndarray]:
    """World points (k, 3) on the arm at ``q`` (m), for clearance checks: joint origins,
    points along each link, the gripper base corners and the fingertips."""
    origins = robot.joint_origins(q)
    pts = [origins]
    for a, b in zip(origins[:-1], origins[1:], strict=True):
        pts.append(a + np.linspace(0.25, 0.75, 3)[:, None] * (b - a))
    T_tool = robot.frame_pose(q, "tool0")
    hx, hy, hz = GRIPPER.palm_half
    corners = np.array(
        [[sx * hx, sy * hy, z] for sx in (-1, 1) for sy in (-1, 1) for z in (0.0, 2 * hz)]
    )
    gripper = corners @ T_tool[:3, :3].T + T_tool[:3, 3]
    T_ee = robot.ee_pose(q)
    # the corners of the pads' bottoms, fingers open (at the middle of each finger's thickness)
    tip_x = GRIPPER.pad_half[0]
    tip_y = GRIPPER.open_half_gap + GRIPPER.finger_centre[1]
    tips_local = np.array(
        [[sx * tip_x, sy * tip_y, GRIPPER.fingertip_below_ee] for sx in (-1, 1) for sy in (-1, 1)]
    )
    tips = tips_local @ T_ee[:3, :3].T + T_ee[:3, 3]
    return {"arm": np.vstack(pts), "gripper": gripper, "fingertips": tips}


def scene_clearance(points: np.ndarray) -> np.ndarray:
    """(k,) height (m) of world points (k, 3) above whatever lies below them in the scene
    (table top, drop box walls, pedestal, floor); negative means inside an obstacle."""
    points = np.asarray(points, dtype=float).reshape(-1, 3)
    below = np.full(len(points), FLOOR_Z)
    for x0, x1, y0, y1, top in OBSTACLES:
        over = (
            (points[:, 0] >= x0)
            & (points[:, 0] <= x1)
            & (points[:, 1] >= y0)
            & (points[:, 1] <= y1)
        )
        below[over] = np.maximum(below[over], top)
    return points[:, 2] - below
