"""The wrist force/torque sensor's part of the sensors' config, and its data-sheet classes.

``WrenchSensorConfig`` is ``SensorConfig.wrench`` (``sensor_preset``): the errors the
simulated sensor between flange and gripper (``simulation.wrench_sensor``) puts on the true
wrench. Each axis pair is (force in N, torque in N m), the same for the three axes of each.
``wrench_preset(name)`` gives a data sheet's class; every figure below is marked with its
source, or as an assumption (docs/design.md, "Realistic sensing").

Sources:

- [FT300-S] Robotiq, "FT 300-S Force Torque Sensor - Instruction Manual": the data stream
  sends a force/torque sample at 100 Hz, as 16-bit integers of Fx * 100 (N) and Mx * 1000
  (N m) (section 4.4.2, p. 34); 300 g, its CoM 17 mm along z (section 5.2.1, p. 71).
  (Read at manualshive.com/en/manual/robotiq/ft-300-s/1471343 and .../ft-300/1471341.)
- [SEL] RoboticsCenter, "Force/torque sensor selection guide" (roboticscenter.ai/guides/
  force-torque-sensor-selection-guide): Robotiq FT 300-S, 300 N range, 0.1 N resolution,
  100 Hz.
- [DESIGN8] ../shared/DESIGN.md section 8: strain-gauge wrist sensors (ATI, Robotiq FT 300)
  resolve about 0.1 N and 0.005 N m and drift with temperature; the UR5e's built-in sensor:
  precision 3.5 N / 0.2 N m, accuracy 4.0 N / 0.3 N m (UR5e data sheet), force range 50 N,
  torque range 10 N m.
- [AXIA] ATI, "Manual, F/T Sensor, Ethernet Axia" (9610-05-Ethernet Axia-09): an unloaded
  reading that jumps by more than 0.05 % of full scale is abnormal noise (section 14.5,
  p. 87); the Axia80-M20's calibration range 0 is 500 N (Fx, Fy), 900 N (Fz), 20 N m
  (table 4.8, p. 36). That bounds a sound sensor of this class at 0.25 N and 0.01 N m: the
  FT 300-S figures below lie inside it.

Re-exported by ``comgrasp_pin.config``; frozen dataclasses, SI units.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

from comgrasp_pin.errors import InvalidInputError

WRENCH_MODELS = ("ideal", "ft300s", "ur_eseries", "custom")
"""The labels of ``WrenchSensorConfig.model``: the data sheet the numbers come from."""


@dataclass(frozen=True)
class WrenchSensorConfig:
    """Error model of the wrist force/torque sensor's readings (sensor frame).

    A sample at time t (s from the world's start) reads the true wrench (the convention of
    ``robot_io.log_files.wrench_log``: what the tool side applies to the sensor) plus
    ``bias + offset + drift(t) + drift_rate * t + noise``, axis by axis.

    Attributes:
        model: the data sheet the numbers come from (``WRENCH_MODELS``; "custom" when
            changed by hand). A label recorded with the run; it changes nothing.
        rate_hz: samples per second (Hz); a simulation's control rate must be a whole
            multiple of it (the sensor samples the true wrench every k-th step).
        noise_std: (force N, torque N m) white noise on every sample, each axis.
        bias: (6,) constant offset of every sample (N, N m): a known zero error.
        bias_std: (force N, torque N m) each axis's offset, drawn once per episode from
            N(0, std): the zero the sensor has when the episode starts (mounting preload,
            temperature since its last bias reset).
        drift_std: (force N / sqrt(s), torque N m / sqrt(s)) random-walk drift: its
            standard deviation after one second; it grows as sqrt(t).
        drift_rate_std: (force N / s, torque N m / s) a slow, temperature-like drift: each
            axis's rate is drawn once per episode from N(0, std) and the reading moves by
            rate * t.
    """

    model: str = "ideal"
    rate_hz: float = 100.0
    noise_std: tuple[float, float] = (0.1, 0.005)
    bias: tuple[float, ...] = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    bias_std: tuple[float, float] = (0.0, 0.0)
    drift_std: tuple[float, float] = (0.0, 0.0)
    drift_rate_std: tuple[float, float] = (0.0, 0.0)

    def __post_init__(self) -> None:
        if self.model not in WRENCH_MODELS:
            raise InvalidInputError(f"model must be one of {WRENCH_MODELS}, not {self.model!r}")
        if not (isinstance(self.rate_hz, (int, float)) and 0 < self.rate_hz < math.inf):
            raise InvalidInputError(f"rate_hz must be a number > 0 (Hz), got {self.rate_hz!r}")
        pairs = {n: getattr(self, n) for n in ("noise_std", "bias_std", "drift_std",
                                                "drift_rate_std")}  # fmt: skip
        for name, pair in pairs.items():
            if len(pair) != 2 or not all(_finite(v) and v >= 0 for v in pair):
                raise InvalidInputError(
                    f"{name} must be (force, torque), two finite numbers >= 0; got {pair!r}"
                )
        if len(self.bias) != 6 or not all(_finite(v) for v in self.bias):
            raise InvalidInputError(
                f"bias must be six finite numbers (force N x3, torque N m x3); got {self.bias!r}"
            )


def _finite(value: object) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


# Robotiq FT 300-S, the strain-gauge class a UR5 (CB3, no built-in sensor) carries.
# noise_std: 0.1 N [SEL, DESIGN8] and 0.005 N m [DESIGN8] per sample, read as one standard
#   deviation; inside the [AXIA] bound of 0.25 N / 0.01 N m.
# rate_hz: 100 Hz, the data stream [FT300-S]. Its 0.01 N / 0.001 N m integer steps
#   [FT300-S] are a tenth of the noise and are not modelled.
# bias_std: 1 N / 0.05 N m, an assumption: ten times the noise, so that an estimator that
#   does not estimate the bias fails visibly (no data sheet gives the zero after mounting).
# drift_std: 0.01 N / 0.0005 N m per sqrt(s), an assumption: one noise std after 100 s,
#   0.6 N / 0.03 N m after an hour ([DESIGN8]: they drift with temperature; no figure found).
# drift_rate_std: 2e-4 N/s, 1e-5 N m/s, an assumption: 0.7 N / 0.04 N m per hour of
#   warm-up.
# The default (model "ideal") is the FT 300-S's rate and noise alone.
_FT300S = replace(WrenchSensorConfig(), model="ft300s", bias_std=(1.0, 0.05),
                  drift_std=(0.01, 5e-4), drift_rate_std=(2e-4, 1e-5))  # fmt: skip
# UR e-series built-in sensor (UR5e), the coarse class [DESIGN8]: the precision (3.5 N,
# 0.2 N m) as each sample's white noise, the accuracy (4.0 N, 0.3 N m) as the episode's
# offset; 500 Hz, the controller's real-time rate (RTDE); the drift as the FT 300-S's
# (assumption). White noise of that size averages down over a window (3.5 N over 500
# samples: 0.16 N), which the data sheet's precision may not: this class is optimistic.
_UR_ESERIES = WrenchSensorConfig(model="ur_eseries", rate_hz=500.0, noise_std=(3.5, 0.2),
                                 bias_std=(4.0, 0.3), drift_std=(0.01, 5e-4),
                                 drift_rate_std=(2e-4, 1e-5))  # fmt: skip

WRENCH_PRESETS = {
    "ideal": WrenchSensorConfig(),
    "ft300s": _FT300S,
    "ur_eseries": _UR_ESERIES,
}
"""The wrist sensor's classes: "ideal" (the FT 300-S's white noise and rate only, no bias or
drift: what the ideal torque sensor's 0.05 N m is to the joint torques), "ft300s" (the
realistic presets' sensor) and "ur_eseries" (a UR e-series arm's built-in sensor, coarser;
not the realistic default, since the UR5 (CB3) has none)."""


def wrench_preset(name: str) -> WrenchSensorConfig:
    """The wrist sensor class ``name`` (``WRENCH_PRESETS``).

    Raises:
        InvalidInputError: an unknown name (the valid ones are listed).
    """
    if name not in WRENCH_PRESETS:
        raise InvalidInputError(
            f"unknown wrench sensor {name!r}; the classes are {tuple(WRENCH_PRESETS)}"
        )
    return WRENCH_PRESETS[name]
