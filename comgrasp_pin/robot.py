"""Serial-arm kinematics and statics on Pinocchio: joint axes, lever arms, ee pose, gravity.

The arm is the chain of 1-DoF joints from the root to the end-effector frame; every other
joint (the gripper's fingers) is locked at its neutral value. All vectors are in the world
frame, in SI units.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin

from comgrasp_pin import validate
from comgrasp_pin._paths import example_robot_data_dir, urdf_path
from comgrasp_pin.errors import InvalidInputError
from comgrasp_pin.file_checks import read_description

UR5_URDF = "ur5_gripper.urdf"  # in the top-level urdf/
UR5_EE_FRAME = "eelink"

_WORLD_ALIGNED = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED


def urdf_model(path: Path, package_dirs: list[str | Path] | None = None) -> pin.Model:
    """Pinocchio's model of the URDF file ``path``, read once and checked first
    (``file_checks.read_description``: a regular file of bounded size, XML without entities,
    mesh files inside its folder or ``package_dirs``); Pinocchio gets the checked text.

    Raises:
        InvalidInputError: the file fails a check, or Pinocchio cannot read it as a URDF.
    """
    text = read_description(path, "URDF", package_dirs or [])
    try:
        return pin.buildModelFromXML(text)
    except (RuntimeError, ValueError, OSError) as exc:
        raise InvalidInputError(f"cannot read {path} as a URDF: {exc}") from None


class RobotModel:
    """A fixed-base serial arm, reduced to the joints on the chain to ``ee_frame``.

    Attributes:
        model: the reduced Pinocchio model (``model.nq == nq``).
        data: its data, reused by every call (not thread-safe; one RobotModel per thread).
        full_model: the model with every joint, as read from the URDF.
        ee_frame: name of the end-effector frame; ``ee_frame_id`` its id in ``model``.
        joint_names: names of the arm joints, in configuration order.
        is_revolute: (n,) bool, True for revolute joints, False for prismatic ones.
        q_lower, q_upper: (n,) joint limits (rad or m).
        urdf_path: the URDF the model was built from.
        package_dirs: folders where the URDF's ``package://`` mesh URIs resolve.
    """

    def __init__(self, full_model: pin.Model, ee_frame: str, urdf_path: Path | None = None):
        check_frame(full_model, ee_frame, "ee_frame")
        self.full_model = full_model
        self.ee_frame = ee_frame
        self.urdf_path = urdf_path
        self.package_dirs: list[str] = []  # where package:// mesh URIs resolve

        chain = _chain_to_frame(full_model, full_model.getFrameId(ee_frame))
        if not chain:
            raise InvalidInputError(
                f"no joint moves the frame {ee_frame!r} (it is fixed to the root): the ee "
                "frame must sit at the end of a chain of 1-DoF joints, e.g. a tool frame"
            )
        for jid in chain:
            joint = full_model.joints[jid]
            if joint.nq != 1 or joint.nv != 1:
                raise InvalidInputError(
                    f"joint {full_model.names[jid]!r} ({joint.shortname()}) is not a 1-DoF "
                    "revolute or prismatic joint; only such arms are supported"
                )
        locked = [j for j in range(1, full_model.njoints) if j not in chain]
        self.model = pin.buildReducedModel(full_model, locked, pin.neutral(full_model))
        self.data = self.model.createData()
        self.ee_frame_id = self.model.getFrameId(ee_frame)
        self.joint_names = [self.model.names[j] for j in range(1, self.model.njoints)]
        self.is_revolute = np.array(
            [_is_revolute(self.model.joints[j]) for j in range(1, self.model.njoints)]
        )
        self.q_lower = self.model.lowerPositionLimit.copy()
        self.q_upper = self.model.upperPositionLimit.copy()

    @classmethod
    def from_urdf(
        cls,
        urdf_path: str | Path,
        ee_frame: str,
        package_dirs: list[str | Path] | None = None,
    ) -> RobotModel:
        """Build from a URDF file. ``package_dirs`` is where ``package://`` mesh URIs resolve
        (only collision geometry needs them; kinematics and inertia do not).

        Raises:
            InvalidInputError: no such file, a folder, a file Pinocchio cannot read as a
                URDF or that fails ``urdf_model``'s checks, an ee frame that is not in it
                or that no joint moves.
        """
        if not isinstance(urdf_path, (str, Path)):
            raise InvalidInputError(f"urdf_path must be a path, got {urdf_path!r}")
        urdf_path = Path(urdf_path)
        if urdf_path.is_dir():  # other kinds (FIFO, device, missing): read_description
            raise InvalidInputError(f"URDF file is a folder, not a file: {urdf_path}")
        dirs = list(package_dirs or [])
        if isinstance(package_dirs, (str, Path)) or not all(
            isinstance(d, (str, Path)) for d in dirs
        ):
            raise InvalidInputError(f"package_dirs must be a list of folders, got {package_dirs!r}")
        robot = cls(urdf_model(urdf_path, dirs), ee_frame, urdf_path)
        robot.package_dirs = [str(p) for p in dirs]
        return robot

    @classmethod
    def ur5(cls) -> RobotModel:
        """The project's UR5 with gripper (``urdf/ur5_gripper.urdf``), ee frame ``eelink``."""
        return cls.from_urdf(
            urdf_path(UR5_URDF), UR5_EE_FRAME, package_dirs=[example_robot_data_dir().parent]
        )

    @property
    def nq(self) -> int:
        """Number of arm joints."""
        return self.model.nq

    def check_q(self, q: np.ndarray) -> np.ndarray:
        """``q`` as a float (n,) array; ValueError for a wrong shape or non-finite values."""
        q = validate.real_array(q, "q")
        if q.shape != (self.nq,):
            raise InvalidInputError(f"q must have shape ({self.nq},), got {q.shape}")
        if not np.all(np.isfinite(q)):
            raise InvalidInputError(f"q contains NaN or inf: {q}")
        return q

    def _kinematics(self, q: np.ndarray) -> None:
        q = self.check_q(q)
        pin.forwardKinematics(self.model, self.data, q)
        pin.updateFramePlacement(self.model, self.data, self.ee_frame_id)

    def joint_origins(self, q: np.ndarray) -> np.ndarray:
        """(n, 3) joint frame origins p_i in the world frame (m)."""
        self._kinematics(q)
        return np.array([self.data.oMi[j].translation for j in range(1, self.model.njoints)])

    def joint_axes(self, q: np.ndarray) -> np.ndarray:
        """(n, 3) unit joint axes a_i in the world frame."""
        jac = self.ee_jacobian(q)
        return np.where(self.is_revolute[:, None], jac[3:].T, jac[:3].T)

    def lever_arms(self, q: np.ndarray) -> np.ndarray:
        """(n, 3) lever arms r_i = p_ee - p_i in the world frame (m)."""
        origins = self.joint_origins(q)
        return self.data.oMf[self.ee_frame_id].translation - origins

    def ee_pose(self, q: np.ndarray) -> np.ndarray:
        """(4, 4) T_world_ee."""
        self._kinematics(q)
        return self.data.oMf[self.ee_frame_id].homogeneous.copy()

    def ee_jacobian(self, q: np.ndarray) -> np.ndarray:
        """(6, n) Jacobian of the ee frame, rows (linear, angular), world-aligned at p_ee.

        Column i is (a_i x r_i, a_i) for a revolute joint and (a_i, 0) for a prismatic one.
        """
        q = self.check_q(q)
        return pin.computeFrameJacobian(self.model, self.data, q, self.ee_frame_id, _WORLD_ALIGNED)

    def gravity_torques(self, q: np.ndarray) -> np.ndarray:
        """(n,) joint torques (N m) that hold the unloaded arm still at ``q``."""
        q = self.check_q(q)
        return pin.computeGeneralizedGravity(self.model, self.data, q).copy()

    def frame_pose(self, q: np.ndarray, frame: str) -> np.ndarray:
        """(4, 4) T_world_frame of any frame of the model, e.g. ``"side_camera"``."""
        check_frame(self.model, frame, "frame")
        q = self.check_q(q)
        fid = self.model.getFrameId(frame)
        pin.forwardKinematics(self.model, self.data, q)
        return pin.updateFramePlacement(self.model, self.data, fid).homogeneous.copy()

    def T_frame_ee(self, frame: str, what: str = "frame") -> np.ndarray:
        """(4, 4) the ee frame's pose in ``frame``, fixed by the URDF: both must be on the
        last link (a flange, a wrist sensor), else InvalidInputError naming ``what``."""
        check_frame(self.model, frame, what)
        f_id = self.model.getFrameId(frame)
        if self.model.frames[f_id].parentJoint != self.model.frames[self.ee_frame_id].parentJoint:
            raise InvalidInputError(
                f"{what} {frame!r} and ee frame {self.ee_frame!r} are not on the same link "
                "chain after the last arm joint: their relative pose changes with q"
            )
        q = pin.neutral(self.model)
        return np.linalg.solve(self.frame_pose(q, frame), self.frame_pose(q, self.ee_frame))

    def random_configuration(self, rng: np.random.Generator) -> np.ndarray:
        """A configuration drawn uniformly within the joint limits (clipped to +-pi)."""
        lo = np.maximum(self.q_lower, -np.pi)
        hi = np.minimum(self.q_upper, np.pi)
        return rng.uniform(lo, hi)


def check_frame(model: pin.Model, frame: object, name: str) -> None:
    """InvalidInputError unless ``frame`` names a frame of ``model`` (the valid names listed)."""
    if not isinstance(frame, str) or not model.existFrame(frame):
        names = sorted({f.name for f in model.frames})
        raise InvalidInputError(
            f"{name} {frame!r} is not a frame of the model; frames are: {names}"
        )


def _chain_to_frame(model: pin.Model, frame_id: int) -> list[int]:
    """Joint ids from the root to the parent joint of ``frame_id`` (universe excluded)."""
    chain = []
    joint_id = model.frames[frame_id].parentJoint
    while joint_id > 0:
        chain.append(joint_id)
        joint_id = model.parents[joint_id]
    return chain[::-1]


def _is_revolute(joint: pin.JointModel) -> bool:
    name = joint.shortname()
    if "Revolute" in name or name.startswith("JointModelR"):
        return True
    if "Prismatic" in name or name.startswith("JointModelP"):
        return False
    raise InvalidInputError(f"unsupported joint type {name}")
