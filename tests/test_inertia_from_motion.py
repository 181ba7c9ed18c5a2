"""The whole payload from a planned motion, end to end in MuJoCo (issue 26, item 4).

`plan_excitation` plans the motion; MuJoCo plays it with the computed-torque servo on the
project's UR5 and example-robot-data's Panda, holding payloads of known inertia, with the
realistic link-side torque sensor; the logs go through real ROS 2 bags and CSV files into
`comgrasp estimate --dynamic`. The truth is the simulator's payload (its inertia checked
against MuJoCo's own in test_payload_motion); the targets are the issue's.
"""

import json

import numpy as np
import pytest

from comgrasp_pin.cli import main
from comgrasp_pin.planning.excitation import ExcitationSettings, plan_excitation
from comgrasp_pin.robot_io import write_bag, write_csv
from comgrasp_pin.robot_io.from_motion.dynamic import estimate_payload_dynamic
from comgrasp_pin.robot_io.payload_files.payload import T_flange_ee
from comgrasp_pin.simulation.arm_worlds import arm_robot, arm_urdf
from comgrasp_pin.simulation.payload_motion import simulate_motion
from comgrasp_pin.simulation.payloads import box, off_axis_weight, rod

DOMINANT_KGM2 = 1e-3  # principal moments held to 10 % (benchmarks/inertia_from_motion.py)
FAST = {"n_random": 200, "n_starts": 1}  # a shorter search than the default, for the suite


def _motion(arm: str, acceleration: float):
    settings = ExcitationSettings(acceleration_limit=acceleration, **FAST)
    return plan_excitation(arm_robot(arm), 20.0, settings=settings, seed=0)


def _runs(arm, motion, payload, seed):
    args = (motion.t, motion.q, motion.qd, motion.qdd)
    empty = simulate_motion(arm, None, *args, seed=100 + seed, offsets_seed=seed)
    return simulate_motion(arm, payload, *args, seed=seed, offsets_seed=seed), empty


def _check_targets(est, payload):
    assert abs(est.mass / payload.mass - 1) < 0.01
    assert np.linalg.norm(est.com_ee - payload.p_com_ee) < 2e-3
    true, axes = np.linalg.eigh(payload.I_com_ee)
    for moment, u in zip(true, axes.T):
        estimated = u @ est.inertia.inertia_com_ee @ u
        std = np.sqrt(np.kron(u, u) @ est.inertia.inertia_cov @ np.kron(u, u))
        assert abs(estimated - moment) < 4 * std  # the stated uncertainty holds the truth
        if moment >= DOMINANT_KGM2:
            assert abs(estimated / moment - 1) < 0.10, (estimated, moment)


@pytest.fixture(scope="module")
def ur5_motion():
    return _motion("ur5", 12.0)


def test_ur5_box_through_bags_and_the_command_line(ur5_motion, tmp_path, capsys):
    log, empty = _runs("ur5", ur5_motion, box(), seed=0)
    bag = write_bag(log, tmp_path / "loaded", "mcap", extra_joints={"finger_joint": 0.0})
    empty_bag = write_bag(empty, tmp_path / "empty", "sqlite3")
    out, script = tmp_path / "RESULT.json", tmp_path / "payload.script"
    args = ["estimate", "--dynamic", "--urdf", str(arm_urdf("ur5")), "--ee-frame", "eelink",
            "--bag", str(bag), "--empty-bag", str(empty_bag), "--out", str(out),
            "--flange-frame", "tool0", "--export-ur", str(script)]  # fmt: skip
    assert main(args) == 0
    result = json.loads(out.read_text())
    assert (
        result["motion"]["velocity_from"] == "log"
        and result["joint_torques"]["arm_model"] == "empty run"
    )
    est = estimate_payload_dynamic(arm_robot("ur5"), log, empty)
    assert result["mass_kg"] == pytest.approx(est.mass, rel=1e-6)  # bags keep the samples
    _check_targets(est, box())
    # the URScript's inertia: about the CoM in tool0's axes
    R = T_flange_ee(arm_robot("ur5"), "tool0")[:3, :3]
    I = R @ np.array(result["inertia"]["inertia_kgm2"]) @ R.T
    line = [s for s in script.read_text().splitlines() if s.startswith("set_target_payload")][0]
    six = [float(v) for v in line.split("[")[2].rstrip("])").split(",")]
    np.testing.assert_allclose(six, [I[0, 0], I[1, 1], I[2, 2], I[0, 1], I[0, 2], I[1, 2]],
                               rtol=1e-6, atol=1e-9)  # fmt: skip
    assert "identified" in script.read_text()


@pytest.mark.parametrize("payload", [rod(), off_axis_weight()], ids=lambda p: p.name)
def test_ur5_other_payloads(ur5_motion, payload):
    log, empty = _runs("ur5", ur5_motion, payload, seed=1)
    _check_targets(estimate_payload_dynamic(arm_robot("ur5"), log, empty), payload)


def test_panda_rod_from_csv_files(tmp_path):
    motion = _motion("panda", 7.5)  # Franka's joint 2 limit
    log, empty = _runs("panda", motion, rod(), seed=2)
    robot = arm_robot("panda")
    from comgrasp_pin.robot_io.log_files import read_csv

    loaded = read_csv(write_csv(log, tmp_path / "l.csv"), robot.joint_names)
    empty = read_csv(write_csv(empty, tmp_path / "e.csv"), robot.joint_names)
    _check_targets(estimate_payload_dynamic(robot, loaded, empty), rod())
