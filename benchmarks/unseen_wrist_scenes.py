"""The wrist camera's side view on held-rod scenes the project never built: right, refused, wrong.

    python benchmarks/unseen_wrist_scenes.py [--family NAME]
        [--out benchmarks/results/unseen_wrist_scenes.json]

Renders every scene of ``unseen.wrist_families`` (benchmarks/unseen/) (rods of other
sections, thicknesses and colours in the jaws, other tilts, a turn out of the jaws' plane,
other light and tables, the gripper low over the table, a box, a cable or a second rod
behind, below or beside the rod) with MuJoCo at the project's measurement pose, runs
``observe_held_rod`` as the robot does (``eyes.look_from_side``'s inputs) on the clean render
and on the realistic preset's depth and calibration errors, and judges each answer against
the rod as built: right (tilt within 1 deg, axis and grasp position within 3 mm), refused
(a PerceptionError) or wrong. Writes the counts per family and every view's outcome.
"""

from __future__ import annotations

import os

os.environ.setdefault("MUJOCO_GL", "egl")

import argparse  # noqa: E402
import json  # noqa: E402
import time  # noqa: E402
from collections import Counter  # noqa: E402
from pathlib import Path  # noqa: E402

from unseen import wrist_families as wf  # noqa: E402  (benchmarks/unseen/, beside this script)

from comgrasp_pin.robot import RobotModel  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
OUTCOMES = ("right", "refused", "wrong")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--family", help="only this family")
    parser.add_argument("--out", default=str(ROOT / "benchmarks/results/unseen_wrist_scenes.json"))
    args = parser.parse_args()
    start = time.time()
    robot = RobotModel.ur5()
    scenes = [s for s in wf.families() if args.family in (None, s.family)]
    rows, counts = [], {}
    for k, scene in enumerate(scenes):
        for depth, judged in wf.side_view_outcome(scene, robot, noise_seed=k).items():
            rows.append({"family": scene.family, "scene": scene.name, "depth": depth,
                         "should_measure": scene.should_measure, **judged})  # fmt: skip
            family = counts.setdefault(scene.family, {d: Counter() for d in wf.DEPTHS})
            family[depth][judged["outcome"]] += 1
            if judged["outcome"] != "right":
                print(scene.family, scene.name, depth, judged, flush=True)
    summary = {f: {d: {o: c[o] for o in OUTCOMES} for d, c in v.items()}
               for f, v in counts.items()}  # fmt: skip
    total = Counter(r["outcome"] for r in rows)
    measured = [r for r in rows if r["should_measure"]]
    result = {"scenes": len(scenes), "views": len(rows),
              "total": {o: total[o] for o in OUTCOMES},
              "should_measure": {o: sum(r["outcome"] == o for r in measured) for o in OUTCOMES},
              "by_family": summary,
              "judge": {"tilt_deg": wf.TILT_BOUND_DEG, "position_m": wf.POSITION_BOUND},
              "rows": rows, "wall_s": round(time.time() - start, 1),
              "date": time.strftime("%Y-%m-%d %H:%M:%S UTC", time.gmtime())}  # fmt: skip
    Path(args.out).write_text(json.dumps(result, indent=1) + "\n")
    keys = ("total", "should_measure", "by_family", "wall_s")
    print(json.dumps({k: result[k] for k in keys}, indent=1))


if __name__ == "__main__":
    main()
