"""comgrasp_pin: centre-of-mass-based grasp adaptation from joint torques and RGBD cameras."""

from comgrasp_pin import robot_io
from comgrasp_pin.errors import (
    ComGraspError,
    EmptyGripperError,
    IKError,
    InvalidInputError,
    LogError,
    NotStaticError,
    OutputError,
    PerceptionError,
    SolverError,
    UnobservableError,
)
from comgrasp_pin.estimation import (
    AxisPrior,
    ComEstimate,
    com_along_axis,
    estimate_com,
)
from comgrasp_pin.planning import PosePlan, plan_wrist_poses
from comgrasp_pin.robot import RobotModel
from comgrasp_pin.robot_io import (
    JointLog,
    Payload,
    PayloadEstimate,
    estimate_from_log,
    load_robot,
    payload_in_flange,
    plan_measurement_poses,
    read_log,
)

__all__ = [
    "AxisPrior",
    "ComEstimate",
    "ComGraspError",
    "EmptyGripperError",
    "IKError",
    "InvalidInputError",
    "JointLog",
    "LogError",
    "NotStaticError",
    "OutputError",
    "Payload",
    "PayloadEstimate",
    "PerceptionError",
    "PosePlan",
    "RobotModel",
    "SolverError",
    "UnobservableError",
    "com_along_axis",
    "estimate_com",
    "estimate_from_log",
    "load_robot",
    "payload_in_flange",
    "plan_measurement_poses",
    "plan_wrist_poses",
    "read_log",
    "robot_io",
]
__version__ = "0.3.0"  # the one source: pyproject.toml reads it (tool.setuptools.dynamic)


def __dir__() -> list[str]:
    """What ``dir(comgrasp_pin)`` lists: the public names (``__all__``) and the version.

    Not the submodules that importing them loads (``errors``, ``validate``, ``geometry``).
    """
    return sorted([*__all__, "__version__"])
