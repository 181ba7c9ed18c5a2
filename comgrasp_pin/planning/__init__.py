"""Plans as pure functions, no simulator: where to grasp, and where the arm goes to measure.

- Grasping: the regrasp decision (``regrasp``), the retry policy (``retry``), the put-down
  geometry (``put_down``), the holding moment of the jaws (``holding``).
- Measuring: extra wrist poses that make the 3-D CoM observable (``wrist_poses``), measurement
  poses for a real arm (``measurement_poses``), excitation motions for the inertia
  (``excitation``, its search in ``excitation_search``), self-collision from the URDF
  (``collision``). Motion files are written by ``robot_io.payload_files.motion_files``.

Layer: imports ``estimation``, ``motion``, ``robot`` and the shared modules (``config``,
``geometry``, ``workcell``, ``errors``); nothing that acts or sees.
"""

from comgrasp_pin.planning.collision import SelfCollision
from comgrasp_pin.planning.excitation import ExcitationMotion, plan_excitation
from comgrasp_pin.planning.excitation_search import ExcitationSettings
from comgrasp_pin.planning.measurement_poses import PosePlan, plan_measurement_poses
from comgrasp_pin.planning.wrist_poses import best_next_pose, plan_wrist_poses

__all__ = [
    "PosePlan",
    "plan_measurement_poses",
    "plan_wrist_poses",
    "best_next_pose",
    "ExcitationMotion",
    "ExcitationSettings",
    "plan_excitation",
    "SelfCollision",
]
