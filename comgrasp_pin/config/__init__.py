"""The config tree: every number that tunes a run (frozen dataclasses, SI units).

    tree.py     EpisodeConfig -> trial, regrasp, motion, sensors, world; run.json records it
    sensors.py  the sensors' part (torque sensor, depth cameras' errors) and its presets
    wrench.py   the wrist force/torque sensor's part (data-sheet classes, part of the sensors')
    depth_line.py  the wrist camera's depth-line error model (part of the sensors')
    live.py     a connected arm's measurement (comgrasp live): speeds, holds, contact limits
    log_limits.py  the largest values a robot log may hold (beyond them no sensor gives them)
    trial.py    the trial grasp's part, and the procedure a real arm's sensors need
    paths.py    every number of the tree by its dotted path (``motion.grip_force``), for sweeps

Layer: the bottom, beside ``errors`` and ``validate``; it imports nothing else of the
package, and every layer above reads its numbers from here. Import the names from
``comgrasp_pin.config``; ``comgrasp_pin.config.paths`` is used as a module.
"""

from comgrasp_pin.config.depth_line import DepthLineErrorConfig
from comgrasp_pin.config.live import LiveConfig
from comgrasp_pin.config.log_limits import (
    MAX_ABS_FORCE_N,
    MAX_ABS_JOINT_EFFORT,
    MAX_ABS_JOINT_POSITION_RAD,
    MAX_ABS_JOINT_VELOCITY_RAD_S,
    MAX_ABS_TIME_S,
    MAX_ABS_TORQUE_NM,
)
from comgrasp_pin.config.sensors import (
    SENSOR_PRESETS,
    DepthNoiseConfig,
    SensorConfig,
    TorqueSensorConfig,
    sensor_preset,
)
from comgrasp_pin.config.tree import EpisodeConfig, MotionConfig, RegraspConfig, WorldConfig
from comgrasp_pin.config.trial import ESTIMATORS, TAU_BEFORE, TrialConfig, hardware_trial
from comgrasp_pin.config.wrench import (
    WRENCH_MODELS,
    WRENCH_PRESETS,
    WrenchSensorConfig,
    wrench_preset,
)

__all__ = [
    "SENSOR_PRESETS",
    "DepthLineErrorConfig",
    "DepthNoiseConfig",
    "EpisodeConfig",
    "MotionConfig",
    "RegraspConfig",
    "SensorConfig",
    "TorqueSensorConfig",
    "TrialConfig",
    "hardware_trial",
    "LiveConfig",
    "MAX_ABS_FORCE_N",
    "MAX_ABS_JOINT_EFFORT",
    "MAX_ABS_JOINT_POSITION_RAD",
    "MAX_ABS_JOINT_VELOCITY_RAD_S",
    "MAX_ABS_TIME_S",
    "MAX_ABS_TORQUE_NM",
    "ESTIMATORS",
    "TAU_BEFORE",
    "WorldConfig",
    "WRENCH_MODELS",
    "WRENCH_PRESETS",
    "WrenchSensorConfig",
    "sensor_preset",
    "wrench_preset",
]
