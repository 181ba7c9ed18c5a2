"""The static wrench path on MuJoCo's UR5 against the simulator's truth.

The sessions are those of benchmarks/wrench_static.py.

Reference: the payload MuJoCo holds (``Payload``, a box from its mass, sides and centre),
never a number from the estimator. Four poses planned by ``plan_measurement_poses`` (what
``comgrasp plan-poses`` runs), a quintic between them, 2.5 s still at each; the wrist
sensor's log goes through ``estimate_wrench_static`` as ``comgrasp estimate --wrench`` takes
it (still windows found in the log).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

from comgrasp_pin.config import MotionConfig, sensor_preset
from comgrasp_pin.robot_io.planning import plan_measurement_poses
from comgrasp_pin.robot_io.wrench_static import estimate_wrench_static
from comgrasp_pin.simulation.arm_worlds import arm_robot

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
from wrench_static import (  # noqa: E402
    gripper_excess,
    held_body,
    random_payload,
    session_trajectory,
    simulate,
)


@pytest.fixture(scope="module")
def robot():
    return arm_robot("ur5")


def _sessions(robot, draw, preset):
    """(payload, excess, empty WrenchLog, loaded WrenchLog) of one benchmark draw."""
    sensors = sensor_preset(preset)
    payload = random_payload(np.random.default_rng((draw, 1)))
    excess = gripper_excess(robot, sensors.gripper_mass_error, sensors.gripper_com_error)
    traj = session_trajectory(plan_measurement_poses(robot, k=4, seed=draw).q, MotionConfig())
    _, empty = simulate(held_body(None, excess), traj, sensors, 2 * draw + 1, draw)
    _, loaded = simulate(held_body(payload, excess), traj, sensors, 2 * draw + 2, draw)
    return payload, excess, empty, loaded


def _z(est, mass, com_ee):
    err = np.r_[est.mass - mass, est.com_ee - com_ee]
    return err / np.sqrt(np.diag(est.cov))


@pytest.mark.parametrize("draw", [0, 1])
def test_ideal_sensor_gives_the_simulated_payload(robot, draw):
    payload, excess, _, loaded = _sessions(robot, draw, "ideal")
    assert excess is None
    est = estimate_wrench_static(robot, loaded)
    assert est.verdict == "identified" and est.n_poses == 4
    assert abs(est.mass / payload.mass - 1) < 0.01
    assert np.linalg.norm(est.com_ee - payload.p_com_ee) < 0.002
    assert np.all(np.abs(_z(est, payload.mass, payload.p_com_ee)) < 4)


@pytest.mark.parametrize("draw", [2, 3, 4])
def test_realistic_sensor_with_a_calibrated_tool_holds_the_truth(robot, draw):
    """The realistic preset's gripper is heavier than its URDF: the tool identified with
    nothing held (another session: its own offset and drift) takes it out; the URDF's tool
    leaves it in the payload, by the simulated excess."""
    payload, excess, empty, loaded = _sessions(robot, draw, "realistic")
    tool = estimate_wrench_static(robot, empty, subtract_tool=False)
    calibrated = (tool.fit.theta[:4], tool.fit.theta_cov[:4, :4])
    est = estimate_wrench_static(robot, loaded, tool=calibrated)
    assert abs(est.mass / payload.mass - 1) < 0.01
    assert np.linalg.norm(est.com_ee - payload.p_com_ee) < 0.002
    assert np.all(np.abs(_z(est, payload.mass, payload.p_com_ee)) < 3)
    with_urdf = estimate_wrench_static(robot, loaded)
    both = held_body(payload, excess)  # what the URDF's tool leaves: payload and excess
    assert abs(with_urdf.mass - both.mass) < 3 * np.sqrt(with_urdf.cov[0, 0])
    assert abs(with_urdf.mass - payload.mass) > 0.5 * excess.mass
