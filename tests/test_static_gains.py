"""The static estimate (robot_io.estimate_from_log) with the drive gains' covariance: a log of
motor currents read with gains K whose relative errors delta_j scale joint j's efforts. The
project's UR5 at 3 poses, torques from Pinocchio RNEA with a payload body (tests/_payload) plus
0.05 N m noise per sample. The gains' part of the covariance against a Monte Carlo made on the
data (each joint's efforts scaled by 1 + delta, re-estimated without the gains' covariance);
nothing changes without it; `comgrasp estimate --current-gains --gain-std` on a CSV of
currents."""

import dataclasses
import json

import numpy as np
import pytest
from _logs import rnea_torques, session

from comgrasp_pin._paths import urdf_path
from comgrasp_pin.cli import main
from comgrasp_pin.robot_io import JointLog, estimate_from_log, write_csv
from comgrasp_pin.robot_io.front_door import load_robot
from comgrasp_pin.robot_io.results import result_dict

URDF = str(urdf_path("ur5_gripper.urdf"))
MASS, COM = 0.8, np.array([0.03, -0.02, 0.05])
UR_Q = np.array(
    [[0.0, -1.6, 1.6, -1.57, -1.57, 0.0], [0.4, -1.2, 1.2, -0.4, 0.8, 1.0],
     [-0.5, -1.9, 1.5, -2.5, -0.6, -1.2]]
)  # fmt: skip
K = np.array([13.2, 13.2, 9.3, 4.6, 4.6, 4.6])  # N m per A (UR5-like)
REL = 0.1  # the gains' relative std
DRAWS = 200


@pytest.fixture(scope="module")
def robot():
    return load_robot(URDF, "eelink")


@pytest.fixture(scope="module")
def torque_session(robot):
    """(log of torques, before, after): 200 Hz, 0.05 N m noise per sample."""
    log, before, after, _ = session(UR_Q, rnea_torques(robot, MASS, COM), robot.joint_names,
                                    200.0, 0.05, seed=21)  # fmt: skip
    return log, before, after


@pytest.fixture(scope="module")
def current_log(torque_session):
    """The same log marked as read from currents with gains K (its efforts, torques, as is)."""
    return dataclasses.replace(torque_session[0], current_gains=K)


def test_gains_part_matches_monte_carlo_on_the_data(robot, torque_session, current_log):
    _, before, after = torque_session
    plain = estimate_from_log(robot, current_log, before, after)
    gain_cov = np.diag((REL * K) ** 2)
    r = estimate_from_log(robot, current_log, before, after, gain_cov=gain_cov)
    est = r
    assert est.mass == plain.mass
    np.testing.assert_array_equal(est.com_ee, plain.com_ee)
    np.testing.assert_allclose(est.cov, plain.cov + r.joint_torques.gains_cov, rtol=1e-12)
    assert np.all(est.std > plain.std)
    parts = r.std_parts
    assert parts is not None
    np.testing.assert_allclose(parts["noise"], plain.std[0], rtol=1e-9)
    np.testing.assert_allclose(np.hypot(parts["noise"], parts["gains"]), est.std[0], rtol=1e-12)
    assert result_dict(r)["std"]["mass_kg_by_source"] == parts
    gains_std = np.sqrt(np.diag(r.joint_torques.gains_cov))
    # Monte Carlo on the data: each joint's efforts scaled by 1 + delta_j, re-estimated
    rng = np.random.default_rng(5)
    draws = []
    for _ in range(DRAWS):
        delta = REL * rng.standard_normal(robot.nq)
        scaled = dataclasses.replace(current_log, effort=current_log.effort * (1 + delta))
        e = estimate_from_log(robot, scaled, before, after)
        draws.append(np.r_[e.mass, e.com_ee])
    spread = np.std(draws, axis=0, ddof=1)
    ratio = spread / gains_std
    print("MC spread / stated gains part (mass, cx, cy, cz):", ratio)
    assert np.all((ratio > 0.85) & (ratio < 1.15)), ratio


def test_nothing_changes_without_gain_cov_or_with_torques(robot, torque_session, current_log):
    torques, before, after = torque_session
    base = estimate_from_log(robot, torques, before, after)
    gain_cov = np.diag((REL * K) ** 2)
    for r in (estimate_from_log(robot, current_log, before, after),  # no gain_cov
              estimate_from_log(robot, torques, before, after, gain_cov=gain_cov)):  # fmt: skip
        assert r.joint_torques.gains_cov is None and r.std_parts == {}
        assert r.mass == base.mass
        np.testing.assert_array_equal(r.com_ee, base.com_ee)
        np.testing.assert_array_equal(r.cov, base.cov)
        assert result_dict(r) == result_dict(base)


def test_gain_cov_of_the_wrong_shape_is_refused(robot, torque_session, current_log):
    from comgrasp_pin.errors import InvalidInputError

    _, before, after = torque_session
    with pytest.raises(InvalidInputError, match="gain_cov"):
        estimate_from_log(robot, current_log, before, after, gain_cov=np.eye(3))


def test_cli_gain_std_widens_the_static_mass_std(robot, torque_session, tmp_path):
    torques, before, after = torque_session
    currents = JointLog(torques.time, torques.joint_names, torques.position,
                        torques.effort / K, "currents")  # fmt: skip
    csv = write_csv(currents, tmp_path / "currents.csv")
    windows = [",".join(f"{a:.4f}:{b:.4f}" for a, b in ws) for ws in (before, after)]
    gains = ",".join(f"{k:g}" for k in K)
    results = {}
    for name, extra in (("exact", []), ("std", ["--gain-std", "0.1"])):
        out = tmp_path / f"{name}.json"
        code = main(["estimate", "--urdf", URDF, "--ee-frame", "eelink", "--csv", str(csv),
                     "--before", windows[0], "--after", windows[1], "--current-gains", gains,
                     *extra, "--out", str(out)])  # fmt: skip
        assert code == 0
        results[name] = json.loads(out.read_text())
    exact, widened = results["exact"], results["std"]
    assert widened["mass_kg"] == pytest.approx(exact["mass_kg"], rel=1e-12)
    assert abs(widened["mass_kg"] - MASS) < 3 * widened["std"]["mass_kg"]
    assert widened["std"]["mass_kg"] > 1.5 * exact["std"]["mass_kg"]
    by_source = widened["std"]["mass_kg_by_source"]
    assert by_source["noise"] == pytest.approx(exact["std"]["mass_kg"], rel=1e-6)
    assert by_source["gains"] > by_source["noise"]
    assert exact["std"]["mass_kg_by_source"]["gains"] == 0.0  # gains without std: exact
