"""The wrist sensor's part of a trial grasp's readings: its differences and their noise.

The same windows that average the joint torques average the wrist sensor
(``TorqueMeasurement.wrench``). Per pose, the payload's wrench is the held window's mean
minus the empty window's at the same configuration; where the empty window was not measured
(an extra pose, whose tau_before is modelled), the empty wrench is the URDF's tool beyond the
sensor at that pose plus the sensor's offset seen at the measured poses (as
``trial_plan.modelled_tau_before`` does for the torques).

The differences' noise, from what the robot knows: each window's standard error, and the
sensor's data sheet (``WrenchSensorConfig``): a random-walk drift shared by windows that
overlap in time (``estimation.drift``, as the torques' ``drift_cov``) and a slow drift at a
rate unknown but fixed over the episode (its std times each difference's elapsed time,
fully correlated across poses). N, N m, s.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from comgrasp_pin.config import WrenchSensorConfig
from comgrasp_pin.errors import InvalidInputError
from comgrasp_pin.estimation import ComEstimate
from comgrasp_pin.estimation.drift import difference_covariance, difference_weights
from comgrasp_pin.estimation.regressor import stacked_regressor
from comgrasp_pin.estimation.wrench_com import (
    estimate_com_wrench,
    source_shares,
    tool_wrench,
    wrench_regressor,
)
from comgrasp_pin.procedures.measurement import HeldReadings
from comgrasp_pin.robot import RobotModel

SENSOR_FRAME = "ft_sensor"
"""The URDF frame the cell's wrist sensor measures in."""
JOINT_TORQUES, WRENCH, BOTH = "joint torques", "wrench", "both"
SOURCES = (JOINT_TORQUES, WRENCH, BOTH)
"""What a CoM location is estimated from (``com_location.locate_com``'s ``source``)."""


def has_wrench(held: HeldReadings) -> bool:
    """Whether every held window and every measured empty one read the wrist sensor."""
    windows = [*held.after, *(b for b in held.before if b is not None)]
    return all(m.wrench is not None for m in windows)


def wrench_before(robot: RobotModel, held: HeldReadings, use: list[int]) -> np.ndarray:
    """(k, 6) the empty wrench at the poses ``use``: measured, or modelled (module doc)."""
    measured = [(b.q, b.wrench) for b in held.before if b is not None]
    offset = np.mean([w - tool_wrench(robot, q, SENSOR_FRAME) for q, w in measured], axis=0)
    rows = []
    for i in use:
        b = held.before[i]
        if b is None:  # an extra pose: the tool at its configuration, the measured offset
            rows.append(tool_wrench(robot, held.after[i].q, SENSOR_FRAME) + offset)
        else:
            rows.append(b.wrench)
    return np.array(rows)


def wrench_cov(held: HeldReadings, use: list[int], sensor: WrenchSensorConfig) -> np.ndarray:
    """(6 k, 6 k) covariance of the k wrench differences at ``use``, pose-major."""
    measured = [b for b in held.before if b is not None]
    count = iter(range(len(measured)))
    index_of = [None if b is None else next(count) for b in held.before]
    empty_of = [index_of[i] for i in use]
    after = [held.after[i] for i in use]
    windows = [*after, *measured]
    weights = difference_weights(empty_of, len(measured))
    # the time each difference spans: from its empty window, or the measured ones' mean
    start = [np.mean([m.time for m in measured]) if j is None else measured[j].time
             for j in empty_of]  # fmt: skip
    elapsed = np.array([a.time - t for a, t in zip(after, start)])
    spans = [(float(m.time), float(m.duration)) for m in windows]
    white = np.array([np.asarray(m.wrench_std_error, dtype=float) for m in windows])
    drift = np.repeat(np.asarray(sensor.drift_std, dtype=float), 3)
    cov = difference_covariance(spans, white, weights, drift)
    rate = np.repeat(np.asarray(sensor.drift_rate_std, dtype=float), 3)
    cov += np.kron(np.outer(elapsed, elapsed), np.diag(rate**2))
    return 0.5 * (cov + cov.T)


@dataclass(frozen=True)
class WrenchRows:
    """The wrist sensor's differences at the poses a CoM location uses, and their noise.

    Attributes:
        before: (k, 6) the empty wrench per pose (N, N m).
        after: (k, 6) the held wrench per pose.
        cov: (6 k, 6 k) the differences' covariance, pose-major (``wrench_cov``).
        both: stack the joint torques' rows too (source ``BOTH``).
    """

    before: np.ndarray
    after: np.ndarray
    cov: np.ndarray
    both: bool

    @classmethod
    def of(cls, robot, held: HeldReadings, use: list[int], sensor, source: str) -> WrenchRows:
        """The rows of ``source`` (``WRENCH`` or ``BOTH``) at the poses ``use``.

        Raises:
            InvalidInputError: an unknown source, or readings without the wrist sensor.
        """
        if source not in SOURCES:
            raise InvalidInputError(f"source must be one of {SOURCES}, not {source!r}")
        if sensor is None or not has_wrench(held):
            raise InvalidInputError(f"source {source!r} needs the wrist sensor's readings")
        after = np.array([held.after[i].wrench for i in use])
        return cls(wrench_before(robot, held, use), after, wrench_cov(held, use, sensor),
                   source == BOTH)  # fmt: skip

    def estimate(self, robot, q, method, prior, motion, torques) -> ComEstimate:
        """``estimate_com_wrench`` on the first ``len(q)`` poses (``torques`` with both)."""
        k = len(q)
        return estimate_com_wrench(robot, q, self.before[:k], self.after[:k], SENSOR_FRAME,
                                   wrench_cov=self.cov[: 6 * k, : 6 * k], method=method,
                                   com_prior=prior, payload_motion_ee=motion,
                                   torques=torques)  # fmt: skip

    def shares(self, robot, q: np.ndarray, cov_t: np.ndarray, T_ee_obj) -> dict:
        """The shares at the first ``len(q)`` poses (``information_shares``)."""
        k = len(q)
        return information_shares(robot, q, cov_t, self.cov[: 6 * k, : 6 * k], T_ee_obj)


def information_shares(
    robot: RobotModel, q: np.ndarray, cov_t, cov_w, T_ee_obj: np.ndarray
) -> dict:
    """The wrench's and the torques' shares of the information on the mass and on the CoM
    along the rod (``wrench_com.source_shares``; the rod's small motion between poses left
    out)."""
    Y_t, _ = stacked_regressor(robot, q)
    Y_w, _ = wrench_regressor(robot, q, SENSOR_FRAME)
    along = np.r_[0.0, T_ee_obj[:3, 0]]
    return source_shares({WRENCH: (Y_w, cov_w), JOINT_TORQUES: (Y_t, cov_t)},
                         {"mass": np.eye(4)[0], "com_along_rod": along})  # fmt: skip
