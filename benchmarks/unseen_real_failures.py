"""The top view on MuJoCo frames that reproduce real cameras' failure modes (issue 34).

    python benchmarks/unseen_real_failures.py [--quick] [--seed 0] [--draws 1]
        [--out benchmarks/results/unseen_real_failures.json]

Renders the frames of ``unseen.real_failures`` (benchmarks/unseen/): the colour image
shifted against the depth by 5-30 px, a tool whose handle is under 1 cm high, a
structured-light camera's depth noise and holes, textured and coloured tables. Runs
``detect_rod_top_down`` on each and counts right / refused / wrong per failure mode, wrong
as issue 34 has it (a measurement more than 20 % off in length, 10 deg in yaw or 3 cm in
centre); each frame also without its colour image (``depth_alone``). Colour-shift,
thin-handle and table frames run on the clean render and on a structured-light camera's
depth (the top view looks at the colour only where such a depth fails). Writes every
frame's mode, parameter, outcome and the refusal's message or the errors. ``--quick``:
fewer frames (~30 s). ``--draws N``: each frame with a structured-light camera's depth
under N draws of its noise (the first the one a single run draws): an answer that holds
for one draw may not for the next. Each answer is also asked in the fitted table's frame
(``differing_in_table_frame``) and, in the world frame, with the pick area moved by 3 cm in
x and y where no object enters or leaves (``unseen.moved_areas``; ``moved_areas`` counts
them, ``differing_for_moved_areas`` the frames whose answer changed in one): issue 44's one
answer per scene.
"""

from __future__ import annotations

import os

os.environ.setdefault("MUJOCO_GL", "egl")

import argparse  # noqa: E402
import json  # noqa: E402
import time  # noqa: E402
from collections import Counter  # noqa: E402
from pathlib import Path  # noqa: E402

from unseen import real_failures as rf  # noqa: E402  (benchmarks/unseen/, beside this script)

ROOT = Path(__file__).resolve().parents[1]
OUTCOMES = ("right", "refused", "wrong")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="fewer frames")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--draws", type=int, default=1, help="noise draws per noisy frame")
    parser.add_argument("--out", default=str(ROOT / "benchmarks/results/unseen_real_failures.json"))
    args = parser.parse_args()
    start = time.time()
    frames = rf.frames(args.seed, args.quick)
    renders = rf._Renders()
    rows, counts = [], {}
    for frame in frames:
        for draw in range(args.draws if frame.depth != "clean" else 1):
            judged = rf.run_frame(frame, renders, rf.noise_seed(frame, args.seed, draw))
            rows.append({"mode": frame.mode, "parameter": frame.parameter, "draw": draw,
                         **judged})  # fmt: skip
            counts.setdefault(frame.mode, Counter())[judged["outcome"]] += 1
            print(frame.mode, frame.parameter, draw, judged, flush=True)
    by_mode = {m: {o: c[o] for o in OUTCOMES} for m, c in counts.items()}
    total = Counter(r["outcome"] for r in rows)
    alone = Counter(r["depth_alone"]["outcome"] for r in rows)
    differ = sum(not v for r in rows for v in r["same_in_table_frame"].values())
    moved = sum(not v for r in rows for v in r["same_for_moved_areas"].values())
    result = {
        "seed": args.seed,
        "quick": args.quick,
        "draws": args.draws,
        "frames": len(rows),
        "total": {o: total[o] for o in OUTCOMES},
        "total_depth_alone": {o: alone[o] for o in OUTCOMES},
        "differing_in_table_frame": differ,
        "moved_areas": sum(r["moved_areas"] for r in rows),
        "differing_for_moved_areas": moved,
        "by_mode": by_mode,
        "wrong_bounds": {
            "length_rel": rf.WRONG_LENGTH,
            "yaw_deg": rf.WRONG_YAW_DEG,
            "centre_m": rf.WRONG_CENTRE,
        },  # fmt: skip
        "rows": rows,
        "wall_s": round(time.time() - start, 1),
        "date": time.strftime("%Y-%m-%d %H:%M:%S UTC", time.gmtime()),
    }
    Path(args.out).write_text(json.dumps(result, indent=1) + "\n")
    shown = ("total", "total_depth_alone", "differing_in_table_frame", "moved_areas",
             "differing_for_moved_areas", "by_mode", "wall_s")
    print(json.dumps({k: result[k] for k in shown}, indent=1))


if __name__ == "__main__":
    main()
