"""The simulator's own data: the UR5 in the MuJoCo world (servo, noisy torque sensor at
500 Hz) before and after a payload is attached at three poses, written as a ROS 2 bag by
rosbags, estimated by `comgrasp estimate`: the payload lies within the reported interval."""

import json

import numpy as np
import pytest
from _logs import simulated_session

from comgrasp_pin._paths import urdf_path
from comgrasp_pin.cli import main
from comgrasp_pin.robot_io import write_bag

MASS, COM = 0.6, np.array([0.03, -0.015, 0.04])
Q = np.array(
    [[0.0, -1.6, 1.6, -1.57, -1.57, 0.0], [0.4, -1.2, 1.2, -0.4, 0.8, 1.0],
     [-0.5, -1.9, 1.5, -2.5, -0.6, -1.2]]
)  # fmt: skip


@pytest.fixture(scope="module")
def sim_bag(tmp_path_factory):
    log, before, after, grasp = simulated_session(Q, MASS, COM, seed=3)
    bag = write_bag(log, tmp_path_factory.mktemp("sim") / "bag", "mcap",
                    extra_joints={"finger_left_joint": 0.0, "finger_right_joint": 0.0})  # fmt: skip
    return bag, before, after, grasp


def _win(ws):
    return ",".join(f"{a:.4f}:{b:.4f}" for a, b in ws)


@pytest.mark.parametrize("mode", ["windows", "auto"])
def test_simulated_ur5_payload_within_the_interval(sim_bag, tmp_path, mode):
    bag, before, after, grasp = sim_bag
    out = tmp_path / "RESULT.json"
    args = ["estimate", "--urdf", str(urdf_path("ur5_gripper.urdf")), "--ee-frame", "eelink",
            "--bag", str(bag), "--out", str(out)]  # fmt: skip
    if mode == "auto":
        args += ["--auto", "--grasp-time", f"{grasp:.4f}"]
    else:
        args += ["--before", _win(before), "--after", _win(after)]
    assert main(args) == 0
    r = json.loads(out.read_text())
    std = np.sqrt(np.diag(r["cov"]))
    assert r["at_rest"]["n_poses"] == 3 and r["unobservable"] is None
    assert abs(r["mass_kg"] - MASS) < 3 * std[0]
    assert np.all(np.abs(np.array(r["com_m"]) - COM) < 3 * std[1:])
    assert std[0] < 0.005 and np.all(std[1:] < 0.002)  # informative, not merely wide
