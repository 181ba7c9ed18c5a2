"""``comgrasp views [--rgb] --depth --camera-info`` or ``--bag``: perception on a user's frames.

Reads the files (``perception.frames.rgbd_files``; the depth and camera info alone where no colour
is given: both views find the object from the depth alone and draw on the depth),
undistorts them where the camera info's lens
model says so, measures the rod from above (``--view top``) or held in the jaws (``--view
side``) and writes the annotated PNG and a JSON of what was measured. The top view needs the
table's frame: the camera's pose ``--T-world-cam`` (hand-eye or extrinsic calibration), or,
without it, the table's plane fitted in the depth image (frame ``table``). Perception's
refusals and bad files end with exit status 2 and their message.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from comgrasp_pin.cli import args as cli_args
from comgrasp_pin.errors import CameraFileError, InvalidInputError
from comgrasp_pin.geometry import check_transform, tilt_from_level_deg


def add_arguments(views: argparse.ArgumentParser) -> None:
    """The file mode's options of ``comgrasp views``."""
    g = views.add_argument_group(
        "your own camera's frames (instead of a simulated scene)",
        "an RGBD frame as files: the depth (aligned to the colour camera where a colour "
        "image is given) and the camera info; the colour is optional",
    )
    g.add_argument("--rgb", type=Path, metavar="FILE",
                   help="colour PNG or JPEG; optional: without it the object is found from the "
                   "depth alone (the side view always is) and drawn on the depth")  # fmt: skip
    g.add_argument("--depth", type=Path, metavar="FILE",
                   help="single-channel 16-bit PNG in the camera's depth units")  # fmt: skip
    g.add_argument("--camera-info", type=Path, metavar="FILE",
                   help="intrinsics, JSON or YAML: RealSense fields (fx, fy, ppx, ppy, width, "
                   "height, model, coeffs), a ROS CameraInfo (k, d, distortion_model, width, "
                   "height) or a camera_calibration YAML")  # fmt: skip
    g.add_argument("--depth-scale", type=cli_args.float_at_least(0.0), default=None,
                   metavar="S", help="metres per depth unit (0.001: mm; 0.0001: a D405); "
                   "else the camera info's depth_scale")  # fmt: skip
    g.add_argument("--bgr", action="store_true",
                   help="the colour file holds BGR in its RGB channels (a BGR array saved "
                   "by an RGB writer such as PIL)")  # fmt: skip
    g.add_argument(
        "--view",
        choices=("top", "side"),
        default="top",
        help="a rod on the table seen from above, or held in the jaws (%(default)s)",
    )
    g.add_argument("--T-world-cam", type=Path, metavar="FILE", dest="T_world_cam",
                   help="top view: the camera's pose in a frame with z up (4x4, JSON or "
                   "text); without it, the table's plane fitted in the depth is the "
                   "frame")  # fmt: skip
    g.add_argument("--pick-area", default=None, metavar="X0,X1,Y0,Y1",
                   help="top view: where the rod lies (m), in --T-world-cam's frame (needed "
                   "there), or in the table's (origin below the camera, x to the image's "
                   "right, y to its top; default: all of the table in view)")  # fmt: skip
    g.add_argument(
        "--T-ee-cam",
        type=Path,
        metavar="FILE",
        dest="T_ee_cam",
        help="side view: the camera's pose in the ee frame (4x4, JSON or text)",
    )
    b = views.add_argument_group(
        "or the frame as a ROS bag recorded it (instead of --rgb, --depth, --camera-info)",
        "sensor_msgs Image (depth 16UC1 in mm or 32FC1 in m, REP 118; colour rgb8, bgr8, "
        "...) or CompressedImage, and CameraInfo; topics found by type where the bag has one "
        "of each kind",
    )
    b.add_argument("--bag", type=Path, metavar="BAG",
                   help="a ROS 2 bag's folder, .db3 or .mcap, or a ROS 1 .bag file "
                   "(rosbag record's, a RealSense Viewer recording's)")  # fmt: skip
    b.add_argument("--at", type=cli_args.float_at_least(0.0), default=0.0, metavar="S",
                   help="the depth image received nearest S s after the depth topic's first "
                   "(%(default)s); the colour nearest it by stamp, within 50 ms")  # fmt: skip
    b.add_argument("--depth-topic", default=None, metavar="TOPIC",
                   help="the depth image topic (default: the bag's only one)")  # fmt: skip
    b.add_argument("--rgb-topic", default=None, metavar="TOPIC",
                   help="the colour image topic, registered to the depth (default: the "
                   "bag's only other image topic, if any)")  # fmt: skip
    b.add_argument("--camera-info-topic", default=None, metavar="TOPIC",
                   help="the camera info (default: the depth topic's sibling camera_info, "
                   "else the bag's only one)")  # fmt: skip
    b.add_argument("--no-rgb", action="store_true",
                   help="the depth alone, whatever colour the bag holds")  # fmt: skip
    b.add_argument("--world-frame", default=None, metavar="FRAME",
                   help="top view: the camera's pose in FRAME (z up) from the bag's "
                   "/tf_static, instead of --T-world-cam")  # fmt: skip
    b.add_argument("--ee-frame", default=None, metavar="FRAME",
                   help="side view: the camera's pose in FRAME (the TCP between the jaws) "
                   "from the bag's /tf_static, instead of --T-ee-cam")  # fmt: skip


def wants_files(args: argparse.Namespace) -> bool:
    """Whether ``comgrasp views`` runs on the user's files (any of them named)."""
    return any(getattr(args, k, None) is not None
               for k in ("rgb", "depth", "camera_info", "bag"))  # fmt: skip


def read_pose(path: Path, name: str) -> np.ndarray:
    """A (4, 4) rigid transform from JSON (a 4x4 list, or {name: 4x4}) or whitespace text."""
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise CameraFileError(f"cannot read {name} from {path}: {exc}") from None
    try:
        value = json.loads(text)
        if isinstance(value, dict):
            value = value.get(name)
    except json.JSONDecodeError:
        value = _autolab_tf(text) if path.suffix == ".tf" else _rows(text)
    if value is None:
        raise CameraFileError(f"{path} must hold {name} as a 4x4 matrix: JSON [[...], ...] or "
                              f'{{"{name}": [[...], ...]}}, 4 rows of 4 numbers, or an '
                              "autolab_core .tf (from and to frames, translation, rotation "
                              "rows)")  # fmt: skip
    try:
        return check_transform(value, name)
    except InvalidInputError as exc:
        raise CameraFileError(f"{path}: {exc}") from None


def _rows(text: str) -> np.ndarray | None:
    try:
        return np.loadtxt(text.splitlines(), ndmin=2)
    except ValueError:
        return None


def _autolab_tf(text: str) -> np.ndarray | None:
    """autolab_core's RigidTransform file (Dex-Net's, GQ-CNN's camera poses): the from and
    to frames, the translation, the rotation's 3 rows; the transform from -> to."""
    lines = [line for line in text.splitlines() if line.strip()]
    numbers = _rows("\n".join(lines[2:6])) if len(lines) >= 6 else None
    if numbers is None or numbers.shape != (4, 3):
        return None
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = numbers[1:], numbers[0]
    return T


def _pick_area(text: str) -> tuple[float, float, float, float]:
    try:
        area = tuple(float(v) for v in text.split(","))
    except ValueError:
        area = ()
    if len(area) != 4 or not all(np.isfinite(area)) or area[0] >= area[1] or area[2] >= area[3]:
        raise InvalidInputError(f"--pick-area must be X0,X1,Y0,Y1 in m with X0 < X1 and "
                                f"Y0 < Y1, got {text!r}")  # fmt: skip
    return area


def _from_files(args) -> tuple:
    """(RgbdFiles, what the JSON says of them, the outputs' name) of --rgb/--depth/--camera-info."""
    from comgrasp_pin.perception.frames.rgbd_files import read_rgbd

    tf_only = [f"--{k.replace('_', '-')}" for k in ("world_frame", "ee_frame")
               if getattr(args, k) is not None]  # fmt: skip
    if tf_only:
        raise InvalidInputError(f"{', '.join(tf_only)} reads the camera's pose from a bag's "
                                "/tf_static: it needs --bag (else --T-world-cam, "
                                "--T-ee-cam)")  # fmt: skip
    missing = [f"--{k.replace('_', '-')}" for k in ("depth", "camera_info")
               if getattr(args, k) is None]  # fmt: skip
    if missing:
        raise InvalidInputError(f"your own frames need --depth and --camera-info (--rgb is "
                                f"optional), or --bag; missing {', '.join(missing)}")  # fmt: skip
    if args.bgr and args.rgb is None:
        raise InvalidInputError("--bgr tells the colour file's channel order: it needs --rgb")
    order = "bgr" if args.bgr else "rgb"
    files = read_rgbd(args.rgb, args.depth, args.camera_info, args.depth_scale, order)
    return files, {"colour": str(args.rgb) if args.rgb is not None else False}, args.depth.stem


def _from_bag(args) -> tuple:
    """(RgbdFiles, what the JSON says of them, the outputs' name, the pose from /tf_static
    of the camera in a named frame) of --bag."""
    from comgrasp_pin.perception.frames.rgbd_bag import read_rgbd_bag
    from comgrasp_pin.perception.frames.static_tf import camera_pose

    given = [f"--{k.replace('_', '-')}" for k in ("rgb", "depth", "camera_info")
             if getattr(args, k) is not None] + (["--bgr"] if args.bgr else [])  # fmt: skip
    if given:
        raise InvalidInputError(f"--bag reads the frame from the bag: drop {', '.join(given)} "
                                "(the bag's topics are named with --depth-topic, --rgb-topic, "
                                "--camera-info-topic)")  # fmt: skip
    frame = read_rgbd_bag(args.bag, args.at, args.depth_topic, args.rgb_topic,
                          args.camera_info_topic, not args.no_rgb, args.depth_scale)  # fmt: skip
    source = {"colour": frame.rgb_topic or False,
              "bag": {"path": str(args.bag), "depth_topic": frame.depth_topic,
                      "rgb_topic": frame.rgb_topic, "camera_info_topic": frame.info_topic,
                      "time_s": frame.time_s, "colour_skew_s": frame.skew_s}}  # fmt: skip
    for flag, given in (("--T-world-cam", "world_frame"), ("--T-ee-cam", "ee_frame")):
        if getattr(args, given) is not None and getattr(args, flag[2:].replace("-", "_")):
            raise InvalidInputError(f"give the camera's pose once: {flag} or "
                                    f"--{given.replace('_', '-')}")  # fmt: skip
    name = f"{args.bag.resolve().name}_at_{1e3 * frame.time_s:.0f}ms"
    return frame.files, source, name, lambda target: camera_pose(frame.transforms, target,
                                                                  frame.frame_id)  # fmt: skip


def _camera_json(files, color_order: str | None) -> dict:
    c = files.camera
    return {"width": c.width, "height": c.height, "K": c.K.tolist(),
            "distortion_model": c.distortion_model, "D": c.D.tolist(),
            "undistorted": c.distorted, "depth_scale": files.depth_scale,
            "color_order_in_file": color_order}  # fmt: skip


def _top(args, rgb, depth, camera, tf_pose) -> tuple[np.ndarray, dict]:
    from comgrasp_pin.perception import detect_rod_top_down, draw_top_view
    from comgrasp_pin.perception.top_view.table_plane import fit_table_plane

    if args.T_world_cam is not None or args.world_frame is not None:
        frame = "world"
        if args.T_world_cam is not None:
            T = read_pose(args.T_world_cam, "T_world_cam")
        else:
            T = tf_pose(args.world_frame)
        if args.pick_area is None:
            raise InvalidInputError("--T-world-cam needs --pick-area X0,X1,Y0,Y1 (m, in its "
                                    "frame): where on the table the rod lies")  # fmt: skip
    else:
        frame, (T, area) = "table", fit_table_plane(depth, camera)
    if args.pick_area is not None:
        area = _pick_area(args.pick_area)
    det = detect_rod_top_down(rgb, depth, camera, T, area)  # rgb None: the depth alone
    g = det.grasp
    measured = {
        "view": "top", "frame": frame, f"T_{frame}_cam": T.tolist(), "pick_area_m": list(area),
        "centre_m": [g.x, g.y, g.z], "yaw_rad": g.yaw, "yaw_deg": float(np.degrees(g.yaw)),
        "length_m": det.length, "handle_height_m": det.handle_height,
        "table_z_m": det.table_z, "overhang_m": det.overhang,
    }  # fmt: skip
    return draw_top_view(rgb, det, det.axis_px.mean(axis=0), depth=depth), measured


def _side(args, files, rgb, depth, camera, tf_pose) -> tuple[np.ndarray, dict]:
    from comgrasp_pin.perception import draw_side_view, observe_held_rod

    if args.T_ee_cam is not None:
        T_ee_cam = read_pose(args.T_ee_cam, "T_ee_cam")
    elif args.ee_frame is not None:
        T_ee_cam = tf_pose(args.ee_frame)
    else:
        raise InvalidInputError("--view side needs --T-ee-cam FILE (or, with --bag, "
                                "--ee-frame): the camera's pose in the ee frame (the TCP "
                                "between the jaws)")  # fmt: skip
    # the frame as read: an integer depth's rounding is an error the side view allows for
    view = observe_held_rod(files.rgb, files.depth, files.camera, T_ee_cam,
                            depth_scale=files.depth_scale)  # fmt: skip
    measured = {
        "view": "side", "frame": "ee", "T_ee_cam": T_ee_cam.tolist(),
        "T_ee_obj": view.T_ee_obj.tolist(), "tilt_rad": view.theta,
        "tilt_from_level_deg": tilt_from_level_deg(view.theta), "length_m": view.length,
        "grasp_offset_m": view.grasp_offset, "radius_m": view.radius,
    }  # fmt: skip
    return draw_side_view(rgb, view, depth=depth), measured


def run(args: argparse.Namespace) -> int:
    """``comgrasp views`` on the user's files: writes OUT/<depth>_<view>_view.png and .json."""
    import cv2

    from comgrasp_pin.perception.frames.camera_input import camera_frame

    if args.bag is not None:
        files, source, name, tf_pose = _from_bag(args)
    else:
        files, source, name = _from_files(args)
        tf_pose = None
    rgb, depth, camera = camera_frame(files.rgb, files.depth, files.camera, files.depth_scale)
    if args.view == "top":
        image, measured = _top(args, rgb, depth, camera, tf_pose)
    else:  # the side view reads the frame as read too: an integer depth's steps
        image, measured = _side(args, files, rgb, depth, camera, tf_pose)
    measured.update(source)
    in_file = (
        ("bgr" if args.bgr else "rgb") if args.rgb is not None else None
    )  # a bag's: its encoding
    measured["camera"] = _camera_json(files, in_file)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    stem = f"{name}_{args.view}_view"  # (a name's dots are no suffix: frame.001.png)
    png, js = out / f"{stem}.png", out / f"{stem}.json"
    cv2.imwrite(str(png), image)
    js.write_text(json.dumps(measured, indent=2) + "\n")
    print(json.dumps({k: v for k, v in measured.items() if not k.startswith("T_")}, indent=2))
    print(f"wrote {png}\nwrote {js}")
    return 0
