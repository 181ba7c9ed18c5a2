"""Payload out: the file every robot controller takes, from the same ``Payload``.

The payload's mass, CoM and inertia about the CoM are in the flange frame (SI); each text
below converts them to the units and frames its vendor documents (sources: docs/robot.md).
Every file says how its inertia was made: an approximation (static torques cannot see it),
or identified from a motion, with its standard deviation.

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
- Franka Desk's end-effector configuration (``endeffector-config.json``, Settings > End
  effector): ``mass`` (kg), ``centerOfMass`` (m, flange frame F), ``inertia`` (the 3x3
  about the CoM, 9 numbers column-major, kg m^2) and ``transformation`` (F_T_EE, the end
  effector frame in F, 16 numbers column-major, m). JSON has no comments.
- KUKA KRL ``$LOAD={M m,CM {X x,Y y,Z z,A a,B b,C c},J {X jx,Y jy,Z jz}}``: M in kg; X, Y, Z
  the CoM in mm in the flange coordinate system; A, B, C in degrees orient the principal
  inertia axes (A about Z, then B about the new Y, then C about the new X: R = Rz Ry Rx);
  J the principal moments about the CoM, kg m^2.
- KUKA Sunrise (LBR iiwa, Java): ``new LoadData(m, XyzAbcTransformation.ofDeg(x, y, z, a, b,
  c), new Inertia(jx, jy, jz))``, the same numbers as the KRL line.
- ABB RAPID ``loaddata``: ``[mass, [x, y, z], [q1, q2, q3, q4], ix, iy, iz]``: kg; the CoG in
  mm; aom, the principal axes' orientation as a unit quaternion (q1 the scalar part); the
  principal moments, kg m^2; all in the payload's frame (tool0, the wrist frame, for a
  tool's ``tload``; the tool's frame for a payload it holds).
- MoveIt ``moveit_msgs/msg/AttachedCollisionObject`` as YAML: ``link_name``, ``object``
  (``header.frame_id``, ``pose`` at the CoM in flange axes, ``id``, a cylinder primitive when
  the inertia is the cylinder approximation), ``touch_links`` and ``weight`` (the message
  states no unit; the mass in kg is written).

The principal axes are the inertia's eigenvectors, ordered and signed so that their
rotation is the one closest to the identity (none for a diagonal inertia).
"""

from __future__ import annotations

import itertools
import json
from pathlib import Path

import numpy as np
import pinocchio as pin
import yaml

from comgrasp_pin import validate
from comgrasp_pin.errors import InvalidInputError, OutputError
from comgrasp_pin.estimation.trust import IDENTIFIED
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


def principal_axes(inertia: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The principal moments and axes of a symmetric inertia.

    Args:
        inertia: (3, 3) inertia about the CoM (kg m^2), axes of some frame F.

    Returns:
        (moments (3,), R (3, 3)): ``inertia = R @ diag(moments) @ R.T``; R's columns are the
        principal axes in F, a rotation (det +1), the one closest to the identity among the
        equivalent orders and signs (the identity for a diagonal inertia).
    """
    I = 0.5 * (np.asarray(inertia, float) + np.asarray(inertia, float).T)
    if np.abs(I - np.diag(np.diag(I))).max() <= 1e-12 * np.abs(I).max():
        return np.diag(I).copy(), np.eye(3)
    w, V = np.linalg.eigh(I)
    best = (-np.inf, w, V)
    for perm in itertools.permutations(range(3)):
        for signs in itertools.product((1.0, -1.0), repeat=3):
            R = V[:, perm] * np.array(signs)
            if np.linalg.det(R) > 0 and np.trace(R) > best[0]:
                best = (float(np.trace(R)), w[list(perm)], R)
    return best[1], best[2]


def _fixed(value: float, decimals: int) -> str:
    """``value`` with at most ``decimals`` decimals, no exponent (KRL and RAPID literals)."""
    text = f"{float(value):.{decimals}f}".rstrip("0")
    text = text + "0" if text.endswith(".") else text
    return "0.0" if float(text) == 0 else text


def _kuka_numbers(p: Payload) -> tuple[list[str], list[str], list[str]]:
    """KUKA's CoM (mm), A, B, C (deg) and principal moments (kg m^2), as literals."""
    moments, R = principal_axes(p.inertia_flange)
    roll, pitch, yaw = pin.rpy.matrixToRpy(R)  # R = Rz(yaw) Ry(pitch) Rx(roll)
    com = [_fixed(v, 4) for v in 1e3 * p.com_flange]
    abc = [_fixed(v, 5) for v in np.degrees([yaw, pitch, roll])]
    return com, abc, [_fixed(v, 9) for v in moments]


def krl_load(p: Payload) -> str:
    """A KRL text: comments (``;``) and one ``$LOAD=...`` line (KUKA KSS)."""
    (x, y, z), (a, b, c), (jx, jy, jz) = _kuka_numbers(p)
    head = "".join(f"; {line}\n" for line in header_lines(p))
    head += (f"; KUKA $LOAD: M kg; CM X, Y, Z mm in the flange frame ({p.flange_frame}); "
             "A, B, C deg (Z, Y', X'') to the principal axes; J kg m^2 about them\n")  # fmt: skip
    return (f"{head}$LOAD={{M {_fixed(p.mass, 6)},CM {{X {x},Y {y},Z {z},A {a},B {b},C {c}}},"
            f"J {{X {jx},Y {jy},Z {jz}}}}}\n")  # fmt: skip


def sunrise_load_data(p: Payload) -> str:
    """A Java statement for KUKA Sunrise (LBR iiwa): a ``LoadData`` with the KRL numbers."""
    (x, y, z), (a, b, c), (jx, jy, jz) = _kuka_numbers(p)
    head = "".join(f"// {line}\n" for line in header_lines(p))
    head += ("// KUKA Sunrise LoadData: mass kg; centre of mass mm and A, B, C deg (principal "
             f"axes) in the flange frame ({p.flange_frame}); moments kg m^2\n")  # fmt: skip
    return (f"{head}LoadData loadData = new LoadData({_fixed(p.mass, 6)}, "
            f"XyzAbcTransformation.ofDeg({x}, {y}, {z}, {a}, {b}, {c}), "
            f"new Inertia({jx}, {jy}, {jz}));\n")  # fmt: skip


def rapid_loaddata(p: Payload, name: str = "comgrasp_load") -> str:
    """A RAPID text: comments (``!``) and one ``PERS loaddata`` declaration (ABB)."""
    moments, R = principal_axes(p.inertia_flange)
    q = pin.Quaternion(R)
    quat_wxyz = np.array([q.w, q.x, q.y, q.z])
    quat_wxyz *= 1.0 if quat_wxyz[0] >= 0 else -1.0  # q and -q are the same rotation
    cog = ", ".join(_fixed(v, 4) for v in 1e3 * p.com_flange)
    aom = ", ".join(_fixed(v, 9) for v in quat_wxyz)
    inertia = ", ".join(_fixed(v, 9) for v in moments)
    head = "".join(f"! {line}\n" for line in header_lines(p))
    head += (f"! ABB loaddata: mass kg; cog mm in {p.flange_frame}; aom [q1 (scalar), q2, q3, "
             "q4] to the principal axes; ix, iy, iz kg m^2 about them\n")  # fmt: skip
    return f"{head}PERS loaddata {name} := [{_fixed(p.mass, 6)}, [{cog}], [{aom}], {inertia}];\n"


def franka_desk(p: Payload, T_flange_ee: np.ndarray | None = None) -> dict:
    """Franka Desk's end-effector configuration (``endeffector-config.json``) as a dict.

    Args:
        p: the payload, in the flange frame F (``panda_link8`` / ``fr3_link8``).
        T_flange_ee: (4, 4) the end effector frame (TCP) in F, m; default the identity.
    """
    T = np.eye(4) if T_flange_ee is None else _pose_matrix(T_flange_ee, "T_flange_ee")
    desk = {
        "mass": float(p.mass),
        "centerOfMass": [float(v) for v in p.com_flange],
        "transformation": [float(v) for v in T.ravel(order="F")],
        "inertia": [float(v) for v in p.inertia_flange.ravel(order="F")],
    }
    if p.verdict not in (None, IDENTIFIED):  # JSON has no comments: the note as a key
        desk["_comment"] = " ".join(header_lines(p))
    return desk


def _pose_matrix(T: object, name: str) -> np.ndarray:
    """``T`` as a finite (4, 4) rigid transform, or InvalidInputError."""
    T = validate.finite_array(T, name, (4, 4))
    R = T[:3, :3]
    if not (np.allclose(R.T @ R, np.eye(3), atol=1e-6) and np.linalg.det(R) > 0):
        raise InvalidInputError(f"{name} must be a rigid transform (a rotation and a "
                                f"translation, last row 0 0 0 1); got\n{T}")  # fmt: skip
    if not np.allclose(T[3], [0, 0, 0, 1]):
        raise InvalidInputError(f"{name}: its last row must be 0 0 0 1; got {T[3]}")
    return T


def _pose(position: np.ndarray, R: np.ndarray) -> dict:
    q = pin.Quaternion(np.asarray(R, float))
    return {
        "position": dict(zip("xyz", (float(v) for v in position), strict=True)),
        "orientation": {"x": float(q.x), "y": float(q.y), "z": float(q.z), "w": float(q.w)},
    }


def _cylinder(p: Payload) -> tuple[float, float, np.ndarray] | None:
    """(L, R, axis in the flange frame) of the cylinder approximation, or None."""
    kind, _, rest = p.inertia_model.partition(":")
    if kind != "cylinder":
        return None
    try:
        length, radius = (float(v) for v in rest.split(",")[:2])
    except ValueError:  # not the spec payload_in_flange writes: no geometry, only the mass
        return None
    w, V = np.linalg.eigh(p.inertia_flange)  # the axis: the moment m R^2 / 2
    return length, radius, V[:, int(np.argmin(np.abs(w - p.mass * radius**2 / 2)))]


def moveit_yaml(
    p: Payload,
    link_name: str | None = None,
    T_link_flange: np.ndarray | None = None,
    object_id: str = "payload",
) -> str:
    """A ``moveit_msgs/msg/AttachedCollisionObject`` as YAML (``ros2 topic pub`` syntax).

    Args:
        p: the payload.
        link_name: the robot link it is attached to; default the flange frame.
        T_link_flange: (4, 4) the flange frame in that link; default the identity.
        object_id: the collision object's id.

    The object's pose is the CoM with the flange frame's axes, in ``link_name``. A cylinder
    primitive (height L, radius R, its axis along the primitive's z) is added when the
    inertia is the cylinder approximation; otherwise no geometry: MoveIt then attaches the
    world object of that id, which must exist in the planning scene.
    """
    link = link_name or p.flange_frame
    T = np.eye(4) if T_link_flange is None else _pose_matrix(T_link_flange, "T_link_flange")
    obj: dict = {
        "header": {"frame_id": link},
        "pose": _pose(T[:3, :3] @ p.com_flange + T[:3, 3], T[:3, :3]),
        "id": object_id,
    }
    cylinder = _cylinder(p)
    if cylinder is not None:
        length, radius, axis = cylinder
        z_to_axis = pin.Quaternion.FromTwoVectors(np.array([0.0, 0.0, 1.0]), axis)
        obj["primitives"] = [{"type": 3, "dimensions": [length, radius]}]  # 3: CYLINDER
        obj["primitive_poses"] = [_pose(np.zeros(3), z_to_axis.toRotationMatrix())]
    obj["operation"] = 0  # ADD
    msg = {"link_name": link, "object": obj, "touch_links": [link], "weight": float(p.mass)}
    head = "".join(f"# {line}\n" for line in header_lines(p))
    head += "# moveit_msgs/msg/AttachedCollisionObject; weight: the mass in kg\n"
    return head + yaml.safe_dump(msg, sort_keys=False, default_flow_style=None)
