"""`comgrasp estimate` on a 10-minute 500 Hz ROS 2 bag (300 000 JointState messages).

    python benchmarks/bench_estimate_log.py [--minutes 10] [--out benchmarks/results/estimate_log.json]

The bag (sqlite3 and mcap, written by rosbags) holds the Panda's 7 arm joints and 2 finger
joints: 3 poses held empty, then the same 3 held with a 0.8 kg payload, efforts from
Pinocchio RNEA with the payload body plus 0.05 N m noise per sample; 1 s windows mid-hold.
Timed: the whole command in-process (``comgrasp_pin.cli.main``, parsing, reading, windows,
estimate, RESULT.json and exports; with windows given only the messages near them are
decoded), the full bag reading alone (``read_bag``, every message decoded), the command as a
subprocess (with Python start-up and imports), and ``--auto`` (which reads every message to
find the static windows). Target: the command under 10 s.
"""

from __future__ import annotations

import argparse
import json
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import pinocchio as pin

from comgrasp_pin._paths import example_robot_urdf
from comgrasp_pin.cli import main
from comgrasp_pin.robot_io import JointLog, load_robot, write_bag
from comgrasp_pin.robot_io.log_files import read_bag

URDF = example_robot_urdf("panda_description/urdf/panda.urdf")
EE = "panda_hand_tcp"
Q = np.array([[0.0, -0.3, 0.0, -2.2, 0.0, 2.0, 0.8], [0.5, -0.6, 0.3, -1.8, 1.2, 1.2, -0.6],
              [-0.4, 0.2, -0.2, -2.4, -1.0, 2.6, 1.5]])  # fmt: skip
MASS, COM = 0.8, np.array([0.02, -0.01, 0.05])
RATE, NOISE, MOVE_S = 500.0, 0.05, 2.0


def _static_torques(robot, q, loaded):
    model = pin.Model(robot.model)
    if loaded:
        frame = model.frames[robot.ee_frame_id]
        body = pin.Inertia(MASS, COM, np.diag([2e-3, 3e-3, 4e-3]))
        model.appendBodyToJoint(frame.parentJoint, body, frame.placement)
    z = np.zeros(robot.nq)
    return pin.rnea(model, model.createData(), q, z, z)


def make_log(robot, minutes: float, seed: int = 0):
    """A JointLog of ``minutes`` at RATE, its (before, after) windows and the grasp time."""
    rng = np.random.default_rng(seed)
    hold = minutes * 60.0 / 6 - MOVE_S
    qs, taus, before, after, t, grasp = [], [], [], [], 0.0, 0.0
    prev_q, prev_tau = Q[0], _static_torques(robot, Q[0], False)
    for loaded in (False, True):
        for q in Q:
            tau = _static_torques(robot, q, loaded)
            s = np.linspace(0, 1, int(MOVE_S * RATE), endpoint=False)[:, None]
            qs += [prev_q + s * (q - prev_q), np.tile(q, (int(hold * RATE), 1))]
            taus += [prev_tau + s * (tau - prev_tau), np.tile(tau, (int(hold * RATE), 1))]
            mid = t + MOVE_S + hold / 2
            (after if loaded else before).append((mid - 0.5, mid + 0.5))
            t += MOVE_S + hold
            prev_q, prev_tau = q, tau
        grasp = grasp or t + 0.5  # inside the first loaded move
    q, tau = np.concatenate(qs), np.concatenate(taus)
    time_s = np.arange(len(q)) / RATE
    log = JointLog(time_s, tuple(robot.joint_names), q + 1e-5 * rng.standard_normal(q.shape),
                   tau + NOISE * rng.standard_normal(q.shape), "bench")  # fmt: skip
    return log, before, after, grasp


def _windows(ws):
    return ",".join(f"{a:.3f}:{b:.3f}" for a, b in ws)


def run(minutes: float) -> dict:
    robot = load_robot(URDF, EE)
    log, before, after, grasp = make_log(robot, minutes)
    out: dict = {"messages": len(log.time), "minutes": minutes, "rate_hz": RATE,
                 "python": platform.python_version(), "machine": platform.machine()}  # fmt: skip
    with tempfile.TemporaryDirectory() as tmp:
        for storage in ("sqlite3", "mcap"):
            t0 = time.perf_counter()
            bag = write_bag(log, Path(tmp) / storage, storage,
                            extra_joints={"panda_finger_joint1": 0.02, "panda_finger_joint2": 0.02})  # fmt: skip
            write_s = time.perf_counter() - t0
            t0 = time.perf_counter()
            read_bag(bag, robot.joint_names)
            read_s = time.perf_counter() - t0
            args = ["estimate", "--urdf", str(URDF), "--ee-frame", EE, "--bag", str(bag),
                    "--before", _windows(before), "--after", _windows(after),
                    "--out", str(Path(tmp) / "RESULT.json"), "--flange-frame", "panda_link8",
                    "--export-franka", str(Path(tmp) / "franka.json")]  # fmt: skip
            t0 = time.perf_counter()
            assert main(args) == 0
            estimate_s = time.perf_counter() - t0
            auto = [*args[:7], "--auto", "--grasp-time", f"{grasp}", *args[11:13]]
            t0 = time.perf_counter()
            assert main(auto) == 0
            auto_s = time.perf_counter() - t0
            t0 = time.perf_counter()
            subprocess.run([sys.executable, "-m", "comgrasp_pin.cli", *args], check=True,
                           capture_output=True)  # fmt: skip
            subprocess_s = time.perf_counter() - t0
            result = json.loads((Path(tmp) / "RESULT.json").read_text())
            out[storage] = {
                "write_s": round(write_s, 3),
                "read_bag_s": round(read_s, 3),
                "estimate_command_s": round(estimate_s, 3),
                "estimate_subprocess_s": round(subprocess_s, 3),
                "estimate_auto_command_s": round(auto_s, 3),
                "command_over_read": round(estimate_s / read_s, 3),
                "read_us_per_message": round(1e6 * read_s / len(log.time), 2),
                "mass_kg": result["mass_kg"],
                "mass_std_kg": float(np.sqrt(result["cov"][0][0])),
                "target_command_under_10_s": estimate_s < 10.0,
            }
            print(storage, out[storage])
    return out


def _main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--minutes", type=float, default=10.0, help="log length (%(default)s)")
    parser.add_argument("--out", default="benchmarks/results/estimate_log.json",
                        help="result JSON (%(default)s)")  # fmt: skip
    args = parser.parse_args()
    result = run(args.minutes)
    Path(args.out).write_text(json.dumps(result, indent=2) + "\n")
    print(f"wrote {args.out}")


if __name__ == "__main__":
    _main()
