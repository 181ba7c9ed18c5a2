"""`comgrasp live`: measure a payload on a connected Franka and, if identified, set its load.

The steps: connect and check the robot (errors, mode, contact); plan the poses (or read
them, or read a planned motion: ``--motion``); show them and ask before anything moves
(``--yes`` skips); the empty run; attach the payload (a prompt); the loaded run; the estimate
with its verdict (along a motion: the inertia too); ``--set-load`` sends
mass, CoM (flange frame) and inertia only for an ``identified`` verdict and checks what the
robot reports back. ``DIR/live_log.csv`` holds every state read and ``DIR/live.json`` the
windows and the command that estimates the same file offline with the same result.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import time
from pathlib import Path

import numpy as np

from comgrasp_pin.cli.live_plan import prompt_attach, sim_payload
from comgrasp_pin.cli.robot import write_json
from comgrasp_pin.config import LiveConfig
from comgrasp_pin.errors import EmptyGripperError, InvalidInputError, RobotError

LOOPBACK = "127.0.0.1"


def add_subcommand(sub: argparse._SubParsersAction) -> None:
    """Add `live` to the `comgrasp` subparsers ``sub``."""
    from comgrasp_pin.robot_io.payload_files.payload import INERTIA_HELP

    d = LiveConfig()
    p = sub.add_parser(
        "live",
        help="measure a payload on a connected Franka (libfranka's protocol) and set its load",
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    where = p.add_mutually_exclusive_group(required=True)
    where.add_argument("--host", help="the robot's address (its FCI, as in Desk)")
    where.add_argument(
        "--sim", action="store_true", help=f"a simulated FR3 (franky-sim, MuJoCo) on {LOOPBACK}"
    )
    p.add_argument("--urdf", default=None,
                   help="the arm's URDF (default: the FR3 of franka_description, as franky-sim "
                   "ships it)")  # fmt: skip
    p.add_argument(
        "--ee-frame",
        default="fr3_link8",
        help="the flange frame, where libfranka's F_x_Cload is (default fr3_link8)",
    )
    p.add_argument("--poses", default=None, metavar="POSES.json",
                   help="the poses of comgrasp plan-poses (default: planned here, near the "
                   "arm's pose, free of self-collision, D-optimal)")  # fmt: skip
    p.add_argument(
        "--n-poses", type=int, default=d.n_poses, help="poses planned (default %(default)s)"
    )
    p.add_argument("--motion", default=None, metavar="MOTION.json",
                   help="measure along this motion of comgrasp plan-motion instead of at rest "
                   "(the inertia too; played slower where it would exceed the dynamics "
                   "factor)")  # fmt: skip
    p.add_argument("--arm-model", default=None, metavar="ARM.json",
                   help="with --motion: the arm's own dynamics (comgrasp identify-arm of an "
                   "empty run of any motion) stand for the empty run: the payload is "
                   "attached first and the motion played once")  # fmt: skip
    p.add_argument("--dynamics-factor", type=float, default=d.dynamics_factor,
                   help=f"share of the arm's speed limits each move uses, at most "
                   f"{d.max_dynamics_factor:g} (default %(default)s)")  # fmt: skip
    p.add_argument("--yes", action="store_true",
                   help="do not ask before moving nor wait for the payload (scripts; the "
                   "payload must be attached when the empty run ends, or at the start with "
                   "--arm-model)")  # fmt: skip
    p.add_argument("--dry-run", action="store_true",
                   help="plan and show the poses or the motion; move nothing")  # fmt: skip
    p.add_argument("--set-load", action="store_true",
                   help="send the identified load to the robot (set_load); never for another "
                   "verdict")  # fmt: skip
    p.add_argument("--inertia", default="point", help=f"the inertia sent: {INERTIA_HELP}")
    p.add_argument("--sim-payload", default=None, metavar="M,CX,CY,CZ[,IXX,IYY,IZZ]",
                   help="with --sim: the payload attached at the prompt: kg, CoM in the flange "
                   "frame (m), principal moments in the flange's axes (kg m^2)")  # fmt: skip
    p.add_argument(
        "--sim-fault",
        choices=["reflex"],
        default=None,
        help="with --sim: the robot reports a joint reflex (to try the refusal)",
    )
    p.add_argument("--sim-lose-after", type=float, default=None, metavar="S",
                   help="with --sim: the server ends after S s, as a pulled cable would (to try "
                   "the refusal)")  # fmt: skip
    p.add_argument("--out", required=True, metavar="DIR", help="folder for the log and results")
    p.set_defaults(func=run_live, command="live")


def run_live(args: argparse.Namespace) -> int:
    """The `live` command; its exit status."""
    from comgrasp_pin._paths import fr3_urdf
    from comgrasp_pin.live.protocol import check_dynamics_factor

    config = dataclasses.replace(LiveConfig(), n_poses=args.n_poses)
    config = dataclasses.replace(
        config, dynamics_factor=check_dynamics_factor(args.dynamics_factor, config)
    )
    if not args.sim and (args.sim_payload or args.sim_fault or args.sim_lose_after):
        raise InvalidInputError("--sim-payload, --sim-fault and --sim-lose-after are for --sim")
    if args.motion is not None and args.poses is not None:
        raise InvalidInputError("give --poses (at rest) or --motion (along a motion), not both")
    arm_model = None
    if args.arm_model is not None:
        if args.motion is None:
            raise InvalidInputError("--arm-model stands for the empty run along a motion: "
                                    "give --motion too")  # fmt: skip
        from comgrasp_pin.robot_io.from_motion.arm_model import load_arm_model

        arm_model = load_arm_model(args.arm_model)  # a clear error before anything moves
    urdf = args.urdf or str(fr3_urdf())
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    if not args.sim:
        return _session(args, config, urdf, out, args.host, lambda: prompt_attach(args),
                        arm_model)  # fmt: skip
    from comgrasp_pin.simulation.franka_sim import FrankaSim  # the simulated FR3: MuJoCo

    payload = sim_payload(args.sim_payload)
    with FrankaSim(payload, args.sim_fault, args.sim_lose_after) as sim:

        def attach() -> None:
            prompt_attach(args)
            sim.attach()

        return _session(args, config, urdf, out, LOOPBACK, attach, arm_model)


def _session(args, config: LiveConfig, urdf: str, out: Path, host: str, attach,
             arm_model=None) -> int:  # fmt: skip
    """Connect, plan, ask, measure, write, estimate, maybe set the load.

    ``arm_model``: --arm-model's ``ArmModel``, standing for the empty run, or None.
    """
    from comgrasp_pin.cli import live_plan as lp
    from comgrasp_pin.live import FrankaArm, measure, measure_motion
    from comgrasp_pin.live.protocol import Waypoints
    from comgrasp_pin.robot_io import load_robot
    from comgrasp_pin.robot_io.log_files.record import write_csv

    started = time.monotonic()
    robot = load_robot(urdf, args.ee_frame)
    arm = FrankaArm(host, config)
    arm.check_ready()
    q_now = np.array(arm.state().q, dtype=float)
    plan: np.ndarray | Waypoints
    if args.motion is None:
        plan = lp.poses(args, robot, q_now, config)
        lp.show_poses(robot, plan, config)
    else:
        plan = lp.motion(args, robot, arm.limits(), config)
        lp.show_motion(args, robot, plan, q_now, config)
    if args.dry_run:
        print("dry run: nothing moved")
        return 0
    lp.confirm(args, "through these poses" if args.motion is None else "along this motion")
    arm.configure()
    names = tuple(robot.joint_names)
    if isinstance(plan, Waypoints):
        rec = measure_motion(arm, names, plan, attach, config, empty_run=arm_model is None)
    else:
        rec = measure(arm, names, plan, attach, config)
    if len(rec.log.time):
        write_csv(rec.log, out / "live_log.csv")
    if rec.wrench is not None:  # the robot's own estimate of the external wrench, for a look
        np.savetxt(out / "O_F_ext_hat_K.csv", np.column_stack([rec.log.time, rec.wrench]),
                   delimiter=",", header="time,fx,fy,fz,tx,ty,tz", comments="")  # fmt: skip
    info = lp.live_info(args, config, urdf, out, host, plan, rec, time.monotonic() - started)
    write_json(str(out / "live.json"), info)
    if not rec.complete:
        raise RobotError(f"the measurement ended early: {rec.stopped_by}. Kept {len(rec.log.time)} "
                         f"readings in {out / 'live_log.csv'} ({out / 'live.json'})")  # fmt: skip
    return _estimate_and_set(args, robot, arm, rec, out, info, config, arm_model)


def _estimate_and_set(args, robot, arm, rec, out: Path, info: dict, config: LiveConfig,
                      arm_model=None) -> int:  # fmt: skip
    """The estimate of the log as written (offline's computation, on the same file and the
    same windows' text), then ``--set-load``."""
    from comgrasp_pin.live.protocol import load_read_back, load_to_send
    from comgrasp_pin.robot_io import estimate_from_log
    from comgrasp_pin.robot_io.at_rest import parse_windows
    from comgrasp_pin.robot_io.from_motion.dynamic import estimate_payload_dynamic
    from comgrasp_pin.robot_io.log_files import read_csv
    from comgrasp_pin.robot_io.payload_files.controller_files import franka_load
    from comgrasp_pin.robot_io.payload_files.payload import payload_in_flange
    from comgrasp_pin.robot_io.results.report import summary
    from comgrasp_pin.robot_io.results.result_file import write_result

    log = read_csv(out / "live_log.csv", robot.joint_names)
    try:
        if rec.motion_windows is not None:
            empty_text, loaded_text = rec.motion_windows
            l0, l1 = parse_windows(loaded_text, "--window")[0]
            if empty_text is None:  # the arm model stands for the empty run
                est = estimate_payload_dynamic(robot, log, None, (l0, l1), arm_model=arm_model)
            else:
                e0, e1 = parse_windows(empty_text, "--empty-window")[0]
                est = estimate_payload_dynamic(robot, log, log, (l0, l1), (e0, e1))
        else:
            before = parse_windows(rec.before, "--before", joined=True)
            after = parse_windows(rec.after, "--after", joined=True)
            est = estimate_from_log(robot, log, before, after)
    except EmptyGripperError as exc:  # the estimator's own refusal: nothing held
        raise EmptyGripperError(f"{exc}. Nothing was sent to the robot") from None
    write_result(est, out / "RESULT.json")
    print(summary(est))
    print(f"wrote {out / 'RESULT.json'}, {out / 'live_log.csv'}, {out / 'live.json'}")
    if not args.set_load:
        return 0
    payload = None
    if est.verdict == "identified":
        payload = payload_in_flange(robot, est, args.ee_frame, args.inertia)
    send, why = load_to_send(est, payload)
    if not send or payload is None:
        print(f"comgrasp live: set_load refused: {why}", file=sys.stderr)
        return 2
    load = franka_load(payload)
    m, com, inertia = arm.set_load(load)
    wrong = load_read_back(load, m, com, inertia, config.load_tolerance)
    info["set_load"] = {"sent": load, "read_back": {"m_load": m, "F_x_Cload": com.tolist(),
                                                    "I_load": inertia.tolist()},
                        "agrees": not wrong}  # fmt: skip
    write_json(str(out / "live.json"), info)
    if wrong:
        raise RobotError(f"the robot reports a load other than the one sent: {'; '.join(wrong)}")
    print(f"set_load: {load['mass']:.4f} kg, CoM {np.round(1e3 * np.array(load['F_x_Cload']), 2)} "
          f"mm in {args.ee_frame}; the robot reports the same")  # fmt: skip
    return 0
