"""The MuJoCo world that plays reality: the only part of comgrasp_pin that imports MuJoCo."""

from comgrasp_pin.simulation.sim import Simulation
from comgrasp_pin.simulation.world import WorldConfig, build_model, build_spec

__all__ = ["Simulation", "WorldConfig", "build_model", "build_spec"]
