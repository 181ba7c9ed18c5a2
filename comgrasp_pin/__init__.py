"""comgrasp_pin: centre-of-mass-based grasp adaptation from joint torques and RGBD cameras."""

from comgrasp_pin.robot import RobotModel

__all__ = ["RobotModel"]
__version__ = "0.1.0"
