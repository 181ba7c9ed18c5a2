"""comgrasp_pin: centre-of-mass-based grasp adaptation from joint torques and RGBD cameras."""

from comgrasp_pin.errors import (
    ComGraspError,
    EmptyGripperError,
    InvalidInputError,
    SolverError,
    UnobservableError,
)
from comgrasp_pin.estimation import (
    AxisPrior,
    ComEstimate,
    ComEstimateBatch,
    com_along_axis,
    estimate_com,
    estimate_com_batch,
    plan_wrist_poses,
)
from comgrasp_pin.robot import RobotModel

__all__ = [
    "AxisPrior",
    "ComEstimate",
    "ComEstimateBatch",
    "ComGraspError",
    "EmptyGripperError",
    "InvalidInputError",
    "RobotModel",
    "SolverError",
    "UnobservableError",
    "com_along_axis",
    "estimate_com",
    "estimate_com_batch",
    "plan_wrist_poses",
]
__version__ = "0.1.0"
