"""The MuJoCo world: the robot compiled from the project's URDF, placed in the paper's scene.

``build_spec`` gives an editable ``mujoco.MjSpec`` (tests and the episode code add objects
or payloads to it); ``build_model`` compiles it. Kinematics and inertia come from the URDF
only; what this module adds is what a URDF cannot say: drives, sensors, cameras, contact
settings and the scene.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable, Sequence

import mujoco
import numpy as np

from comgrasp_pin._paths import example_robot_data_dir, sim_path, urdf_path
from comgrasp_pin.config import WorldConfig
from comgrasp_pin.robot import UR5_URDF

ARM_JOINTS = (
    "shoulder_pan_joint",
    "shoulder_lift_joint",
    "elbow_joint",
    "wrist_1_joint",
    "wrist_2_joint",
    "wrist_3_joint",
)
FINGER_JOINTS = ("finger_left_joint", "finger_right_joint")
GRIPPER_BODIES = ("gripper_base", "finger_left", "finger_right")
PAD_GEOMS = ("pad_left", "pad_right")
EE_SITE = "eelink"
FT_SITE = "ft_sensor"
"""The wrist force/torque sensor's site, at the origin of the body ``FT_BODY`` (the URDF's
``ft_sensor`` link: on the flange, z out of it, the gripper mounted on it): MuJoCo's
``force`` and ``torque`` sensors ``FT_SENSORS`` on it measure what the gripper's subtree
(fingers, and what they hold) exchanges with the arm."""
FT_BODY = "ft_sensor"
FT_SENSORS = ("ft_force", "ft_torque")
TOP_CAMERA = "top_down"
SIDE_CAMERA = "side_camera"

# MuJoCo cameras look along their -z with y up; the optical (OpenCV) frame looks along +z with
# y down. The URDF's side_camera frame is optical, so MuJoCo's camera sits rotated by pi about x.
_QUAT_OPTICAL_MUJOCO_WXYZ = (0.0, 1.0, 0.0, 0.0)

# Raised again at compile time for the unprefixed attach (see _attach_unprefixed).
warnings.filterwarnings("ignore", message="Attaching a spec with an empty prefix")

_VISUAL_GROUP = 1
_COLLISION_GROUP = 3  # hidden in renders


def robot_spec() -> mujoco.MjSpec:
    """The robot alone, compiled by MuJoCo's URDF reader from ``urdf/``.

    Mesh URIs ``package://example-robot-data/...`` are resolved to the installed package.
    Static bodies are kept (``fusestatic`` off) so that ``eelink`` and ``side_camera`` exist.
    """
    urdf = urdf_path(UR5_URDF).read_text()
    urdf = urdf.replace("package://example-robot-data/", f"{example_robot_data_dir()}/")
    compiler = '<mujoco><compiler fusestatic="false" discardvisual="false" strippath="false"/>'
    urdf = urdf.replace("</robot>", compiler + "</mujoco></robot>")
    return mujoco.MjSpec.from_string(urdf)


def build_spec(
    config: WorldConfig | None = None,
    extras: Sequence[Callable[[mujoco.MjSpec], None]] = (),
) -> mujoco.MjSpec:
    """The scene with the robot, drives, sensors and cameras; ``extras`` edit it further
    (each is called with the spec, e.g. to add an object)."""
    config = config or WorldConfig()
    spec = mujoco.MjSpec.from_file(str(sim_path("scene.xml")))
    spec.option.timestep = config.sim_dt
    spec.option.noslip_iterations = config.noslip_iterations
    spec.option.impratio = config.impratio
    _attach_unprefixed(spec, robot_spec())

    _set_contacts(spec, config)
    _add_drives(spec, config)
    _add_sensors_and_cameras(spec, config)
    for extra in extras:
        extra(spec)
    return spec


def build_model(
    config: WorldConfig | None = None,
    extras: Sequence[Callable[[mujoco.MjSpec], None]] = (),
) -> mujoco.MjModel:
    """Compile the world (see ``build_spec``)."""
    spec = build_spec(config, extras)
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message="Attaching a spec with an empty prefix")
        return spec.compile()


def _attach_unprefixed(spec: mujoco.MjSpec, child: mujoco.MjSpec) -> None:
    """Attach ``child`` at the world origin keeping its names, so that frame and joint names
    are the URDF's in both Pinocchio and MuJoCo. (MuJoCo warns that an unprefixed attach may
    not save to XML; we never save the attached spec, so the warning is silenced.)"""
    old_handler = mujoco.get_mju_user_warning()
    mujoco.set_mju_user_warning(lambda _msg: None)
    try:
        spec.attach(child, frame=spec.worldbody.add_frame(), prefix="")
    finally:
        mujoco.set_mju_user_warning(old_handler)


def _set_contacts(spec: mujoco.MjSpec, config: WorldConfig) -> None:
    """URDF visuals render, URDF collisions are hidden; only the gripper collides."""
    for body in spec.bodies:
        for geom in body.geoms:
            is_collision = geom.contype != 0 or geom.conaffinity != 0
            if not is_collision and body.name not in ("world", "table", "drop_box"):
                geom.group = _VISUAL_GROUP
                continue
            if body.name in ("world", "table", "drop_box"):
                continue
            geom.group = _COLLISION_GROUP
            if body.name not in GRIPPER_BODIES:
                geom.contype = geom.conaffinity = 0
    for side in ("left", "right"):
        # The URDF gives each finger a visual pad, a visual finger, a collision pad and a
        # collision finger, in that order. The visual pad keeps the name ``pad_{side}``
        # (segmentation); the colliding pad is ``pad_{side}_contact`` and carries the
        # contact settings. The finger behind it (set back 4 mm) gets them as well.
        geoms = spec.body(f"finger_{side}").geoms
        geoms[0].name = f"pad_{side}"
        colliding = [g for g in geoms if g.contype != 0 or g.conaffinity != 0]
        colliding[0].name = f"pad_{side}_contact"
        for geom in colliding:
            geom.friction = list(config.pad_friction)
            geom.condim = config.pad_condim
            geom.priority = 1  # the pads' friction and condim decide in pad-object contacts


def _add_drives(spec: mujoco.MjSpec, config: WorldConfig) -> None:
    """Position servos on the arm joints, force-controlled fingers kept symmetric."""
    for name, armature in zip(ARM_JOINTS, config.armature, strict=True):
        joint = spec.joint(name)
        joint.armature = armature
        joint.actfrclimited = 0  # the URDF's effort limits must not clip the readings silently
        act = spec.add_actuator(name=name, target=name, trntype=mujoco.mjtTrn.mjTRN_JOINT)
        act.set_to_position(kp=config.kp, dampratio=config.dampratio)
        act.ctrllimited = 0
        act.forcelimited = 0
    for name in FINGER_JOINTS:
        joint = spec.joint(name)
        joint.armature = config.finger_armature
        joint.solref_limit = [0.005, 1.0]  # a stiff end stop
        joint.damping = np.array([5.0, 0.0, 0.0])  # N s / m
        joint.actfrclimited = 0
        act = spec.add_actuator(name=name, target=name, trntype=mujoco.mjtTrn.mjTRN_JOINT)
        act.ctrllimited = 1
        act.ctrlrange = [-100.0, 100.0]  # N; positive closes
    # The joint limits stop the fingers 1 mm apart; a pad-pad contact could only fight them
    # (closed on nothing, the pads would be pushed through each other and lock).
    spec.add_exclude(bodyname1="finger_left", bodyname2="finger_right")
    spec.add_equality(
        type=mujoco.mjtEq.mjEQ_JOINT,
        name1=FINGER_JOINTS[0],
        name2=FINGER_JOINTS[1],
        data=np.r_[0.0, 1.0, 0.0, 0.0, 0.0, np.zeros(7)],
    )


def _add_sensors_and_cameras(spec: mujoco.MjSpec, config: WorldConfig) -> None:
    spec.body("eelink").add_site(name=EE_SITE, size=[0.005, 0, 0], group=_COLLISION_GROUP)
    for name in ARM_JOINTS:
        spec.add_sensor(
            name=f"tau_{name}",
            type=mujoco.mjtSensor.mjSENS_JOINTACTFRC,
            objname=name,
            objtype=mujoco.mjtObj.mjOBJ_JOINT,
        )
    add_ft_sensor(spec, FT_BODY)
    spec.body("side_camera").add_camera(
        name=SIDE_CAMERA, quat=list(_QUAT_OPTICAL_MUJOCO_WXYZ), fovy=config.side_camera_fovy_deg
    )


def add_ft_sensor(spec: mujoco.MjSpec, body: str) -> None:
    """A site ``FT_SITE`` at the origin of ``body`` (a body welded to its parent: the wrist
    sensor's tool side) and MuJoCo's ``force`` and ``torque`` sensors ``FT_SENSORS`` on it.

    MuJoCo's convention (XML reference, sensor/force and sensor/torque): the site's body is
    the child; the sensors give the interaction between its subtree and its parent, in the
    site's frame, torque about the site: the wrench the parent (the arm) applies to the
    subtree, i.e. minus the wrench of ``robot_io.log_files.wrench_log``'s convention
    (``wrench_sensor.wrench_from_sensors`` turns one into the other).
    """
    spec.body(body).add_site(name=FT_SITE, size=[0.005, 0, 0], group=_COLLISION_GROUP)
    for name, kind in zip(FT_SENSORS, ("FORCE", "TORQUE"), strict=True):
        spec.add_sensor(
            name=name,
            type=getattr(mujoco.mjtSensor, f"mjSENS_{kind}"),
            objname=FT_SITE,
            objtype=mujoco.mjtObj.mjOBJ_SITE,
        )
