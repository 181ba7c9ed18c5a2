"""The arm's own model, drive gains and honest intervals, in MuJoCo against its truth (issue 32).

The simulated UR5 plays two different excitation motions (A and B). The estimator is given
a WRONG URDF model of the arm (upper arm and forearm 20 % lighter than the simulated ones):
the situation of a real arm whose vendor inertials are off. The references are independent
of the code under test: the simulator's payload, a zero payload, gains the test itself puts
into the torques, and a Monte Carlo over gain errors made on the data.
"""

import json
from dataclasses import replace

import numpy as np
import pinocchio as pin
import pytest

from comgrasp_pin.cli import main
from comgrasp_pin.errors import InvalidInputError, LogError
from comgrasp_pin.estimation.trust import Checks, judge, motion_reasons
from comgrasp_pin.planning.excitation import ExcitationSettings, plan_excitation
from comgrasp_pin.robot_io import write_csv
from comgrasp_pin.robot_io.from_motion.arm_model import (
    arm_model_dict,
    check_matches,
    identify_arm,
    load_arm_model,
)
from comgrasp_pin.robot_io.from_motion.dynamic import check_on_log, estimate_payload_dynamic
from comgrasp_pin.robot_io.from_motion.gain_calibration import calibrate_gains
from comgrasp_pin.simulation.arm_worlds import arm_robot, arm_urdf
from comgrasp_pin.simulation.payload_motion import simulate_motion
from comgrasp_pin.simulation.payloads import box

FAST = {"n_random": 200, "n_starts": 1}
Z95 = 1.96


def _wrong_robot():
    """The UR5 with links 2 and 3 (upper arm, forearm) 20 % lighter than the simulator's."""
    robot = arm_robot("ur5")
    for j in (2, 3):
        I = robot.model.inertias[j]
        robot.model.inertias[j] = pin.Inertia(0.8 * I.mass, I.lever, 0.8 * I.inertia)
    robot.data = robot.model.createData()
    return robot


@pytest.fixture(scope="module")
def runs():
    robot = arm_robot("ur5")
    settings = ExcitationSettings(acceleration_limit=12.0, **FAST)
    A = plan_excitation(robot, 20.0, settings=settings, seed=0)
    B = plan_excitation(robot, 20.0, settings=settings, seed=1)
    a, b = (A.t, A.q, A.qd, A.qdd), (B.t, B.q, B.qd, B.qdd)
    return {
        "empty_A": simulate_motion("ur5", None, *a, seed=11, offsets_seed=1),
        "empty_B": simulate_motion("ur5", None, *b, seed=12, offsets_seed=2),
        "loaded_B": simulate_motion("ur5", box(), *b, seed=13, offsets_seed=3),
        "loaded_A": simulate_motion("ur5", box(), *a, seed=14, offsets_seed=4),
    }


@pytest.fixture(scope="module")
def wrong():
    return _wrong_robot()


@pytest.fixture(scope="module")
def arm(runs, wrong):
    return identify_arm(wrong, runs["empty_A"])


def test_a_wrong_urdf_reads_an_empty_arm_as_a_payload_and_says_it_is_unreliable(runs, wrong):
    est = estimate_payload_dynamic(wrong, runs["empty_B"])
    assert est.mass - Z95 * np.sqrt(est.cov[0, 0]) > 0.05  # a confident wrong payload...
    assert est.verdict == "unreliable"  # ...that the verdict does not let through
    assert any("nominal model" in r for r in est.reasons)


def test_the_identified_arm_model_gives_a_payload_of_another_motion(runs, wrong, arm):
    payload = box()
    est = estimate_payload_dynamic(wrong, runs["loaded_B"], arm_model=arm)
    assert est.joint_torques.arm_model == "identified arm model"
    assert abs(est.mass / payload.mass - 1) < 0.02
    assert np.linalg.norm(est.com_ee - payload.p_com_ee) < 5e-3  # the 2 % and 5 mm
    z = (np.concatenate([[est.mass], est.com_ee]) - [payload.mass, *payload.p_com_ee]) / np.sqrt(
        np.diag(est.cov)
    )
    assert np.all(np.abs(z) < 4), z
    assert est.std_parts["arm model"] > 0  # the arm model's own uncertainty is carried
    assert est.verdict == "identified", est.reasons
    assert est.motion.validation.explained_total > 0.95


def test_an_empty_arm_with_the_arm_model_claims_no_payload(runs, wrong, arm):
    est = estimate_payload_dynamic(wrong, runs["empty_B"], arm_model=arm)
    std = np.sqrt(est.cov[0, 0])
    assert est.mass - Z95 * std <= 0 <= est.mass + Z95 * std
    assert est.verdict == "nothing held" and est.reasons == (est.reasons[0],)  # that one alone
    assert "no payload seen" in est.reasons[0]
    assert est.motion.solver_status.startswith("not run")


def test_the_arm_model_file_round_trips_and_refuses_other_arms(runs, wrong, arm, tmp_path):
    path = tmp_path / "ARM.json"
    path.write_text(json.dumps(arm_model_dict(arm)))
    back = load_arm_model(path)
    np.testing.assert_array_equal(back.params, arm.params)
    np.testing.assert_array_equal(back.base_columns, arm.base_columns)
    a = estimate_payload_dynamic(wrong, runs["loaded_B"], arm_model=arm)
    b = estimate_payload_dynamic(wrong, runs["loaded_B"], arm_model=back)
    assert a.mass == pytest.approx(b.mass, rel=1e-9)
    with pytest.raises(InvalidInputError, match="drive gains"):
        check_matches(arm, wrong, replace(runs["loaded_B"], current_gains=np.ones(6)))
    with pytest.raises(InvalidInputError, match="joints"):
        check_matches(replace(arm, joint_names=("a",) * 6), wrong, runs["loaded_B"])
    (tmp_path / "bad.json").write_text('{"format": "something else"}')
    with pytest.raises(LogError, match="identify-arm"):
        load_arm_model(tmp_path / "bad.json")


def test_the_gains_covariance_matches_gain_errors_made_on_the_data(runs):
    """Scale each joint's efforts by 1 + delta, delta ~ N(0, 0.1): the masses' spread is the
    stated gains' std (the linearisation checked by Monte Carlo on the data itself)."""
    robot = arm_robot("ur5")
    K = np.array([8.0, 9.0, 10.0, 11.0, 12.0, 13.0])
    loaded, empty = (replace(runs[k], current_gains=K) for k in ("loaded_B", "empty_B"))
    est = estimate_payload_dynamic(robot, loaded, empty, gain_cov=np.diag((0.1 * K) ** 2))
    rng = np.random.default_rng(5)
    masses = []
    for _ in range(16):
        s = 1 + 0.1 * rng.standard_normal(6)
        logs = [replace(x, effort=x.effort * s) for x in (loaded, empty)]
        masses.append(estimate_payload_dynamic(robot, *logs).mass)
    ratio = np.std(masses, ddof=1) / est.std_parts["gains"]
    assert 0.6 < ratio < 1.6, (ratio, masses)


def test_calibrated_gains_recover_the_gains_put_into_the_currents(runs):
    robot = arm_robot("ur5")
    K_true = np.array([9.0, 11.0, 8.0, 10.0, 7.0, 12.0])
    currents = [
        replace(runs[k], effort=runs[k].effort / K_true, current_gains=np.ones(6))
        for k in ("loaded_B", "empty_B")
    ]
    cal = calibrate_gains(robot, *currents, known_mass_kg=box().mass)
    std = np.sqrt(np.diag(cal.cov))
    assert np.all(np.abs(cal.gains - K_true) < 4 * std), (cal.gains, std)
    # within 3 % where the motion determines the gain (std 0.1 %); the last wrist joint's
    # (std 2.5 %: the box barely loads it) is held by its 4 std above
    assert np.all(np.abs(cal.gains[:5] / K_true[:5] - 1) < 0.03)
    assert np.linalg.norm(cal.com_m - box().p_com_ee) < 5e-3


def _checks(**kw):
    base = dict(mass_kg=1.0, mass_std_kg=0.01, arm_model="empty run", explained=0.99,
                halves_mass_kg=(1.0, 1.01), halves_diff_std_kg=0.02)  # fmt: skip
    return Checks(**{**base, **kw})


def _verdict(c: Checks):
    """The verdict of a motion's checks: the shared rules (trust.judge) and the motion's own."""
    cov = np.diag([c.mass_std_kg**2, 1e-6, 1e-6, 1e-6])
    return judge(c.mass_kg, np.zeros(3), cov, 50.0, motion_reasons(c))


@pytest.mark.parametrize(
    "change, word, phrase",
    [
        ({"mass_kg": 0.01}, "nothing held", "no payload seen"),
        ({"mass_kg": -0.5}, "unreliable", "negative"),
        ({"mass_kg": 60.0}, "unreliable", "heavier than the arm"),
        ({"arm_model": "URDF model + friction"}, "unreliable", "nominal model"),
        ({"explained": 0.5}, "unreliable", "explains 50 %"),
        ({"halves_mass_kg": (1.0, 1.2)}, "unreliable", "halves disagree"),
    ],
)
def test_each_verdict_rule_objects_alone(change, word, phrase):
    """Each rule alone; with no payload seen the fit's rules (explained, halves) stay quiet."""
    assert _verdict(_checks()) == ("identified", ())
    got, reasons = _verdict(_checks(**change))
    assert got == word and len(reasons) == 1 and phrase in reasons[0]
    nothing = _verdict(_checks(mass_kg=0.0, explained=0.0, halves_mass_kg=(0.0, 0.5)))
    assert nothing[0] == "nothing held"
    assert len(nothing[1]) == 1 and "no payload seen" in nothing[1][0]


def test_a_result_that_is_not_finite_is_never_identified():
    """NaN in the CoM or the covariance: unreliable, whatever else the checks say."""
    cov = np.diag([1e-4, 1e-6, 1e-6, 1e-6])
    word, reasons = judge(1.0, np.array([0.0, np.nan, 0.0]), cov, 50.0)
    assert word == "unreliable" and "not finite" in reasons[0]
    word, reasons = judge(float("nan"), np.zeros(3), cov, 50.0)
    assert word == "unreliable" and "not finite" in reasons[0]
    assert judge(1.0, np.zeros(3), None, 50.0)[0] == "unreliable"  # no uncertainty


def test_identify_arm_then_estimate_from_the_command_line(runs, tmp_path, capsys):
    urdf, args = str(arm_urdf("ur5")), ["--ee-frame", "eelink"]
    write_csv(runs["empty_A"], tmp_path / "empty.csv")
    write_csv(runs["loaded_B"], tmp_path / "loaded.csv")
    arm_json, out, png = tmp_path / "ARM.json", tmp_path / "RESULT.json", tmp_path / "fit.png"
    assert main(["identify-arm", "--urdf", urdf, *args, "--csv", str(tmp_path / "empty.csv"),
                 "--out", str(arm_json)]) == 0  # fmt: skip
    assert main(["estimate", "--dynamic", "--urdf", urdf, *args, "--csv",
                 str(tmp_path / "loaded.csv"), "--arm-model", str(arm_json), "--plot", str(png),
                 "--out", str(out)]) == 0  # fmt: skip
    result = json.loads(out.read_text())
    assert (
        result["verdict"] == "identified"
        and result["joint_torques"]["arm_model"] == "identified arm model"
    )
    assert abs(result["mass_kg"] / box().mass - 1) < 0.02
    lo, hi = result["interval95_mass_kg"]
    assert lo < box().mass < hi
    assert len(result["motion"]["validation"]["rms_Nm"]) == 6
    assert "VERDICT: identified" in capsys.readouterr().out
    import matplotlib.image

    assert matplotlib.image.imread(png).shape[0] > 500  # a panel per joint
    code = main(["estimate", "--dynamic", "--urdf", urdf, *args, "--csv",
                 str(tmp_path / "loaded.csv"), "--arm-model", str(arm_json), "--empty-csv",
                 str(tmp_path / "empty.csv"), "--out", str(out)])  # fmt: skip
    assert code == 2 and "not both" in capsys.readouterr().err


def test_a_second_log_of_the_same_payload_confirms_it_and_an_empty_one_does_not(runs, wrong, arm):
    est = estimate_payload_dynamic(wrong, runs["loaded_B"], arm_model=arm)
    same = check_on_log(wrong, est, runs["loaded_A"], arm)  # the box again, motion A
    assert same.motion.second_log.explained_total > 0.95 and same.verdict == "identified"
    other = check_on_log(wrong, est, runs["empty_B"], arm)  # nothing held
    assert other.motion.second_log.explained_total < 0.5
    assert other.verdict == "unreliable" and "second log" in other.reasons[-1]
