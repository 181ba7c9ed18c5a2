"""`comgrasp views`: both camera views of one trial grasp, with what perception found drawn on."""

from __future__ import annotations

from pathlib import Path

import cv2

from comgrasp_pin.config import EpisodeConfig
from comgrasp_pin.perception import draw_side_view, draw_top_view
from comgrasp_pin.simulation.episode import measure_and_score
from comgrasp_pin.simulation.eyes import look_from_above
from comgrasp_pin.simulation.scene import Scene, World
from comgrasp_pin.simulation.world import SIDE_CAMERA, TOP_CAMERA


def save_camera_views(out_dir: Path, obj: str = "obj2", seed: int = 0) -> list[Path]:
    """Top view of the rod on the table (mask outline, rectangle, axis, grasp point) and side
    view of it held after the trial grasp (outline, rectangle, axis, TCP, tilt), as PNGs."""
    out_dir.mkdir(parents=True, exist_ok=True)
    world = World(Scene.sample(obj, seed), EpisodeConfig(), seed)
    try:
        detection = look_from_above(world.rig, world.sim.data)
        top = draw_top_view(world.rig.rgb(world.sim.data, TOP_CAMERA), detection,
                            detection.axis_px.mean(axis=0))  # fmt: skip
        trial, _ = measure_and_score(world)
        side = draw_side_view(world.rig.rgb(world.sim.data, SIDE_CAMERA), trial.side_view)
    finally:
        world.close()
    paths = [
        out_dir / f"{obj}_seed{seed}_top_view.png",
        out_dir / f"{obj}_seed{seed}_side_view.png",
    ]
    cv2.imwrite(str(paths[0]), top)
    cv2.imwrite(str(paths[1]), side)
    return paths
