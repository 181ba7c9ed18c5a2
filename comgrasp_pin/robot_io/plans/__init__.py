"""Where the arm goes to measure: measurement poses and excitation motions.

Within the joint limits and free of self-collision, D-optimal for the payload's
parameters, and written as programs (URScript, ROS 2 trajectories) that play them.
"""

from comgrasp_pin.robot_io.plans.collision import SelfCollision
from comgrasp_pin.robot_io.plans.excitation import ExcitationMotion, plan_excitation
from comgrasp_pin.robot_io.plans.excitation_search import ExcitationSettings
from comgrasp_pin.robot_io.plans.poses import PosePlan, plan_measurement_poses

__all__ = [
    "PosePlan",
    "plan_measurement_poses",
    "ExcitationMotion",
    "ExcitationSettings",
    "plan_excitation",
    "SelfCollision",
]
