"""The empty run laid on the loaded one (robot_io.from_motion.alignment,
motion_signals.find_motion).

Synthetic runs: one smooth multi-sine motion (analytic positions and velocities, at rest at
both ends) played with still parts of different lengths before and after it, sampled at
100 Hz with jitter in the sample times and noise; the true shift between the runs is known
to a fraction of a sample. Then the real UR10e pair (the same motion loaded and empty).
"""

import json
import re
from pathlib import Path

import numpy as np
import pytest

from comgrasp_pin.errors import MotionLogError
from comgrasp_pin.robot import RobotModel
from comgrasp_pin.robot_io import JointLog
from comgrasp_pin.robot_io.from_motion.alignment import MAX_GAP_RAD, align_empty
from comgrasp_pin.robot_io.from_motion.motion_signals import (
    EDGE_S,
    MOTION_MARGIN_S,
    MOTION_SPEED,
    filtered_signals,
    find_motion,
    motion_samples,
)

RATE = 100.0
MOTION_S = 12.0
Q0 = np.array([0.0, -1.6, 1.6, -1.57, -1.57, 0.0])
UR = Path(__file__).resolve().parents[2] / "shared" / "realdata" / "ur10e_rtde"
UR_GAINS = np.array([10.0, 10.6956, 8.4566, 9.0029, 9.48, 10.1232])


@pytest.fixture(scope="module")
def robot():
    return RobotModel.ur5()


def positions(tau, seed=0, amplitude=0.5):
    """(len(tau), 6) a windowed four-harmonic motion over [0, MOTION_S], still outside."""
    rng = np.random.default_rng(seed)
    inside = (tau >= 0) & (tau <= MOTION_S)
    window = np.where(inside, np.sin(np.pi * tau / MOTION_S) ** 2, 0.0)
    w = 2 * np.pi / (MOTION_S / 2)
    q = np.tile(Q0, (len(tau), 1))
    for j in range(6):
        for h in range(1, 5):
            a, b = rng.normal(0, amplitude / h / 2, 2)
            q[:, j] += window * (a * np.sin(h * w * tau) + b * (np.cos(h * w * tau) - 1))
    return q


def run(robot, still_before, still_after, seed=0, motion_seed=0, cut_end_s=0.0):
    """(log, the motion's start in the log's time): jittered times, noisy readings."""
    rng = np.random.default_rng(seed)
    n = int((still_before + MOTION_S + still_after - cut_end_s) * RATE)
    raw = np.arange(n) / RATE + rng.uniform(0.0, 0.004, n)  # 0-4 ms late, in order
    tau = raw - still_before
    eps = 1e-5
    qd = (positions(tau + eps, motion_seed) - positions(tau - eps, motion_seed)) / (2 * eps)
    q = positions(tau, motion_seed) + 2e-5 * rng.standard_normal((n, 6))
    log = JointLog(
        raw - raw[0], tuple(robot.joint_names), q, 0.05 * rng.standard_normal((n, 6)),
        "synthetic", qd + 1e-3 * rng.standard_normal((n, 6)),
    )  # fmt: skip
    return log, still_before - raw[0]


def test_shift_found_within_a_sample_despite_different_still_parts(robot):
    loaded, start_l = run(robot, 2.0, 1.0, seed=1)
    empty, start_e = run(robot, 0.6, 2.5, seed=2)
    S = motion_samples(robot, loaded, crop=True)
    E, alignment = align_empty(robot, S, empty)
    truth = start_e - start_l
    assert abs(alignment.shift_s - truth) < 1 / RATE
    assert alignment.rms_gap_rad < 1e-3 and alignment.method == "found"
    np.testing.assert_allclose(E.t, S.t + alignment.shift_s)
    np.testing.assert_allclose(E.q, S.q, atol=5e-3)
    assert alignment.loaded_motion_s == (S.t[0], S.t[-1])
    json.dumps(alignment.as_dict())
    # the loaded run's 2 s still start, uncropped, is more than the empty run has: refused
    # with the part it misses and the window both runs cover, not with the runs' lengths
    with pytest.raises(MotionLogError, match=r"misses the start of the loaded motion: its "
                       r"first \d+\.\d+ s .*--window"):  # fmt: skip
        align_empty(robot, motion_samples(robot, loaded), empty)


def test_motion_found_within_two_samples(robot):
    loaded, start = run(robot, 2.0, 1.0, seed=3)
    t0, t1 = find_motion(filtered_signals(robot, loaded))
    tau = np.arange(-1.0, MOTION_S + 1.0, 1e-3)
    eps = 1e-5
    speed = np.abs(positions(tau + eps) - positions(tau - eps)).max(axis=1) / (2 * eps)
    moving = tau[speed > MOTION_SPEED]
    assert abs(t0 - (start + moving[0] - MOTION_MARGIN_S)) < 2 / RATE
    assert abs(t1 - (start + moving[-1] + MOTION_MARGIN_S)) < 2 / RATE
    # cropped for an empty run's subtraction: EDGE_S inside the motion at each end (the
    # still arm's stuck friction, spread by the filter, stays out), thinned to a 0.1 s grid
    first, last = start + moving[0] + EDGE_S, start + moving[-1] - EDGE_S
    S = motion_samples(robot, loaded, crop=True)
    tol = 2 / RATE
    assert first - tol <= S.t[0] < first + 0.2 and last - 0.2 < S.t[-1] <= last + tol


def test_nothing_moving_is_refused_with_the_speeds(robot):
    still, _ = run(robot, 2.0, 1.0, seed=4)
    full = filtered_signals(robot, still)
    with pytest.raises(MotionLogError, match=r"nothing moves .* reaches \d\.\d+ rad/s"):
        find_motion(full, speed=50.0)


def test_empty_run_missing_the_motions_end_names_the_end(robot):
    loaded, start_l = run(robot, 1.0, 1.0, seed=5)
    empty, start_e = run(robot, 1.0, 1.0, seed=6, cut_end_s=4.0)  # the motion's last 3 s
    S = motion_samples(robot, loaded, crop=True)
    with pytest.raises(MotionLogError) as error:
        align_empty(robot, S, empty)
    message = str(error.value)
    found = re.search(r"misses the end of the loaded motion: its last (\d+\.\d+) s", message)
    assert found, message
    missing = S.t[-1] + (start_e - start_l) - empty.time[-1]
    assert abs(float(found.group(1)) - missing) < 0.02
    assert "start" not in message.split("Record")[0]
    assert "does not cover" not in message and not re.search(r"empty run \(\d", message)
    assert f"--window {S.t[0]:.2f}:" in message


def test_a_different_motion_is_refused_with_the_gap(robot):
    loaded, _ = run(robot, 1.0, 1.0, seed=7)
    other, _ = run(robot, 1.0, 1.0, seed=8, motion_seed=1)
    S = motion_samples(robot, loaded, crop=True)
    with pytest.raises(MotionLogError, match=r"not the same motion") as error:
        align_empty(robot, S, other)
    gap = float(re.search(r"(\d+\.\d+) rad apart", str(error.value)).group(1))
    assert gap > MAX_GAP_RAD


def _ur_log(robot, name):
    data = np.loadtxt(UR / name, skiprows=1)
    t = data[:, 0] - data[0, 0]
    current, qd = data[:, 13:19], data[:, 7:13]
    return JointLog(t, tuple(robot.joint_names), data[:, 1:7], current * UR_GAINS, name, qd)


@pytest.mark.skipif(not UR.is_dir(), reason=f"the real UR10e pair is not in {UR.parent}")
def test_real_ur10e_pair_aligned():
    from comgrasp_pin.robot_io import load_robot

    robot = load_robot(UR / "ur10e.urdf", "tool0", gravity_base=(0, 0, -9.81))
    loaded = _ur_log(robot, "excitation_loaded_2805g.csv")
    empty = _ur_log(robot, "excitation_empty.csv")
    span_l = find_motion(filtered_signals(robot, loaded))
    span_e = find_motion(filtered_signals(robot, empty))
    # each motion lasts the same, found 1.18 s later in the loaded log
    assert abs((span_l[1] - span_l[0]) - (span_e[1] - span_e[0])) < 0.05
    S = motion_samples(robot, loaded, crop=True)
    E, alignment = align_empty(robot, S, empty)
    assert alignment.rms_gap_rad < 0.01
    assert abs(alignment.shift_s - (span_e[0] - span_l[0])) < 0.05
    assert abs(alignment.shift_s + 1.18) < 0.02  # measured: -1.180 s, rms 0.35 mrad
    with pytest.raises(MotionLogError, match="misses the start of the loaded motion"):
        align_empty(robot, motion_samples(robot, loaded), empty)  # its still start, uncropped
