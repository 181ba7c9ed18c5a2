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
from comgrasp_pin.estimation.wrench_com import tool_beyond
from comgrasp_pin.planning.measurement_poses import plan_measurement_poses
from comgrasp_pin.robot_io.at_rest.wrench_static import estimate_wrench_static
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
    plan = plan_measurement_poses(robot, k=4, seed=draw, sensor_frame="ft_sensor")
    traj = session_trajectory(plan.q, MotionConfig())
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
    tool = tool_beyond(robot, "ft_sensor")  # the ideal world's tool is the URDF's, known
    known = (np.r_[tool.mass, tool.mass * np.asarray(tool.lever)], np.zeros((4, 4)))
    est = estimate_wrench_static(robot, loaded, tool=known)
    assert est.verdict == "identified" and est.at_rest.n_poses == 4
    assert abs(est.mass / payload.mass - 1) < 0.01
    assert np.linalg.norm(est.com_ee - payload.p_com_ee) < 0.002
    assert np.all(np.abs(_z(est, payload.mass, payload.p_com_ee)) < 4)


@pytest.mark.parametrize("draw", [2, 3, 4])
def test_realistic_sensor_with_a_calibrated_tool_holds_the_truth(robot, draw):
    """The realistic preset's gripper is heavier than its URDF: the tool identified with
    nothing held (another session: its own offset and drift) takes it out; the URDF's tool
    leaves it in the payload, by the simulated excess."""
    payload, excess, empty, loaded = _sessions(robot, draw, "realistic")
    sheet = sensor_preset("realistic").wrench  # the data sheet's drift, as a user knows it
    drift = {"drift_std": sheet.drift_std, "drift_rate_std": sheet.drift_rate_std}
    tool = estimate_wrench_static(robot, empty, subtract_tool=False, **drift)
    calibrated = (tool.wrench.fit.theta[:4], tool.wrench.fit.theta_cov[:4, :4])
    est = estimate_wrench_static(robot, loaded, tool=calibrated, **drift)
    assert est.verdict == "identified" and est.wrench.fit.chi2_dof < 4
    assert abs(est.mass / payload.mass - 1) < 0.01
    assert np.linalg.norm(est.com_ee - payload.p_com_ee) < 0.002
    assert np.all(np.abs(_z(est, payload.mass, payload.p_com_ee)) < 3)
    with_urdf = estimate_wrench_static(robot, loaded, **drift)
    assert with_urdf.verdict == "unreliable"  # its tool's error is not known: it is not
    both = held_body(payload, excess)  # what the URDF's tool leaves: payload and excess
    assert abs(with_urdf.mass - both.mass) < 3 * np.sqrt(with_urdf.cov[0, 0])
    assert abs(with_urdf.mass - payload.mass) > 0.5 * excess.mass


def _window_mean_cov(windows, rw_std, rate_std):
    """(k, k) covariance of k window means of a random walk W (Var W_t = rw_std^2 t) plus a
    drift r t (r ~ N(0, rate_std^2)), one axis; windows (a, b) apart in time, written out:
    E[min(s, t)] is the earlier window's middle for two windows, a + (b - a) / 3 for one."""
    k = len(windows)
    C = np.empty((k, k))
    for i, (a, b) in enumerate(windows):
        for j, (c, d) in enumerate(windows):
            C[i, j] = a + (b - a) / 3 if i == j else 0.5 * min(a + b, c + d)
    mid = np.array([0.5 * (a + b) for a, b in windows])
    return rw_std**2 * C + rate_std**2 * np.outer(mid, mid)


def test_the_drift_between_windows_in_the_covariance_gives_honest_intervals():
    """Readings with the FT 300-S's drift, drawn sample by sample at 100 Hz here: with the
    drift's covariance the residuals match it (chi2 per dof near 1) and the 95 % intervals
    hold the truth 95 % of the time; with the windows' white noise alone the residuals are
    many times that noise."""
    from comgrasp_pin.estimation.wrench import fit_static_wrench

    sheet = sensor_preset("realistic").wrench
    rw, rate = np.repeat(sheet.drift_std, 3), np.repeat(sheet.drift_rate_std, 3)
    rng = np.random.default_rng(35)
    g_sensor = np.array([[0, 0, -9.81], [0, -8.5, -4.9], [6.9, 0, -6.9], [-5.7, 5.7, 5.7]])
    windows = [(0.1, 2.4), (8.0, 10.5), (17.0, 19.5), (28.0, 30.5)]
    white = np.repeat(np.asarray(sheet.noise_std), 3) / np.sqrt(240)
    cov = np.zeros((24, 24))
    for axis in range(6):
        C = _window_mean_cov(windows, rw[axis], rate[axis])
        cov[axis::6, axis::6] = C + np.diag(np.full(4, white[axis] ** 2))
    t = np.arange(0, 30.5, 0.01)
    inside = [(t >= a) & (t <= b) for a, b in windows]
    z, chi2, chi2_white = [], [], []
    for _ in range(300):
        m, c = rng.uniform(0.5, 2.0), rng.uniform(-0.05, 0.1, 3)
        drift = np.cumsum(rng.normal(size=(len(t), 6)) * rw * 0.1, axis=0)  # sqrt(0.01 s)
        drift += np.outer(t, rng.normal(size=6) * rate)
        wrench = np.array([np.r_[m * g, np.cross(c, m * g)] for g in g_sensor])
        wrench += rng.normal(size=6) + np.array([drift[w].mean(axis=0) for w in inside])
        wrench += white * rng.normal(size=(4, 6))
        fit = fit_static_wrench(g_sensor, wrench, None, wrench_cov=cov)
        z.append((np.r_[fit.mass - m, fit.com_sensor - c]) / np.sqrt(np.diag(fit.cov)))
        chi2.append(fit.chi2_dof)
        chi2_white.append(fit_static_wrench(g_sensor, wrench, white).chi2_dof)
    assert 0.8 < np.mean(chi2) < 1.2
    coverage = np.mean(np.abs(z) < 1.96, axis=0)
    assert np.all((coverage > 0.91) & (coverage < 0.99)), coverage
    assert np.median(chi2_white) > 5
