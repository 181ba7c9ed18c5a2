"""`comgrasp live`'s plan and its questions: the poses or the motion, shown before anything
moves; the prompts; ``live.json``, the record of what ran and how to estimate it again."""

from __future__ import annotations

import dataclasses
import json
import sys
from pathlib import Path

import numpy as np

from comgrasp_pin.config import LiveConfig
from comgrasp_pin.errors import InvalidInputError


def poses(args, robot, q_start: np.ndarray, config: LiveConfig) -> np.ndarray:
    """The measurement poses (k, n): read from --poses, or planned near ``q_start``."""
    from comgrasp_pin.live.protocol import check_poses_fit
    from comgrasp_pin.planning.measurement_poses import plan_measurement_poses

    if args.poses is not None:
        try:
            Q = np.array(json.loads(Path(args.poses).read_text())["q_rad"], dtype=float)
        except (OSError, ValueError, KeyError, TypeError) as exc:
            msg = f"--poses {args.poses}: not a plan-poses JSON ({exc})"
            raise InvalidInputError(msg) from None
        if Q.ndim != 2 or Q.shape[1] != robot.nq or not np.all(np.isfinite(Q)):
            raise InvalidInputError(f"--poses {args.poses}: q_rad must be (k, {robot.nq}) finite")
    else:
        margin = config.approach_rad + config.joint_margin_rad
        plan = plan_measurement_poses(
            robot, config.n_poses, start=q_start, n_candidates=600,
            min_height=config.min_height_m, max_offset=config.max_pose_offset_rad, margin=margin,
        )  # fmt: skip
        Q = plan.q
    check_poses_fit(Q, robot.q_lower, robot.q_upper, config.approach_rad)
    return Q


def motion(args, robot, limits, config: LiveConfig):
    """The planned motion of --motion as the arm will play it (``protocol.Waypoints``)."""
    from comgrasp_pin.live.protocol import motion_waypoints
    from comgrasp_pin.robot_io.payload_files.motion_files import read_motion

    t, q, qd, qdd = read_motion(args.motion, robot.joint_names)
    outside = (q < robot.q_lower) | (q > robot.q_upper)
    if np.any(outside):
        k, j = np.argwhere(outside)[0]
        raise InvalidInputError(
            f"--motion {args.motion}: joint {j + 1} leaves its limits at {t[k]:.2f} s "
            f"({q[k, j]:.3f} rad): plan it for this arm"
        )
    return motion_waypoints(t, q, qd, qdd, limits, config.dynamics_factor, config)


def show_poses(robot, Q: np.ndarray, config: LiveConfig) -> None:
    print(f"{len(Q)} poses for {robot.ee_frame}, each approached from both sides "
          f"(+-{config.approach_rad:g} rad), the empty arm first, then the payload; moves at "
          f"{config.dynamics_factor:g} of the arm's limits:")  # fmt: skip
    for i, q in enumerate(Q):
        print(f"  pose {i}: " + " ".join(f"{v:7.1f}" for v in np.degrees(q)) + "  deg")


def show_motion(args, robot, w, q_now: np.ndarray, config: LiveConfig) -> None:
    slower = f" at {1 / w.slow_down:.2f} of its planned speed" if w.slow_down > 1 else ""
    reach = np.degrees(np.abs(np.vstack([w.q, w.start]) - w.start).max(axis=0))
    runs = "empty first, then with the payload"
    if args.arm_model:
        runs = "with the payload (the arm's own from --arm-model)"
    print(f"a planned motion for {robot.ee_frame}, played {runs}: "
          f"through {len(w.t)} waypoints{slower}, as fast as dynamics factor "
          f"{config.dynamics_factor:g} allows (about {w.duration_s:.0f} s)")  # fmt: skip
    print("  start:  " + " ".join(f"{v:7.1f}" for v in np.degrees(w.start)) + "  deg "
          f"({np.degrees(np.abs(w.start - q_now).max()):.1f} deg from the arm's pose)")  # fmt: skip
    print("  reach:  " + " ".join(f"{v:7.1f}" for v in reach) + "  deg from the start")


def confirm(args, what: str) -> None:
    """Ask before the arm moves (``--yes``: don't)."""
    if args.yes:
        return
    if not sys.stdin.isatty():
        raise InvalidInputError("the arm would move: give --yes to move without asking")
    answer = input(f"Keep clear of the arm. Move {what}? [y/N] ")
    if answer.strip().lower() not in ("y", "yes"):
        raise InvalidInputError("not confirmed: nothing moved")


def prompt_attach(args) -> None:
    if args.yes or not sys.stdin.isatty():
        return
    done = "" if getattr(args, "arm_model", None) else "Empty run done. "
    input(f"{done}Attach the payload, keep clear of the arm, and press Enter ")


def sim_payload(text: str | None):
    """--sim-payload's ``SimPayload``, or None."""
    from comgrasp_pin.simulation.franka_sim import SimPayload

    if text is None:
        return None
    try:
        v = [float(x) for x in text.split(",")]
    except ValueError:
        v = []
    if len(v) not in (4, 7) or not np.all(np.isfinite(v)) or v[0] <= 0:
        raise InvalidInputError(f"--sim-payload {text!r}: give M,CX,CY,CZ[,IXX,IYY,IZZ], M > 0")
    moments = v[4:] if len(v) == 7 else [1e-3] * 3
    return SimPayload(v[0], (v[1], v[2], v[3]), tuple(map(tuple, np.diag(moments))))


def offline_args(rec, arm_model: str | None = None) -> str:
    """The `comgrasp estimate` options that estimate the recording's log as live did."""
    if rec.motion_windows is not None:
        empty, loaded = rec.motion_windows
        if empty is None:
            return f"--dynamic --window {loaded} --arm-model {arm_model}"
        return f"--dynamic --window {loaded} --empty-csv {{log}} --empty-window {empty}"
    return f"--before {rec.before} --after {rec.after}"


def live_info(args, config, urdf, out, host, plan, rec, wall_s: float) -> dict:
    """live.json: what ran, the windows, and the offline command that reads the same log."""
    log = out / "live_log.csv"
    offline = (
        f"comgrasp estimate --urdf {urdf} --ee-frame {args.ee_frame} --csv {log} "
        + offline_args(rec, args.arm_model).format(log=log)
        + f" --out {out / 'RESULT_offline.json'}"
    )
    along = {"poses_rad": plan.tolist()} if isinstance(plan, np.ndarray) else {
        "motion": str(args.motion), "motion_slow_down": plan.slow_down,
        "motion_played_s": plan.duration_s, "windows": rec.spans}  # fmt: skip
    return {
        "host": host,
        "simulated": bool(args.sim),
        "urdf": str(urdf),
        "ee_frame": args.ee_frame,
        "config": dataclasses.asdict(config),
        **along,
        "complete": rec.complete,
        "stopped_by": rec.stopped_by,
        "n_readings": len(rec.log.time),
        "before": rec.before,
        "after": rec.after,
        "robot_wrench_estimate_nonzero": rec.wrench is not None,
        "wall_time_s": round(wall_s, 2),
        "offline": offline,
    }
