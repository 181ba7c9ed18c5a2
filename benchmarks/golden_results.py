"""Golden results: every number the command line and the benchmarks write, kept for a refactor.

A refactor must not change a single number: run this once against the code before it and
once after, then ``benchmarks/compare_results.py BEFORE AFTER`` (every number within 1e-12
relative, every exit status the same, the payload files' numbers the same). The same command
lines run against the code in ``--code`` (on ``PYTHONPATH``, ``python -m comgrasp_pin.cli``),
each in its own folder of ``--out`` holding RESULT.json and the payload files it wrote,
``cmd.txt``, ``stdout.txt``, ``stderr.txt`` and ``rc.txt`` (a run that fails today is kept:
its status is a golden too):

- the README's UR10e steps on the real recording (``../shared/realdata``, read where it lies,
  never copied): ``calibrate-gains``, ``identify-arm``, ``estimate --dynamic`` with the arm
  model, with the empty run, with the URDF's nominal model; the real Panda log, nominal model;
- synthetic UR5 logs (Pinocchio's RNEA, fixed seeds) in ``--inputs``, written once if missing
  and then reused: static joint torques (windows, ``--auto``, IPOPT), the wrist sensor at rest
  (``--auto``, ``--windows``, drift, ``--keep-tool``/``--tool``, nothing held), before/after
  pairs with the wrench and the efforts, a motion's wrench and joint torques;
- ``benchmarks/real_logs.py``, ``wrench_static.py --quick``, ``wrench_dynamic.py --seeds 4``
  (``bench/``) and ``comgrasp reproduce --quick --workers 2`` (``reproduce_quick/``; its rows
  are checked with ``benchmarks/compare_runs.py``).

    python benchmarks/golden_results.py --code ../golden_wt --inputs ../golden/inputs \
        --out ../golden/before
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import time
from importlib import metadata
from pathlib import Path

import numpy as np

REALDATA = Path(__file__).resolve().parents[2] / "shared" / "realdata"
UR10E_GAINS = "10.0,10.6956,8.4566,9.0029,9.48,10.1232"
RATE, HOLD, MOVE = 200.0, 2.0, 1.0  # static logs: Hz, s still at each pose, s between poses
POSES = np.array([[0.0, -1.6, 1.6, -1.57, -1.57, 0.0], [0.4, -1.2, 1.2, -0.4, 0.8, 1.0],
                  [-0.5, -1.9, 1.5, -2.5, -0.6, -1.2], [0.2, -1.4, 1.0, -1.0, 0.3, 2.0]])  # fmt: skip
BIAS = np.array([1.5, -2.0, 3.0, 0.1, -0.05, 0.2])  # the wrist sensor's offsets (N, N m)
WRIST_3 = (0.1879, np.zeros(3), np.diag([0.0171364731454, 0.0171364731454, 0.033822]))
SENSOR, EE = "ft_sensor", "eelink"
THREADS = {k: "1" for k in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")}


# ------------------------------------------------------------------ inputs (numpy + Pinocchio)


def _arm(urdf: Path):
    """(model, id of the locked joint at the sensor): the UR5, fingers locked, the tool moved
    onto a joint of its own at the sensor frame (what it passes is the sensor's wrench)."""
    import pinocchio as pin

    full = pin.buildModelFromUrdf(str(urdf))
    lock = [j for j in range(1, full.njoints) if full.names[j].startswith("finger")]
    model = pin.buildReducedModel(full, lock, pin.neutral(full))
    s = model.frames[model.getFrameId(SENSOR)]
    wrist = pin.Inertia(*WRIST_3)
    tool = pin.Inertia.FromDynamicParameters(
        model.inertias[s.parentJoint].toDynamicParameters() - wrist.toDynamicParameters()
    )
    model.inertias[s.parentJoint] = wrist
    jid = model.addJoint(s.parentJoint, pin.JointModelRZ(), s.placement, "sensor_lock")
    model.appendBodyToJoint(jid, s.placement.actInv(tool), pin.SE3.Identity())
    return model, jid


def _simulate(urdf: Path, motion, payload, held, seed: int, effort: bool = True) -> np.ndarray:
    """Columns time, q, tau, wrench along ``motion`` = (t, q, qd, qdd); ``payload`` (mass, CoM
    in the ee frame, 3x3 inertia about the CoM) is held where ``held`` is true."""
    import pinocchio as pin

    t, q, qd, qdd = motion
    model, jid = _arm(urdf)
    s = model.frames[model.getFrameId(SENSOR)]
    ee = model.frames[model.getFrameId(EE)]
    body = s.placement.actInv(ee.placement).act(pin.Inertia(*payload))
    loaded = pin.Model(model)
    loaded.appendBodyToJoint(jid, body, pin.SE3.Identity())
    rng = np.random.default_rng(seed)
    tau, wrench, z = np.empty_like(q), np.empty((len(t), 6)), np.zeros(1)
    datas = {True: (loaded, loaded.createData()), False: (model, model.createData())}
    for i, h in enumerate(held):
        m, data = datas[bool(h)]
        tau[i] = pin.rnea(m, data, np.r_[q[i], z], np.r_[qd[i], z], np.r_[qdd[i], z])[:6]
        wrench[i] = -data.f[jid].vector
    wrench += BIAS + rng.standard_normal(wrench.shape) * np.r_[[0.1] * 3, [0.005] * 3]
    tau += 0.3 * np.tanh(qd / 0.01) + 0.5 * qd + 0.2 + 0.05 * rng.standard_normal(tau.shape)
    q_read = q + 1e-5 * rng.standard_normal(q.shape)
    return np.column_stack([t, q_read, *([tau] if effort else []), wrench])


def _write(path: Path, columns: np.ndarray, effort: bool = True) -> None:
    """The CSV the project reads: time, J.position, J.effort per joint, force_x..torque_z."""
    joints = ["shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint", "wrist_1_joint",
              "wrist_2_joint", "wrist_3_joint"]  # fmt: skip
    fields = ("position", "effort") if effort else ("position",)
    head = ["time"] + [f"{j}.{f}" for f in fields for j in joints]
    head += [f"{k}_{a}" for k in ("force", "torque") for a in "xyz"]
    np.savetxt(path, columns, fmt="%.17g", delimiter=",", header=",".join(head), comments="")


def _still_poses(poses: np.ndarray, passes: int = 1):
    """A motion at rest HOLD s at each pose (``passes`` times over), smooth moves between."""
    n_hold, n_move = int(HOLD * RATE), int(MOVE * RATE)
    u = np.linspace(0.0, 1.0, n_move, endpoint=False)
    s = 3 * u**2 - 2 * u**3
    q = []
    seq = np.vstack([poses] * passes)
    for i, p in enumerate(seq):
        q += [np.tile(p, (n_hold, 1))]
        if i + 1 < len(seq):
            q += [p + s[:, None] * (seq[i + 1] - p)]
    q = np.vstack(q)
    t = np.arange(len(q)) / RATE
    qd = np.gradient(q, t, axis=0)
    return t, q, qd, np.gradient(qd, t, axis=0)


def _windows(first: int, count: int) -> str:
    """The still windows of poses first..first+count-1 of a _still_poses motion."""
    starts = [(HOLD + MOVE) * i for i in range(first, first + count)]
    return ",".join(f"{a + 0.3:.2f}:{a + HOLD - 0.3:.2f}" for a in starts)


def _fourier(duration: float = 16.0, rate: float = 250.0, seed: int = 0):
    """A smooth excitation at rest at both ends, four windowed harmonics per joint."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, duration, 1 / rate)
    w, window = 4 * np.pi / duration, np.sin(np.pi * t / duration) ** 2
    q = np.tile(POSES[0], (len(t), 1))
    for j in range(6):
        for h in range(1, 5):
            a, b = rng.normal(0, 0.25 / h, 2)
            q[:, j] += window * (a * np.sin(h * w * t) + b * (np.cos(h * w * t) - 1))
    qd = np.gradient(q, t, axis=0)
    return t, q, qd, np.gradient(qd, t, axis=0)


def make_inputs(code: Path, inputs: Path) -> None:
    """Write the synthetic logs (and the URDF they were made with) unless already there."""
    if (inputs / "DONE").exists():
        return
    inputs.mkdir(parents=True, exist_ok=True)
    urdf = inputs / "ur5_gripper.urdf"
    shutil.copyfile(code / "urdf" / "ur5_gripper.urdf", urdf)
    small = (0.6, np.array([0.03, -0.015, 0.04]), 1e-4 * np.eye(3))
    none = (0.0, np.zeros(3), np.zeros((3, 3)))
    session = _still_poses(POSES[:3], passes=2)  # three poses empty, then holding
    held = session[0] >= 3 * (HOLD + MOVE) - 0.5 * MOVE
    _write(inputs / "session.csv", _simulate(urdf, session, small, held, seed=1))
    still = _still_poses(POSES)
    always = np.ones(len(still[0]), bool)
    for name, load, seed in (("wrench_static", small, 2), ("wrench_empty_static", none, 3)):
        _write(inputs / f"{name}.csv", _simulate(urdf, still, load, always, seed, False), False)
    motion = _fourier()
    dyn = (0.8, np.array([0.02, -0.01, 0.08]), np.diag([4e-3, 5e-3, 3e-3]))
    for name, load, seed in (("motion_loaded", dyn, 6), ("motion_empty", none, 7)):
        _write(inputs / f"{name}.csv", _simulate(urdf, motion, load, [True] * len(motion[0]), seed))
    (inputs / "DONE").write_text("written by benchmarks/golden_results.py\n")


# ------------------------------------------------------------------ the cases


def _exports(*kinds: str) -> list[str]:
    files = {"ur": "payload.script", "franka": "franka.json", "ros2": "payload.yaml",
             "urdf": "payload.urdf", "mjcf": "payload.mjcf.xml", "franka-desk": "desk.json",
             "kuka": "load.dat", "kuka-sunrise": "load.java", "abb": "load.mod",
             "moveit": "attach.yaml"}  # fmt: skip
    return [a for k in kinds or files for a in (f"--export-{k}", files[k])]


def cli_cases(inputs: Path, real: Path) -> dict[str, list[str]]:
    """Case name -> the arguments of ``comgrasp``, run in the case's own folder."""
    u10, ur = real / "ur10e_rtde", real / "ur10e_rtde" / "ur10e.urdf"
    loaded, empty = u10 / "excitation_loaded_2805g.csv", u10 / "excitation_empty.csv"
    gains, arm = "../ur10e_calibrate_gains/GAINS.json", "../ur10e_identify_arm/ARM.json"
    u10e = ["--urdf", ur, "--ee-frame", "tool0"]
    dyn = ["estimate", "--dynamic", *u10e, "--csv", loaded, "--out", "RESULT.json"]
    u5 = ["--urdf", inputs / "ur5_gripper.urdf", "--ee-frame", EE]
    pairs = ["--before", _windows(0, 3), "--after", _windows(3, 3)]
    static = ["estimate", *u5, "--csv", inputs / "session.csv", "--out", "RESULT.json"]
    wrench = ["estimate", "--wrench", *u5, "--sensor-frame", SENSOR, "--out", "RESULT.json"]
    w_static, w_empty = inputs / "wrench_static.csv", inputs / "wrench_empty_static.csv"
    motion = ["--csv", inputs / "motion_loaded.csv"]
    panda = metadata.distribution("example-robot-data").locate_file(
        "cmeel.prefix/share/example-robot-data/robots/panda_description/urdf/panda.urdf"
    )
    cases = {
        "ur10e_calibrate_gains": ["calibrate-gains", *u10e, "--csv", loaded, "--empty-csv",
                                  empty, "--known-mass", "2.805", "--known-mass-std", "0.005",
                                  "--current-gains", UR10E_GAINS, "--out", "GAINS.json"],
        "ur10e_identify_arm": ["identify-arm", *u10e, "--csv", empty, "--current-gains", gains,
                               "--out", "ARM.json"],
        "ur10e_dynamic_arm_model": [*dyn, "--arm-model", arm, "--current-gains", gains,
                                    *_exports("ur", "urdf", "kuka", "abb", "ros2")],
        "ur10e_dynamic_empty": [*dyn, "--empty-csv", empty, "--current-gains", UR10E_GAINS,
                                "--gain-std", "0.1", *_exports("ur", "franka-desk", "mjcf")],
        "ur10e_dynamic_empty_gains": [*dyn, "--empty-csv", empty, "--current-gains", gains,
                                      *_exports("ur", "moveit")],
        "ur10e_dynamic_nominal": [*dyn, "--current-gains", gains, *_exports("ur", "urdf")],
        "panda_dynamic_nominal": ["estimate", "--dynamic", "--urdf", panda, "--ee-frame",
                                  "panda_link8", "--csv", real / "panda_tauJ" /
                                  "excitation_no_payload.csv", "--out", "RESULT.json"],
        "static_windows": [*static, *pairs, "--flange-frame", "tool0", "--inertia",
                           "cylinder:0.3,0.02,x", *_exports()],
        "static_auto_drift": [*static, "--auto", "--grasp-time", "8.5", "--drift-std", "0.005",
                              *_exports("ur", "franka")],
        "static_ipopt_torque_std": [*static, *pairs, "--method", "ipopt", "--torque-std",
                                    "0.004", *_exports("ros2")],
        "wrench_pairs": [*wrench, "--csv", inputs / "session.csv", *pairs, *_exports("kuka")],
        "wrench_static_auto": [*wrench, "--csv", w_static, "--auto", "--flange-frame", "tool0",
                               *_exports("ur", "abb", "urdf", "mjcf", "moveit")],
        "wrench_static_windows": [*wrench, "--csv", w_static, "--windows", _windows(0, 4),
                                  "--wrench-std", "0.05,0.002", *_exports("franka-desk")],
        "wrench_static_drift": [*wrench, "--csv", w_static, "--wrench-drift",
                                "0.01,0.0005,2e-4,1e-5"],
        "wrench_keep_tool": [*wrench[:-1], "TOOL.json", "--csv", w_empty, "--keep-tool"],
        "wrench_static_tool": [*wrench, "--csv", w_static, "--tool",
                               "../wrench_keep_tool/TOOL.json", *_exports("ur")],
        "wrench_nothing_held": [*wrench, "--csv", w_empty, *_exports("ur")],
        "wrench_dynamic_empty": [*wrench, *motion, "--dynamic", "--empty-csv",
                                 inputs / "motion_empty.csv", *_exports("urdf", "ur", "kuka")],
        "wrench_dynamic_nominal": [*wrench, *motion, "--dynamic", *_exports("ur")],
        "joints_dynamic_empty": ["estimate", "--dynamic", *u5, *motion, "--empty-csv",
                                 inputs / "motion_empty.csv", "--out", "RESULT.json",
                                 *_exports("ur", "franka")],
    }  # fmt: skip
    return {name: [str(a) for a in args] for name, args in cases.items()}


def bench_cases(code: Path, real: Path) -> dict[str, list[str]]:
    """Name -> the command (``{out}``: the case's folder), run from ``--code``."""
    py, b = sys.executable, code / "benchmarks"
    return {
        "bench/real_logs": [py, b / "real_logs.py", "--data", real, "--out", "{out}/real_logs.json"],
        "bench/wrench_static": [py, b / "wrench_static.py", "--quick", "--out", "{out}/wrench_static.json"],
        "bench/wrench_dynamic": [py, b / "wrench_dynamic.py", "--seeds", "4", "--out", "{out}/wrench_dynamic.json"],
        "reproduce_quick": [py, "-m", "comgrasp_pin.cli", "reproduce", "--quick", "--workers", "2",
                            "--out", "{out}"],
    }  # fmt: skip


# ------------------------------------------------------------------ running


def run_case(name: str, cmd: list, cwd: Path, folder: Path, env: dict) -> float:
    """Run ``cmd`` with a fresh ``folder``: cmd.txt, stdout.txt, stderr.txt, rc.txt."""
    if folder.exists():
        shutil.rmtree(folder)
    folder.mkdir(parents=True)
    cmd = [str(a).replace("{out}", str(folder)) for a in cmd]
    start = time.perf_counter()
    res = subprocess.run(cmd, cwd=cwd or folder, env=env, capture_output=True, text=True)
    took = time.perf_counter() - start
    (folder / "cmd.txt").write_text(" ".join(cmd) + "\n")
    (folder / "stdout.txt").write_text(res.stdout)
    (folder / "stderr.txt").write_text(res.stderr)
    (folder / "rc.txt").write_text(f"{res.returncode}\n")
    print(f"{name:28s} rc={res.returncode}  {took:6.1f} s", flush=True)
    return took


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--code", type=Path, required=True, help="the checkout whose code runs")
    ap.add_argument("--inputs", type=Path, required=True, help="synthetic logs (made if missing)")
    ap.add_argument("--out", type=Path, required=True, help="the goldens' folder")
    ap.add_argument("--data", type=Path, default=REALDATA, help="the real data's folder")
    ap.add_argument("--only", help="comma-separated case names (default: all)")
    ap.add_argument("--no-bench", action="store_true", help="skip the benchmarks and reproduce")
    args = ap.parse_args()
    code, inputs, out = (p.resolve() for p in (args.code, args.inputs, args.out))
    if not (args.data / "ur10e_rtde").is_dir():
        raise SystemExit(f"the real data is not here: {args.data} (../shared/realdata)")
    make_inputs(code, inputs)
    env = {**os.environ, **THREADS, "PYTHONPATH": str(code), "MUJOCO_GL": "egl"}
    cli = [sys.executable, "-m", "comgrasp_pin.cli"]
    cases = {k: (cli + v, None) for k, v in cli_cases(inputs, args.data.resolve()).items()}
    if not args.no_bench:
        cases |= {k: (v, code) for k, v in bench_cases(code, args.data.resolve()).items()}
    only = set(args.only.split(",")) if args.only else set(cases)
    total = sum(run_case(k, c, cwd, out / k, env) for k, (c, cwd) in cases.items() if k in only)
    print(f"{len(only & set(cases))} cases in {total:.0f} s into {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
