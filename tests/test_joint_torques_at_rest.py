"""robot_io.at_rest.joint_torques: the Panda target (3 planned poses, 0.05 N m per sample
at 200 Hz, 1 s windows), the reported sigma against a Monte Carlo spread, carried-over
tau_before, a tilted mount. Truth from Pinocchio RNEA with an appended payload body
(tests/_payload)."""

import numpy as np
import pinocchio as pin
import pytest
from _logs import rnea_torques, session
from _payload import panda, payload_torques

from comgrasp_pin.errors import InvalidInputError, LogError
from comgrasp_pin.planning.measurement_poses import plan_measurement_poses
from comgrasp_pin.robot_io import estimate_from_log, load_robot

MASS, COM = 0.85, np.array([0.025, -0.012, 0.06])
START = np.array([0.0, -0.3, 0.0, -2.2, 0.0, 2.0, 0.8])
NOISE, RATE = 0.05, 200.0


@pytest.fixture(scope="module")
def robot():
    return panda()


@pytest.fixture(scope="module")
def planned(robot):
    return plan_measurement_poses(robot, 3, start=START, torque_std=NOISE / np.sqrt(RATE)).q


def test_panda_target_truth_within_three_sigma(robot, planned):
    log, before, after, _ = session(planned, rnea_torques(robot, MASS, COM), robot.joint_names,
                                    RATE, NOISE, seed=3)  # fmt: skip
    r = estimate_from_log(robot, log, before, after)
    est = r
    assert est.unobservable_ee is None and est.at_rest.n_poses == 3
    std = est.std
    assert abs(est.mass - MASS) < 3 * std[0]
    assert np.all(np.abs(est.com_ee - COM) < 3 * std[1:])
    # the noise of one averaged reading: 0.05 / sqrt(201 samples), from the samples' spread
    np.testing.assert_allclose(r.joint_torques.torque_std, NOISE / np.sqrt(201), rtol=0.15)
    assert r.joint_torques.noise_from == "samples"


def test_reported_sigma_matches_monte_carlo_spread(robot, planned):
    """200 synthetic logs (noise redrawn, no bags): the mean reported std is within 30 % of
    the spread of the estimates."""
    log, before, after, _ = session(planned, rnea_torques(robot, MASS, COM), robot.joint_names,
                                    RATE, 0.0)  # fmt: skip
    rng = np.random.default_rng(7)
    estimates, stds = [], []
    for _ in range(200):
        noisy = type(log)(log.time, log.joint_names, log.position,
                          log.effort + NOISE * rng.standard_normal(log.effort.shape))  # fmt: skip
        est = estimate_from_log(robot, noisy, before, after)
        estimates.append(np.r_[est.mass, est.com_ee])
        stds.append(est.std)
    spread = np.std(estimates, axis=0, ddof=1)
    ratio = np.mean(stds, axis=0) / spread
    print("sigma / MC spread (mass, cx, cy, cz):", ratio)
    assert np.all(np.abs(ratio - 1) < 0.3), ratio
    bias = np.abs(np.mean(estimates, axis=0) - np.r_[MASS, COM])
    assert np.all(bias < 4 * spread / np.sqrt(200))


def test_given_torque_std_is_the_std_of_an_averaged_reading(robot, planned):
    log, before, after, _ = session(planned, rnea_torques(robot, MASS, COM), robot.joint_names,
                                    RATE, NOISE, seed=4)  # fmt: skip
    from_samples = estimate_from_log(robot, log, before, after)
    given = estimate_from_log(robot, log, before, after, torque_std=NOISE / np.sqrt(201))
    np.testing.assert_allclose(given.std, from_samples.std, rtol=0.15)
    assert given.joint_torques.noise_from == "given"


def test_tau_before_is_carried_to_the_after_configuration(robot, planned):
    """The after poses sag by up to 0.02 rad: without the carry-over the mass would be off by
    far more than its std; with it, the truth is within 3 sigma."""
    shift = np.array([0.0, 0.02, -0.01, 0.015, 0.0, -0.02, 0.01])
    log, before, after, _ = session(planned, rnea_torques(robot, MASS, COM), robot.joint_names,
                                    RATE, NOISE, seed=5, q_shift_after=shift)  # fmt: skip
    est = estimate_from_log(robot, log, before, after)
    assert abs(est.mass - MASS) < 3 * est.std[0]
    assert np.all(np.abs(est.com_ee - COM) < 3 * est.std[1:])


def test_tilted_mount(robot, planned):
    """An arm on a 30 deg slope: torques from Pinocchio with model.gravity tilted in the base
    frame; load_robot with that gravity recovers the payload."""
    g = 9.81 * np.array([np.sin(np.radians(30)), 0.0, -np.cos(np.radians(30))])
    tilted = panda()
    tilted.model.gravity = pin.Motion(np.r_[g, 0.0, 0.0, 0.0])

    def torques(Qs, loaded):
        tb, ta = payload_torques(tilted, Qs, MASS, COM)
        return ta if loaded else tb

    log, before, after, _ = session(planned, torques, robot.joint_names, RATE, NOISE, seed=6)
    mounted = load_robot(robot.urdf_path, robot.ee_frame, gravity_base=g)
    est = estimate_from_log(mounted, log, before, after)
    assert abs(est.mass - MASS) < 3 * est.std[0]
    assert np.all(np.abs(est.com_ee - COM) < 3 * est.std[1:])
    wrong = estimate_from_log(robot, log, before, after)  # floor gravity assumed
    assert np.max(np.abs(wrong.com_ee - COM)) > 0.05  # the mount matters: 5 cm off
    # and the residuals say so (the chi-square rule): its interval widens to hold the truth
    assert wrong.std[1:].max() > 10 * est.std[1:].max()
    assert np.all(np.abs(wrong.com_ee - COM) < wrong.t95[1:] * wrong.std[1:])


def test_unpaired_windows_are_refused(robot, planned):
    log, before, after, _ = session(planned, rnea_torques(robot, MASS, COM), robot.joint_names)
    with pytest.raises(LogError, match="same count"):
        estimate_from_log(robot, log, before, after[:2])


def test_one_pose_reports_the_unobservable_direction(robot, planned):
    log, before, after, _ = session(planned, rnea_torques(robot, MASS, COM), robot.joint_names)
    est = estimate_from_log(robot, log, before[:1], after[:1])
    down_ee = robot.ee_pose(planned[0])[:3, :3].T @ np.array([0, 0, -1.0])
    np.testing.assert_allclose(est.unobservable_ee, down_ee, atol=1e-4)  # q has encoder noise


def test_a_drifting_sensor_is_covered_with_drift_std(robot, planned):
    """200 logs whose efforts drift (a random walk of 0.01 N m / sqrt(s) per joint, drawn on
    the log's own clock, and the white noise): with ``drift_std`` the reported std is within
    30 % of the estimates' spread. Taken as white noise, the drift shows in the residuals and
    their chi-square widens the std towards the spread (0.66-1.03 of it here): not as close
    as the model of the drift."""
    log, before, after, _ = session(planned, rnea_torques(robot, MASS, COM), robot.joint_names,
                                    RATE, 0.0)  # fmt: skip
    rng = np.random.default_rng(8)
    drift, dt = 0.01, np.diff(log.time, prepend=log.time[0])[:, None]
    results: dict = {0.0: ([], []), drift: ([], [])}
    for _ in range(200):
        walk = np.cumsum(drift * np.sqrt(dt) * rng.standard_normal(log.effort.shape), axis=0)
        effort = log.effort + walk + NOISE * rng.standard_normal(log.effort.shape)
        noisy = type(log)(log.time, log.joint_names, log.position, effort)
        for drift_std, (estimates, stds) in results.items():
            est = estimate_from_log(robot, noisy, before, after, drift_std=drift_std)
            estimates.append(np.r_[est.mass, est.com_ee])
            stds.append(est.std)
    ratios = {}
    for drift_std, (estimates, stds) in results.items():
        ratios[drift_std] = np.mean(stds, axis=0) / np.std(estimates, axis=0, ddof=1)
    print("sigma / MC spread without and with drift_std:", ratios)
    assert np.all(np.abs(ratios[drift] - 1) < 0.3), ratios[drift]
    assert np.all(ratios[0.0] > 0.5), ratios[0.0]
    assert np.mean(np.abs(ratios[drift] - 1)) < np.mean(np.abs(ratios[0.0] - 1))


def test_a_negative_drift_is_refused(robot, planned):
    log, before, after, _ = session(planned, rnea_torques(robot, MASS, COM), robot.joint_names,
                                    RATE, NOISE)  # fmt: skip
    with pytest.raises(InvalidInputError, match="drift_std"):
        estimate_from_log(robot, log, before, after, drift_std=-0.1)
