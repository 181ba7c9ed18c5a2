"""The excitation motion's condition number against random motions, UR5 and Panda (issue 26).

    python benchmarks/excitation.py [--duration 20] [--out benchmarks/results/excitation.json]

For each arm: ``plan_excitation`` with the default settings (its planning time, on one core
of a shared machine), and the median of 20 random rest-to-rest Fourier motions of the same
length, start, family and limits (each joint scaled to its tightest limit), free of collision
and of the floor (``random_condition_numbers``). Condition numbers of the stacked payload
regressor, columns scaled by a 1 kg payload 0.1 m out (``parameter_scale``), and in SI
units. Target (issue 26): planned at least 3x better than the random median.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import os
import time
from pathlib import Path

import numpy as np
from excitation_baseline import random_condition_numbers  # benchmarks/, beside this script

from comgrasp_pin._paths import example_robot_urdf, urdf_path
from comgrasp_pin.planning.excitation import (
    ExcitationSettings,
    plan_excitation,
)
from comgrasp_pin.robot import RobotModel

ARMS = {
    "ur5": (urdf_path("ur5_gripper.urdf"), "eelink"),
    "panda": (example_robot_urdf("panda_description/urdf/panda.urdf"), "panda_hand_tcp"),
}


def run(name: str, duration_s: float, seed: int) -> dict:
    urdf, ee = ARMS[name]
    robot = RobotModel.from_urdf(urdf, ee)
    t0 = time.perf_counter()
    motion = plan_excitation(robot, duration_s, seed=seed)
    plan_s = time.perf_counter() - t0
    t0 = time.perf_counter()
    random = random_condition_numbers(robot, duration_s, count=20, seed=seed + 1)
    random_s = time.perf_counter() - t0
    median = float(np.median(random))
    row = {
        "urdf": str(urdf), "ee_frame": ee, "duration_s": duration_s,
        "start_rad": motion.series.q0.tolist(),
        "planned_condition_number": motion.condition_number,
        "planned_condition_number_si": motion.condition_number_si,
        "random_median_condition_number": median,
        "random_condition_numbers": random.tolist(),
        "ratio_random_median_to_planned": median / motion.condition_number,
        "target_ratio": 3.0,
        "plan_time_s": plan_s, "random_time_s": random_s,
        "solver_status": list(motion.solver_status),
        "peak_velocity_share": motion.peak_velocity_share.tolist(),
        "peak_acceleration_share": motion.peak_acceleration_share.tolist(),
        "min_height_m": motion.min_height_m,
    }  # fmt: skip
    print(f"{name}: planned {motion.condition_number:.1f} ({plan_s:.1f} s), random median "
          f"{median:.1f}, ratio {row['ratio_random_median_to_planned']:.2f}", flush=True)  # fmt: skip
    return row


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=20.0)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--arms", default="ur5,panda")
    parser.add_argument("--out", default="benchmarks/results/excitation.json")
    args = parser.parse_args()
    results = {
        "settings": dataclasses.asdict(ExcitationSettings()),
        "column_scale": "1 kg payload, 0.1 m: (m, m L x3, m L^2 x6)",
        "load_average": os.getloadavg(),
        "arms": {name: run(name, args.duration, args.seed) for name in args.arms.split(",")},
    }
    Path(args.out).write_text(json.dumps(results, indent=2) + "\n")
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
