"""The top view on scenes the project never built: measured right, refused, or wrong.

    python benchmarks/unseen_scenes.py [--family NAME] [--seed 0]
        [--out benchmarks/results/unseen_scenes.json]

Renders every scene of ``unseen.families`` (benchmarks/unseen/) (another table colour or
texture, the camera higher, lower or tilted, other light, other rods, clutter, a second rod
touching, crossing or beside the first) with MuJoCo, runs ``detect_rod_top_down`` on the
clean render and on the realistic preset's noisy depth, and judges each answer against the
scene as built: right (within 3 mm (realistic depth: the project's own 4.5 mm), 1 deg and 8 mm
in length of a rod of the scene), refused
(a PerceptionError) or wrong. Writes the counts per family and every scene's outcome, and
the perception thresholds it ran with.
"""

from __future__ import annotations

import os

os.environ.setdefault("MUJOCO_GL", "egl")

import argparse  # noqa: E402
import json  # noqa: E402
import time  # noqa: E402
from collections import Counter  # noqa: E402
from pathlib import Path  # noqa: E402

from unseen import families as uf  # noqa: E402  (benchmarks/unseen/, beside this script)

from comgrasp_pin.perception.top_view import rod_alongside, rod_shape  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]


def thresholds() -> dict:
    """The one-rod checks' tuning numbers and the judge's bounds, as run."""
    checks = {m.__name__.rsplit(".", 1)[1]: {n: getattr(m, n) for n in dir(m)
                                             if n.isupper() and not n.startswith("_")}
              for m in (rod_shape, rod_alongside)}  # fmt: skip
    bounds = {"centre_m": uf.CENTRE_BOUND, "yaw_deg": uf.YAW_BOUND_DEG,
              "length_m": uf.LENGTH_BOUND,
              "realistic_centre_m": uf.REALISTIC_CENTRE_BOUND}  # fmt: skip
    return {**checks, "judge": bounds}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--family", help="only this family")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--out", default=str(ROOT / "benchmarks/results/unseen_scenes.json"))
    args = parser.parse_args()
    start = time.time()
    scenes = [s for s in uf.families(args.seed) if args.family in (None, s.family)]
    rows, counts = [], {}
    for k, scene in enumerate(scenes):
        outcomes = uf.top_view_outcome(scene, noise_seed=args.seed * 1000 + k)
        for depth, judged in outcomes.items():
            rows.append({"family": scene.family, "scene": scene.name, "depth": depth,
                         "should_measure": scene.should_measure, **judged})  # fmt: skip
            family = counts.setdefault(scene.family, {d: Counter() for d in uf.DEPTHS})
            family[depth][judged["outcome"]] += 1
            if judged["outcome"] != "right":
                print(scene.family, scene.name, depth, judged, flush=True)
    summary = {f: {d: {o: c[o] for o in ("right", "refused", "wrong")} for d, c in v.items()}
               for f, v in counts.items()}  # fmt: skip
    total = Counter(r["outcome"] for r in rows)
    result = {"seed": args.seed, "scenes": len(scenes), "views": len(rows),
              "total": {o: total[o] for o in ("right", "refused", "wrong")},
              "by_family": summary, "thresholds": thresholds(), "rows": rows,
              "wall_s": round(time.time() - start, 1),
              "date": time.strftime("%Y-%m-%d %H:%M:%S UTC", time.gmtime())}  # fmt: skip
    Path(args.out).write_text(json.dumps(result, indent=1) + "\n")
    print(json.dumps({k: result[k] for k in ("total", "by_family", "wall_s")}, indent=1))


if __name__ == "__main__":
    main()
