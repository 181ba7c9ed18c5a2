"""Each error source's part of a motion's interval: neither too wide nor too narrow.

Two-sided Monte Carlo per source, as tests/test_dynamic_estimate.py does for the noise: the
rms normal score (each z through Student's t of its stated degrees of freedom) of the mass
and the CoM over repeated draws lies in a band that a covariance three times too large or
too small in variance leaves (about 0.55 or 1.7). References: Pinocchio's RNEA of the arm
with the payload appended (not the regressor under test), friction of the model's own shape
(so that no model error the same in every draw enters), the truth of the appended body.
Sources: the drive gains (one error shared by all joints, and independent errors), the arm's
identified model, a wrist sensor's wrench along a motion.
"""

import numpy as np
import pytest
from test_dynamic_estimate import MC_PAYLOAD, arm_efforts, fourier_motion, normal_score
from test_wrench_dynamic import wrench_log

from comgrasp_pin.robot import RobotModel
from comgrasp_pin.robot_io import JointLog, estimate_payload_dynamic, identify_arm
from comgrasp_pin.robot_io.from_motion.motion_system import COULOMB_SPEED
from comgrasp_pin.robot_io.from_motion.wrench_dynamic import estimate_wrench_dynamic

DRAWS = 40
BAND = (0.65, 1.5)
"""The rms normal score of mass and CoM pooled (4 per draw): 1 when calibrated, sampling
spread about 0.06 over 40 draws (0.07 over 30); a variance 3 times off gives about 0.55 or
1.7. Measured: gains common 1.03, per joint 0.81; arm model 1.05; wrench 1.21. With every
motion estimate's covariance scaled by 3 or 1/3 (a mutation run by hand): gains common 0.64,
1.56; per joint 0.47, 1.40; arm model 0.61, 1.60; wrench 0.77, 1.83. All fail but two,
which stay in the band because those sources read off-centre unperturbed: the per-joint
gains' 1/3 (1.40) and the wrench's 3 (0.77)."""
SLOW_DRAWS = 30
"""Draws of the slower sources (an arm identified, a wrench computed, per draw)."""
GAINS = np.array([10.0, 10.7, 8.5, 9.0, 9.5, 10.1])  # N m / A


@pytest.fixture(scope="module")
def robot():
    return RobotModel.ur5()


def efforts(robot, inertia, motion, rng, noise=0.05, offset=0.2):
    """The arm's efforts with friction of the model's own shape (no model error)."""
    return arm_efforts(robot, inertia, motion, rng, noise, offset, COULOMB_SPEED)


def log_of(robot, motion, tau, rng, gains=None):
    t, q = motion[0], motion[1]
    q_read = q + 1e-5 * rng.standard_normal(q.shape)
    return JointLog(t, tuple(robot.joint_names), q_read, tau, "synthetic", current_gains=gains)


def rms_score(estimates_and_truths) -> float:
    scores = [normal_score((np.r_[e.mass, e.com_ee] - np.r_[m.mass, m.lever]) / e.std, e.dof)
              for e, m in estimates_and_truths]  # fmt: skip
    return float(np.sqrt(np.mean(np.square(scores))))


@pytest.mark.parametrize("correlation", [1.0, 0.0])
def test_the_gains_part_holds(robot, correlation):
    """Gains 10 % off, drawn anew each draw (common, or per joint) and stated as gain_cov."""
    motion = fourier_motion(robot, duration=8.0)
    s = 0.1 * GAINS
    cov = np.outer(s, s) * (correlation + (1 - correlation) * np.eye(6))
    out = []
    for i in range(DRAWS):
        rng = np.random.default_rng(300 + i)
        delta = np.full(6, rng.normal(0, 0.1)) if correlation == 1 else rng.normal(0, 0.1, 6)
        scale = 1 / (1 + delta)  # the log's efforts are K_nominal I = tau / (1 + delta)
        loaded = log_of(robot, motion, scale * efforts(robot, MC_PAYLOAD, motion, rng), rng, GAINS)
        empty = log_of(robot, motion, scale * efforts(robot, None, motion, rng, offset=0.25), rng,
                       GAINS)  # fmt: skip
        out.append((estimate_payload_dynamic(robot, loaded, empty, gain_cov=cov), MC_PAYLOAD))
    assert out[0][0].std_parts["gains"] > 0
    assert BAND[0] < rms_score(out) < BAND[1]


def test_the_arm_models_part_holds(robot):
    """The arm's model identified anew each draw on an empty run of another motion."""
    motion = fourier_motion(robot, duration=8.0)
    other = fourier_motion(robot, duration=12.0, seed=1)
    out = []
    for i in range(SLOW_DRAWS):
        rng = np.random.default_rng(500 + i)
        arm = identify_arm(robot, log_of(robot, other, efforts(robot, None, other, rng), rng))
        loaded = log_of(robot, motion, efforts(robot, MC_PAYLOAD, motion, rng), rng)
        out.append((estimate_payload_dynamic(robot, loaded, arm_model=arm), MC_PAYLOAD))
    assert out[0][0].std_parts["arm model"] > 0
    assert BAND[0] < rms_score(out) < BAND[1]


def test_the_wrench_part_holds(robot):
    """A wrist sensor's wrench along a motion (noise, bias), the tool from an empty run."""
    motion = fourier_motion(robot, duration=8.0)
    out = []
    for i in range(SLOW_DRAWS):
        loaded = wrench_log(robot, MC_PAYLOAD, motion, seed=700 + 2 * i, effort=False)
        empty = wrench_log(robot, None, motion, seed=701 + 2 * i, effort=False)
        out.append((estimate_wrench_dynamic(robot, loaded, empty_log=empty), MC_PAYLOAD))
    assert BAND[0] < rms_score(out) < BAND[1]
