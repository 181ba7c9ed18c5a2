"""Payload out into robot models: the robot's URDF with the payload in it, an MJCF body.

- ``urdf_with_payload``: the robot's own URDF (the file the robot was read from, checked as
  every description is) with a fixed joint ``payload_joint`` and a link ``payload`` on the
  ee frame: the link's frame is the ee frame, its ``<inertial>`` the payload (origin at the
  CoM, no rotation, so the inertia is about the CoM in the ee frame's axes; kg, m, kg m^2).
  The ee frame may be a link of the URDF or a joint (Pinocchio names a frame after each);
  a joint's frame is its child link's, so the payload goes on that link.
- ``mjcf_payload_body``: ``<body name="payload">`` with ``<inertial pos mass fullinertia>``
  (MuJoCo's order Ixx Iyy Izz Ixy Ixz Iyz, about the CoM), its frame the flange frame, placed
  in the body MuJoCo makes for the link of the flange's last moving joint (the link's name is
  in a comment); a point mass (or any inertia with a zero moment) is written with
  ``quat`` and ``diaginertia``, since MuJoCo refuses a singular ``fullinertia``.

Both files carry a comment that says how the inertia was made.
"""

from __future__ import annotations

import os
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pinocchio as pin

from comgrasp_pin.errors import InvalidInputError
from comgrasp_pin.file_checks import read_description
from comgrasp_pin.robot import RobotModel
from comgrasp_pin.robot_io.payload_files.controller_files import principal_axes
from comgrasp_pin.robot_io.payload_files.payload import Payload, T_flange_ee, header_lines

PAYLOAD_LINK, PAYLOAD_JOINT = "payload", "payload_joint"


def _g(value: float) -> str:
    return repr(float(value) + 0.0)  # + 0.0: no "-0.0"


def _vec(values) -> str:
    return " ".join(_g(v) for v in values)


def _comment(p: Payload):
    return ET.Comment(" " + " | ".join(header_lines(p)).replace("--", "- -") + " ")


def _frame_pose(robot: RobotModel, name: str) -> np.ndarray:
    """(4, 4) the pose of frame ``name`` of the full model at its neutral configuration."""
    model = robot.full_model
    data = model.createData()
    pin.framesForwardKinematics(model, data, pin.neutral(model))
    return data.oMf[model.getFrameId(name)].homogeneous


def urdf_link_of(robot: RobotModel, frame: str, root: ET.Element) -> tuple[str, np.ndarray]:
    """The URDF link that ``frame`` is fixed on, and (4, 4) T_link_frame.

    Args:
        robot: the robot read from the URDF whose root element is ``root``.
        frame: a frame of the robot: a link's name, or a joint's (its child link's frame).
        root: the URDF's ``<robot>`` element.

    Raises:
        InvalidInputError: ``frame`` is neither a link nor a joint of the URDF.
    """
    links = {str(link.get("name")) for link in root.findall("link")}
    children = {j.get("name"): child.get("link") for j in root.findall("joint")
                if (child := j.find("child")) is not None}  # fmt: skip
    link = frame if frame in links else children.get(frame)
    if link is None or not robot.full_model.existFrame(frame):
        raise InvalidInputError(f"frame {frame!r} is neither a link nor a joint of the URDF; "
                                f"links: {sorted(links)}")  # fmt: skip
    return link, np.linalg.solve(_frame_pose(robot, link), _frame_pose(robot, frame))


def _origin(T: np.ndarray) -> ET.Element:
    return ET.Element("origin", xyz=_vec(T[:3, 3]), rpy=_vec(pin.rpy.matrixToRpy(T[:3, :3])))


def _payload_link(p: Payload, com: np.ndarray, inertia: np.ndarray) -> ET.Element:
    link = ET.Element("link", name=PAYLOAD_LINK)
    inertial = ET.SubElement(link, "inertial")
    inertial.append(ET.Element("origin", xyz=_vec(com), rpy="0 0 0"))
    inertial.append(ET.Element("mass", value=_g(p.mass)))
    I = inertia
    inertial.append(ET.Element("inertia", ixx=_g(I[0, 0]), ixy=_g(I[0, 1]), ixz=_g(I[0, 2]),
                               iyy=_g(I[1, 1]), iyz=_g(I[1, 2]), izz=_g(I[2, 2])))  # fmt: skip
    return link


def _relocate_meshes(root: ET.Element, source_dir: Path, out_dir: Path) -> None:
    """Relative mesh paths made relative to ``out_dir`` (package:// and URIs unchanged)."""
    for mesh in root.iter("mesh"):
        name = mesh.get("filename")
        if name and "://" not in name and not os.path.isabs(name):
            mesh.set("filename", os.path.relpath(source_dir / name, out_dir))


def urdf_with_payload(
    robot: RobotModel,
    p: Payload,
    urdf_path: str | Path | None = None,
    out_dir: str | Path | None = None,
) -> str:
    """The robot's URDF text with the payload as a fixed link ``payload`` on the ee frame.

    Args:
        robot: the robot, read from ``urdf_path`` (default ``robot.urdf_path``).
        p: the payload, in a frame on the ee frame's body (``T_flange_ee``).
        urdf_path: the URDF to copy.
        out_dir: the folder the text will be written in: relative mesh paths are rewritten
            to resolve from there; None keeps them as written.

    Raises:
        InvalidInputError: the URDF fails its checks, already has a ``payload`` link or
            ``payload_joint`` joint, or the ee frame is not a link or joint of it.
    """
    path = Path(urdf_path if urdf_path is not None else robot.urdf_path)  # type: ignore[arg-type]
    text = read_description(path, "URDF", robot.package_dirs)
    parser = ET.XMLParser(target=ET.TreeBuilder(insert_comments=True))
    root = ET.fromstring(text, parser=parser)
    names = {e.get("name") for e in root.findall("link")} | {
        e.get("name") for e in root.findall("joint")
    }
    if PAYLOAD_LINK in names or PAYLOAD_JOINT in names:
        raise InvalidInputError(f"{path} already has a link {PAYLOAD_LINK!r} or a joint "
                                f"{PAYLOAD_JOINT!r}: rename or remove them")  # fmt: skip
    link, T_link_ee = urdf_link_of(robot, robot.ee_frame, root)
    T_fe = T_flange_ee(robot, p.flange_frame)
    R_ef = T_fe[:3, :3].T
    com_ee = R_ef @ (p.com_flange - T_fe[:3, 3])
    joint = ET.Element("joint", name=PAYLOAD_JOINT, type="fixed")
    joint.append(ET.Element("parent", link=link))
    joint.append(ET.Element("child", link=PAYLOAD_LINK))
    joint.append(_origin(T_link_ee))
    new = [_comment(p), _payload_link(p, com_ee, R_ef @ p.inertia_flange @ R_ef.T), joint]
    if len(root):
        root[-1].tail = "\n  "
    for element in new:
        ET.indent(element, "  ", level=1)
        element.tail = "\n  "
        root.append(element)
    new[-1].tail = "\n"
    if out_dir is not None:
        _relocate_meshes(root, path.resolve().parent, Path(out_dir).resolve())
    return '<?xml version="1.0"?>\n' + ET.tostring(root, encoding="unicode") + "\n"


def body_of_frame(robot: RobotModel, frame: str) -> tuple[str, np.ndarray]:
    """The link of ``frame``'s last moving joint (MuJoCo's body for it), and T_link_frame."""
    model = robot.full_model
    joint = model.frames[model.getFrameId(frame)].parentJoint
    for f in model.frames:
        after_joint = model.frames[f.parentFrame].type == pin.FrameType.JOINT
        if f.type == pin.FrameType.BODY and f.parentJoint == joint and after_joint:
            return f.name, np.linalg.solve(_frame_pose(robot, f.name), _frame_pose(robot, frame))
    raise InvalidInputError(f"frame {frame!r} is not on a moving link")


def mjcf_payload_body(p: Payload, robot: RobotModel | None = None) -> str:
    """An MJCF ``<body name="payload">`` with the payload's ``<inertial>``, to paste in.

    Args:
        p: the payload; the body's frame is its flange frame.
        robot: where given, the body is placed in the body of the link of the flange's last
            moving joint (named in the comment); without it, at that body's origin (paste it
            into a body whose frame is the flange frame).
    """
    where, T = f"the body whose frame is {p.flange_frame}", np.eye(4)
    if robot is not None:
        parent, T = body_of_frame(robot, p.flange_frame)
        where = f'<body name="{parent}"> (the {p.flange_frame} frame in it)'
    q = pin.Quaternion(T[:3, :3])
    body = ET.Element("body", name=PAYLOAD_LINK, pos=_vec(T[:3, 3]),
                      quat=_vec([q.w, q.x, q.y, q.z]))  # fmt: skip
    body.append(_comment(p))
    I = 0.5 * (p.inertia_flange + p.inertia_flange.T)
    attributes = {"pos": _vec(p.com_flange), "mass": _g(p.mass)}
    if np.linalg.eigvalsh(I).min() > 1e-12 * max(np.trace(I), 1e-300):
        attributes["fullinertia"] = _vec([I[0, 0], I[1, 1], I[2, 2], I[0, 1], I[0, 2], I[1, 2]])
    else:
        moments, R = principal_axes(I)
        qa = pin.Quaternion(R)
        attributes |= {"quat": _vec([qa.w, qa.x, qa.y, qa.z]), "diaginertia": _vec(moments)}
    body.append(ET.Element("inertial", attributes))
    ET.indent(body, "  ")
    head = f"<!-- paste inside {where}: the payload, its frame {p.flange_frame} (kg, m, kg m^2) -->"
    return head + "\n" + ET.tostring(body, encoding="unicode") + "\n"
