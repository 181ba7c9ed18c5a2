"""The MuJoCo world that plays reality: the only part of comgrasp_pin that imports MuJoCo.

World building, the running simulation, servo, torque sensors, cameras and their depth
errors, objects, skills, the eyes (render -> perception), the simulated ``Cell``, scoring
against the truth, recorder, viewer, episode; the simulated FR3 that speaks libfranka's
protocol (``franka_sim``, franky-sim in its own process).

Layer: above ``procedures`` (the simulated ``Cell`` runs them) and ``robot_io`` (its
``JointLog``), and everything under them; only ``experiments`` and ``cli`` import it.
"""

import os

# Headless rendering by default; must be set before MuJoCo is first imported.
os.environ.setdefault("MUJOCO_GL", "egl")

from comgrasp_pin.simulation.sim import Simulation  # noqa: E402
from comgrasp_pin.simulation.world import build_model, build_spec  # noqa: E402

__all__ = ["Simulation", "build_model", "build_spec"]
