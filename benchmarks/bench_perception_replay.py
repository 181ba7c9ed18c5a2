"""Perception on recorded episode frames: this checkout's against a commit's, same frames.

    python benchmarks/bench_perception_replay.py BEFORE_COMMIT [--objects obj1,obj3]
        [--repeat 3] [--out benchmarks/results/perception_replay.json]

Records what the side view (``observe_held_rod``: full frames and the slip watch's strided
ones), and the top view (``detect_rod_top_down``) receive in real episodes (an accuracy trial
and a regrasp episode per object, ideal and realistic sensors) with their outputs, then runs
every call again in two fresh processes: this checkout's package and BEFORE_COMMIT's
(``git archive`` into a temporary folder). Reports CPU time per call (the best of
``--repeat``; one BLAS thread in both), the ratio before / after, and whether each side's
outputs (every field, every array) and refusals (error type and words) are the recorded
ones: ``identical`` counts equal to the bit, ``within_1e-6`` those whose every output is
within 1e-6 (SI units; pixel outputs in px) with the same refusal, ``max_abs_difference``
the largest move, ``max_deviation_by_output`` the largest move of each output (BEFORE's
outputs against this checkout's, which recorded them). ``calls`` lists every call: its
episode, index, kind, CPU ms before and after, and how far BEFORE's outputs are from this
checkout's.
"""

from __future__ import annotations

import os

os.environ.setdefault("MUJOCO_GL", "egl")

import argparse  # noqa: E402
import dataclasses  # noqa: E402
import json  # noqa: E402
import pickle  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
FUNCTIONS = {"side": "observe_held_rod", "top": "detect_rod_top_down"}


def record(folder: Path, objects: list[str]) -> None:
    """Run the episodes with the perception calls wrapped; one pickle per episode."""
    from comgrasp_pin.experiments.trials import accuracy_trial, make_tasks, regrasp_trial
    from comgrasp_pin.simulation import eyes

    calls: list[dict] = []

    def wrapped(kind: str, fn):
        def call(*args):
            args = list(args)
            if kind == "top" and callable(args[0]):  # the colour image, rendered if asked
                render, taken = args[0], []
                args[0] = lambda: taken.append(render()) or taken[0]
            try:
                result, error = fn(*args), None
            except Exception as exc:  # noqa: BLE001 - recorded, then raised again
                result, error = None, exc
            if kind == "top" and callable(args[0]):
                args[0] = taken[0] if taken else None
            calls.append({"kind": kind, "args": tuple(args), "result": result,
                          "error": None if error is None else (type(error).__name__, str(error))})  # fmt: skip
            if error is not None:
                raise error
            return result

        return call

    eyes.observe_held_rod = wrapped("side", eyes.observe_held_rod)
    eyes.detect_rod_top_down = wrapped("top", eyes.detect_rod_top_down)
    for sensors in ("ideal", "realistic"):
        for method, trial in (("trial", accuracy_trial), ("regrasp", regrasp_trial)):
            for task in make_tasks(objects, 1, 0, (method,)):
                calls.clear()
                trial({**task, "sensors": sensors})
                name = f"{sensors}_{method}_{task['object']}.pkl"
                (folder / name).write_bytes(pickle.dumps(list(calls)))


def _fields(x, path: str = ""):
    """(path, value) of every leaf of a perception output."""
    if dataclasses.is_dataclass(x):
        for f in dataclasses.fields(x):
            yield from _fields(getattr(x, f.name), f"{path}.{f.name}")
    elif isinstance(x, (tuple, list)):
        for i, v in enumerate(x):
            yield from _fields(v, f"{path}[{i}]")
    else:
        yield path, x


def deviations(a, b) -> dict[str, float]:
    """The largest absolute difference of each output (leaf path) between two outputs (inf:
    a different structure, shape, mask or None)."""
    fa, fb = list(_fields(a)), list(_fields(b))
    if [p for p, _ in fa] != [p for p, _ in fb]:
        return {"": float("inf")}
    out = {}
    for (path, x), (_, y) in zip(fa, fb, strict=True):
        if x is None or y is None:
            out[path] = 0.0 if x is y else float("inf")
            continue
        x, y = np.asarray(x), np.asarray(y)
        if x.shape != y.shape or (x.dtype == bool) != (y.dtype == bool):
            out[path] = float("inf")
        elif x.dtype == bool:
            out[path] = 0.0 if np.array_equal(x, y) else float("inf")
        else:
            same = (x == y) | (np.isnan(x) & np.isnan(y))
            out[path] = (
                0.0 if same.all() else float(np.max(np.abs(x[~same].astype(float) - y[~same])))
            )
    return out


def difference(a, b) -> float:
    """The largest absolute difference between two outputs (``deviations``' largest)."""
    return max(deviations(a, b).values(), default=0.0)


def time_frames(folder: Path, repeat: int) -> None:
    """Run every recorded call ``repeat`` times with the package on sys.path; write the
    CPU times and how far each output is from the recorded one to folder/times-<pid>."""
    from comgrasp_pin import perception

    rows = []
    for path in sorted(folder.glob("*.pkl")):
        for index, call in enumerate(pickle.loads(path.read_bytes())):
            fn = getattr(perception, FUNCTIONS[call["kind"]])
            best, out = float("inf"), None
            for _ in range(repeat):
                start = time.thread_time()
                try:
                    out = (fn(*call["args"]), None)
                except Exception as exc:  # noqa: BLE001 - compared with the recorded one
                    out = (None, (type(exc).__name__, str(exc)))
                best = min(best, time.thread_time() - start)
            same_error = (out[1] or ("",))[0] == (call["error"] or ("",))[0]
            fields = deviations(out[0], call["result"]) if same_error else {"": float("inf")}
            watch = call["kind"] == "side" and call["args"][1].shape != (480, 640)
            rows.append({"episode": path.stem, "call": index,
                         "kind": "side_watch" if watch else call["kind"], "ms": 1e3 * best,
                         "difference": max(fields.values(), default=0.0),
                         "same_words": out[1] == call["error"],
                         "fields": {k: v for k, v in fields.items() if v}})  # fmt: skip
    (folder / f"times-{os.getpid()}.json").write_text(json.dumps({"rows": rows, "package": str(
        Path(perception.__file__).parents[2])}))  # fmt: skip


def _run(folder: Path, package_root: Path, repeat: int) -> list[dict]:
    env = {**os.environ, "PYTHONPATH": str(package_root), "OPENBLAS_NUM_THREADS": "1",
           "OMP_NUM_THREADS": "1"}  # fmt: skip
    for old in folder.glob("times-*.json"):
        old.unlink()
    subprocess.run([sys.executable, __file__, "--time-frames", str(folder), "--repeat",
                    str(repeat)], env=env, check=True)  # fmt: skip
    (result,) = [json.loads(p.read_text()) for p in folder.glob("times-*.json")]
    assert Path(result["package"]).resolve() == package_root.resolve(), result["package"]
    return result["rows"]


def _summary(before: list[dict], after: list[dict]) -> dict:
    out = {}
    for kind in ("side", "side_watch", "top"):
        b = [r for r in before if r["kind"] == kind]
        a = [r for r in after if r["kind"] == kind]
        if not a:
            continue
        by_output: dict[str, float] = {}
        for r in b:
            for field, dev in r["fields"].items():
                by_output[field] = max(by_output.get(field, 0.0), dev)
        out[kind] = {
            "calls": len(a),
            "median_ms": {"before": float(np.median([r["ms"] for r in b])),
                          "after": float(np.median([r["ms"] for r in a]))},
            "total_s": {"before": sum(r["ms"] for r in b) / 1e3,
                        "after": sum(r["ms"] for r in a) / 1e3},
            "speedup_total": sum(r["ms"] for r in b) / max(sum(r["ms"] for r in a), 1e-9),
            "identical": {"before": sum(r["difference"] == 0 for r in b),
                          "after": sum(r["difference"] == 0 for r in a)},
            "within_1e-6": {"before": sum(r["difference"] <= 1e-6 for r in b),
                            "after": sum(r["difference"] <= 1e-6 for r in a)},
            "same_refusal_words": {"before": sum(r["same_words"] for r in b),
                                   "after": sum(r["same_words"] for r in a)},
            "max_abs_difference": max(max(r["difference"] for r in a),
                                      max(r["difference"] for r in b)),
            "max_deviation_by_output": dict(sorted(by_output.items())),
        }  # fmt: skip
    return out


def _calls(before: list[dict], after: list[dict]) -> list[dict]:
    """Every call: before and after CPU ms, BEFORE's deviation from this checkout's."""
    return [{"episode": a["episode"], "call": a["call"], "kind": a["kind"],
             "before_ms": round(b["ms"], 3), "after_ms": round(a["ms"], 3),
             "deviation": b["difference"]}
            for b, a in zip(before, after, strict=True)]  # fmt: skip


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("before", nargs="?", help="commit of the code to compare with")
    parser.add_argument("--objects", default="obj1,obj3")
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--out", default=str(ROOT / "benchmarks/results/perception_replay.json"))
    parser.add_argument("--time-frames", help=argparse.SUPPRESS)  # a worker's folder
    args = parser.parse_args()
    if args.time_frames:
        time_frames(Path(args.time_frames), args.repeat)
        return
    with tempfile.TemporaryDirectory() as tmp:
        frames, old = Path(tmp) / "frames", Path(tmp) / "before"
        frames.mkdir()
        old.mkdir()
        archive = subprocess.run(["git", "-C", str(ROOT), "archive", args.before, "comgrasp_pin"],
                                 check=True, capture_output=True).stdout  # fmt: skip
        subprocess.run(["tar", "-x", "-C", str(old)], input=archive, check=True)
        record(frames, args.objects.split(","))
        after = _run(frames, ROOT, args.repeat)
        before = _run(frames, old, args.repeat)
    result = {"before": args.before, "objects": args.objects, "repeat": args.repeat,
              "summary": _summary(before, after), "calls": _calls(before, after),
              "date": time.strftime("%Y-%m-%d %H:%M:%S UTC", time.gmtime()),
              "load_avg_1min": os.getloadavg()[0]}  # fmt: skip
    Path(args.out).write_text(json.dumps(result, indent=2) + "\n")
    print(json.dumps(result["summary"], indent=2))


if __name__ == "__main__":
    main()
