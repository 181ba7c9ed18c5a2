"""Bare arms in MuJoCo for motion tests: the project's UR5 and example-robot-data's Panda.

Each arm is compiled by MuJoCo's own URDF reader from the URDF Pinocchio reads, with the
visual and collision elements removed (MuJoCo cannot read the Panda's ``.dae`` meshes, and a
motion test needs no contacts): kinematics and inertials only, so that MuJoCo's dynamics are
an independent computation of the same robot (``tests/test_payload_motion.py`` checks its
bias forces and mass matrix against Pinocchio's RNEA and CRBA). The gripper's finger joints
are removed, the fingers welded where ``RobotModel`` locks them (the URDF's zero, Pinocchio's
neutral), and a payload, if any, is welded to the ee frame with its exact inertia.

What a URDF does not say, added here:

- Joint friction, Coulomb (MuJoCo ``frictionloss``, N m) and viscous (``damping``,
  N m s/rad): the friction *between the torque sensor and the link* (output bearing and
  seals), which a link-side sensor sees (DESIGN section 8: a Franka's identified Coulomb
  friction is about 0.25 N m on joint 1). The gear's and motor's much larger friction lies
  on the drive side of the sensor; the simulated drive is a torque source after it
  (``payload_motion``), so it is not modelled.
- No armature: a motor's rotor inertia is on the drive side of a link-side sensor too.
- Contacts off (the arm moves through free space; self-collision is the planner's job).
- A wrist force/torque sensor (``world.add_ft_sensor``: a site and MuJoCo's force and torque
  sensors) at the origin of ``SENSOR_FRAME[arm]``, a frame of the same URDF (Pinocchio's
  too): the UR5's ``ft_sensor`` between flange and gripper, the Panda's ``panda_hand`` (the
  hand's mount on the flange). It measures the hand, its fingers and the payload.

Frames: the payload's numbers are in the ee frame of DESIGN section 3, the tool centre
point between the fingers: ``eelink`` on the UR5, ``panda_hand_tcp`` on the Panda (10.34 cm
beyond the flange ``panda_link8``, turned -45 deg about z with the hand).
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

import mujoco
import numpy as np

from comgrasp_pin._paths import example_robot_urdf, urdf_path
from comgrasp_pin.errors import InvalidInputError
from comgrasp_pin.robot import UR5_URDF, RobotModel
from comgrasp_pin.simulation.payloads import Payload
from comgrasp_pin.simulation.world import add_ft_sensor

ARMS = ("ur5", "panda")
PANDA_URDF = "panda_description/urdf/panda.urdf"  # in example-robot-data
EE_FRAME = {"ur5": "eelink", "panda": "panda_hand_tcp"}
PAYLOAD_BODY = "payload"
SENSOR_FRAME = {"ur5": "ft_sensor", "panda": "panda_hand"}
"""The wrist sensor's frame on each arm (a URDF link welded between flange and hand)."""
SIM_DT = 1e-3  # s

# (Coulomb (N m), viscous (N m s/rad)) per joint, link side of the sensor. Panda: about the
# identified 0.25 N m on the four big joints, less on the wrist; the UR5 as if it had the same
# class of link-side sensors (its bigger joints a little more). Assumptions of this size, not
# identified values.
JOINT_FRICTION = {
    "ur5": ((0.4, 0.4, 0.3, 0.15, 0.15, 0.15), (0.1, 0.1, 0.1, 0.05, 0.05, 0.05)),
    "panda": ((0.25, 0.25, 0.25, 0.25, 0.15, 0.15, 0.15), (0.05,) * 7),
}


def _check_arm(arm: str) -> None:
    if arm not in ARMS:
        raise InvalidInputError(f"unknown arm {arm!r}; the motion worlds are {ARMS}")


def arm_urdf(arm: str) -> Path:
    """The URDF both Pinocchio and MuJoCo read for ``arm`` ("ur5" or "panda")."""
    _check_arm(arm)
    return urdf_path(UR5_URDF) if arm == "ur5" else example_robot_urdf(PANDA_URDF)


def arm_robot(arm: str) -> RobotModel:
    """Pinocchio's model of the empty arm (fingers locked), ee frame ``EE_FRAME[arm]``."""
    _check_arm(arm)
    if arm == "ur5":
        return RobotModel.ur5()
    return RobotModel.from_urdf(arm_urdf(arm), EE_FRAME[arm])


def arm_world(
    arm: str, payload: Payload | None = None
) -> tuple[mujoco.MjModel, tuple[str, ...], str]:
    """The arm compiled by MuJoCo, holding ``payload`` (or nothing) in its ee frame.

    Returns:
        (model, joint_names, ee_body): the MuJoCo model (time step ``SIM_DT``, joint
        friction ``JOINT_FRICTION[arm]``, gravity -9.81 m/s^2 along world z), the arm's
        joint names in the order of its ``qpos`` (the order of ``arm_robot(arm)``), and the
        ee body the payload body ``"payload"`` is welded to. The model carries the wrist
        sensor ``world.FT_SENSORS`` at ``SENSOR_FRAME[arm]``.
    """
    _check_arm(arm)
    spec = mujoco.MjSpec.from_string(_kinematics_only(arm_urdf(arm)))
    robot_joints = tuple(arm_robot(arm).joint_names)
    for equality in list(spec.equalities):  # the Panda's mimic finger
        spec.delete(equality)
    for joint in list(spec.joints):
        if joint.name not in robot_joints:
            spec.delete(joint)
    coulomb, viscous = JOINT_FRICTION[arm]
    for name, f_coulomb, f_viscous in zip(robot_joints, coulomb, viscous, strict=True):
        joint = spec.joint(name)
        joint.frictionloss = f_coulomb
        joint.damping = np.array([f_viscous, 0.0, 0.0])
        joint.armature = 0.0
    ee_body = EE_FRAME[arm]
    if payload is not None:
        body = spec.body(ee_body).add_body(name=PAYLOAD_BODY)
        body.mass = payload.mass
        body.ipos = payload.p_com_ee
        I = payload.I_com_ee  # noqa: E741
        body.fullinertia = [I[0, 0], I[1, 1], I[2, 2], I[0, 1], I[0, 2], I[1, 2]]
        body.explicitinertial = True
    add_ft_sensor(spec, SENSOR_FRAME[arm])
    spec.option.timestep = SIM_DT
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    spec.option.disableflags |= mujoco.mjtDisableBit.mjDSBL_CONTACT
    model = spec.compile()
    names = tuple(model.joint(i).name for i in range(model.njnt))
    if names != robot_joints:
        raise AssertionError(f"MuJoCo's joints {names} are not Pinocchio's {robot_joints}")
    return model, names, ee_body


def _kinematics_only(urdf: Path) -> str:
    """The URDF's text without visual and collision elements, with MuJoCo's compiler options
    (static bodies kept, so that the ee frame's body exists)."""
    root = ET.parse(urdf).getroot()
    for link in root.iter("link"):
        for element in link.findall("visual") + link.findall("collision"):
            link.remove(element)
    extension = ET.SubElement(root, "mujoco")
    ET.SubElement(extension, "compiler", fusestatic="false", discardvisual="false")
    return ET.tostring(root, encoding="unicode")
