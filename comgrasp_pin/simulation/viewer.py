"""MuJoCo's interactive viewer on a running simulation (needs a display)."""

from __future__ import annotations

import time

import mujoco.viewer

from comgrasp_pin.simulation.sim import Simulation


class LiveViewer:
    """A Simulation observer that mirrors the world in MuJoCo's passive viewer at ``fps``,
    paced to real time."""

    def __init__(self, sim: Simulation, fps: float = 60.0):
        self._handle = mujoco.viewer.launch_passive(sim.model, sim.data)
        self._period = 1.0 / fps
        self._next = sim.time
        self._start = (time.perf_counter(), sim.time)

    def __call__(self, sim: Simulation) -> None:
        if sim.time < self._next or not self._handle.is_running():
            return
        self._next += self._period
        self._handle.sync()
        ahead = (sim.time - self._start[1]) - (time.perf_counter() - self._start[0])
        if ahead > 0:
            time.sleep(ahead)
