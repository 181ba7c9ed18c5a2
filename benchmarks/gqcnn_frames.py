"""Real RGBD frames for ``real_frames.py --extra``, made from gqcnn's example data.

    git clone --depth 1 https://github.com/BerkeleyAutomation/gqcnn /tmp/gqcnn
    python benchmarks/gqcnn_frames.py /tmp/gqcnn /tmp/gqcnn_frames
    python benchmarks/real_frames.py --extra /tmp/gqcnn_frames/* --source "gqcnn data/examples"

The frames stay outside the repository (UC Berkeley's academic licence): this script writes
them where it is told. ``GQCNN`` is a checkout, or a bare git directory (read with ``git
show``). One folder per frame, named as ``benchmarks/results/real_frames.json`` has them
(a name starting ``clutter`` is a scene of several objects there):

- ``depth_mm.png``: the authors' ``depth_i.npy`` (float, m) as 16-bit mm, 0 where none;
- ``color.png``: the authors' colour image; the PhoXi's, saved at twice the depth's size,
  halved (INTER_AREA);
- ``segmask.png``: the authors' object mask (0 / 255);
- ``camera_info.yaml``: ``data/calib/SENSOR/SENSOR.intr`` as a ROS camera_calibration file
  (no distortion, ``depth_scale`` 0.001);
- ``T_world_cam.txt`` (PrimeSense only): ``data/calib/primesense/primesense.tf`` (translation
  row, then rotation rows) as a 4x4 matrix;
- and the frame as the authors ship it, which ``real_frames.py`` runs too: ``depth.npy``
  (float m, (H, W, 1)), ``camera.intr`` and (PrimeSense) ``camera.tf``, copied unchanged.
"""

from __future__ import annotations

import argparse
import io
import json
import subprocess
from pathlib import Path

import cv2
import numpy as np
import yaml

from comgrasp_pin.cli.camera_files import read_pose

EXAMPLES = "data/examples"
FRAMES = (  # (folder, source folder, index, sensor, with the camera's pose)
    [(f"single_primesense_{i}", "single_object/primesense", i, "primesense", True)
     for i in range(1, 10)]  # (frame 0 is ../shared's flashlight)
    + [(f"clutter_primesense_{i}", "clutter/primesense", i, "primesense", True) for i in range(5)]
    + [(f"clutter_phoxi_{net}_{i}", f"clutter/phoxi/{net}", i, "phoxi", False)
       for net in ("dex-net_4.0", "fcgqcnn") for i in range(5)]
)  # fmt: skip


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("gqcnn", type=Path, help="a gqcnn checkout or bare git directory")
    parser.add_argument("out", type=Path, help="folder to write the frames' folders into")
    args = parser.parse_args()
    read = _reader(args.gqcnn)
    for name, source, i, sensor, with_pose in FRAMES:
        folder = args.out / name
        folder.mkdir(parents=True, exist_ok=True)
        info = _camera_info(json.loads(read(f"data/calib/{sensor}/{sensor}.intr")))
        shape = (info["image_height"], info["image_width"])
        prefix = f"{EXAMPLES}/{source}"
        depth = np.squeeze(np.load(io.BytesIO(read(f"{prefix}/depth_{i}.npy")))).astype(float)
        if depth.shape != shape:
            raise SystemExit(f"{name}: depth {depth.shape}, camera {shape}")
        seen = np.isfinite(depth) & (depth > 0)
        depth_mm = np.zeros(shape, np.uint16)
        depth_mm[seen] = np.clip(np.round(1000 * depth[seen]), 0, 65535)
        cv2.imwrite(str(folder / "depth_mm.png"), depth_mm)
        colour = _image(read(f"{prefix}/color_{i}.png"), cv2.IMREAD_UNCHANGED)
        if colour.shape[:2] != shape:  # PhoXi: twice the depth's size
            colour = cv2.resize(colour, shape[::-1], interpolation=cv2.INTER_AREA)
        cv2.imwrite(str(folder / "color.png"), colour)
        mask = _image(read(f"{prefix}/segmask_{i}.png"), cv2.IMREAD_GRAYSCALE)
        cv2.imwrite(str(folder / "segmask.png"), np.where(mask > 0, 255, 0).astype(np.uint8))
        (folder / "camera_info.yaml").write_text(yaml.safe_dump(info, sort_keys=False))
        if with_pose:  # the authors' .tf, and as a 4x4 text matrix read by the package's reader
            (folder / "camera.tf").write_bytes(read(f"data/calib/{sensor}/{sensor}.tf"))
            np.savetxt(folder / "T_world_cam.txt", read_pose(folder / "camera.tf", "T_world_cam"))
        (folder / "depth.npy").write_bytes(read(f"{prefix}/depth_{i}.npy"))
        (folder / "camera.intr").write_bytes(read(f"data/calib/{sensor}/{sensor}.intr"))
        print(f"{name}: {shape[1]}x{shape[0]}, {100 * (1 - seen.mean()):.0f} % without depth")


def _reader(gqcnn: Path):
    """A function that gives a file of ``gqcnn`` (checkout or bare git directory) as bytes."""
    if (gqcnn / EXAMPLES).is_dir():
        return lambda path: (gqcnn / path).read_bytes()
    return lambda path: (
        subprocess.run(
            ["git", f"--git-dir={gqcnn}", "show", f"HEAD:{path}"], check=True, capture_output=True
        ).stdout
    )


def _image(data: bytes, flags: int) -> np.ndarray:
    return cv2.imdecode(np.frombuffer(data, np.uint8), flags)


def _camera_info(intr: dict) -> dict:
    """autolab_core's intrinsics (JSON) as a ROS camera_calibration file's fields."""
    fx, fy, cx, cy, skew = (float(intr[k]) for k in ("_fx", "_fy", "_cx", "_cy", "_skew"))
    return {
        "image_width": int(intr["_width"]), "image_height": int(intr["_height"]),
        "camera_name": intr["_frame"],
        "camera_matrix": {"rows": 3, "cols": 3, "data": [fx, skew, cx, 0.0, fy, cy, 0, 0, 1.0]},
        "distortion_model": "plumb_bob",
        "distortion_coefficients": {"rows": 1, "cols": 5, "data": [0.0] * 5},
        "depth_scale": 0.001,
    }  # fmt: skip


if __name__ == "__main__":
    main()
