"""Payload out: files a UR, a Franka or a ROS 2 controller takes.

Field names and conventions, as their documentation states them:
- URScript ``set_target_payload(m, cog, inertia=[0,0,0,0,0,0], transition_time=0)``: m in kg;
  cog [CoGx, CoGy, CoGz] the offset (m) from the tool mount (the flange, ``tool0``); inertia
  [Ixx, Iyy, Izz, Ixy, Ixz, Iyz] (kg m^2) with origin in the CoG and axes aligned with the
  tool flange axes (UR Script manual, "set_target_payload", PolyScope 5.x).
- libfranka ``Robot::setLoad(double load_mass, const std::array<double, 3>& F_x_Cload,
  const std::array<double, 9>& load_inertia)``: F_x_Cload the CoM in the flange frame F (m),
  load_inertia the 3x3 inertia (kg m^2) in column-major order.
- ROS 2 ``ur_msgs/srv/SetPayload`` request: ``float32 mass``, ``geometry_msgs/Vector3
  center_of_gravity``; since Jazzy also ``float64 ixx, iyy, izz, ixy, ixz, iyz`` and
  ``builtin_interfaces/Duration transition_time`` (docs.ros.org, ur_msgs SetPayload).
- ROS 2 ``franka_msgs/srv/SetLoad`` request: ``float64 mass``, ``float64[3] center_of_mass``,
  ``float64[9] load_inertia`` (3x3, column-major) (docs.ros.org, franka_msgs SetLoad).

Every file says how its inertia was made: an approximation (static torques cannot see it),
or identified from a motion, with its standard deviation.
"""

from __future__ import annotations

import json
from pathlib import Path

from comgrasp_pin.errors import OutputError
from comgrasp_pin.robot_io.payload_files.payload import Payload, header_lines, six_components


def _list(values) -> str:
    return "[" + ", ".join(f"{float(v):.9g}" for v in values) + "]"


def urscript(p: Payload) -> str:
    """A URScript program text: comments and one ``set_target_payload`` line."""
    head = "".join(f"# {line}\n" for line in header_lines(p))
    return (
        f"{head}set_target_payload({p.mass:.9g}, {_list(p.com_flange)}, "
        f"{_list(six_components(p.inertia_flange))})\n"
    )


def franka_load(p: Payload) -> dict:
    """The arguments of libfranka's ``setLoad`` as a dict (plus a ``comment`` and the frame)."""
    return {
        "mass": float(p.mass),
        "F_x_Cload": [float(v) for v in p.com_flange],
        "load_inertia": [float(v) for v in p.inertia_flange.ravel(order="F")],
        "frame": p.flange_frame,
        "comment": " ".join(header_lines(p)),
    }


def ros2_yaml(p: Payload) -> str:
    """YAML with the request fields of ur_msgs/srv/SetPayload and franka_msgs/srv/SetLoad."""
    c = p.com_flange
    ixx, iyy, izz, ixy, ixz, iyz = six_components(p.inertia_flange)
    head = "".join(f"# {line}\n" for line in header_lines(p))
    return (
        f"{head}"
        "# ur_msgs/srv/SetPayload request (ixx..transition_time: Jazzy and later)\n"
        "ur_msgs/srv/SetPayload:\n"
        f"  mass: {p.mass:.9g}\n"
        f"  center_of_gravity: {{x: {c[0]:.9g}, y: {c[1]:.9g}, z: {c[2]:.9g}}}\n"
        f"  ixx: {ixx:.9g}\n  iyy: {iyy:.9g}\n  izz: {izz:.9g}\n"
        f"  ixy: {ixy:.9g}\n  ixz: {ixz:.9g}\n  iyz: {iyz:.9g}\n"
        "  transition_time: {sec: 0, nanosec: 0}\n"
        "# franka_msgs/srv/SetLoad request (load_inertia: 3x3, column-major)\n"
        "franka_msgs/srv/SetLoad:\n"
        f"  mass: {p.mass:.9g}\n"
        f"  center_of_mass: {_list(c)}\n"
        f"  load_inertia: {_list(p.inertia_flange.ravel(order='F'))}\n"
    )


def write_text(path: str | Path, text: str) -> Path:
    """Write ``text`` to ``path``; OutputError naming the path where it cannot be written."""
    path = Path(path)
    try:
        path.write_text(text)
    except OSError as exc:
        raise OutputError(f"cannot write {path}: {exc}") from None
    return path


def write_urscript(p: Payload, path: str | Path) -> Path:
    """Write ``urscript(p)`` to ``path``."""
    return write_text(path, urscript(p))


def write_franka(p: Payload, path: str | Path) -> Path:
    """Write ``franka_load(p)`` as JSON to ``path``."""
    return write_text(path, json.dumps(franka_load(p), indent=2) + "\n")


def write_ros2(p: Payload, path: str | Path) -> Path:
    """Write ``ros2_yaml(p)`` to ``path``."""
    return write_text(path, ros2_yaml(p))
