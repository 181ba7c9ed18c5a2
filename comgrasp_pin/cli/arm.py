"""`comgrasp identify-arm` and `comgrasp calibrate-gains`: an arm's own model, once (DESIGN.md 4d).

- ``identify-arm``: the empty arm's base parameters, friction and their covariance from a
  run of any excitation motion, as ARM.json; ``estimate --dynamic --arm-model ARM.json``
  then takes a loaded run of any motion.
- ``calibrate-gains``: weigh it once. From a loaded and an empty run of the same motion and
  the payload's weighed mass, the drive gains (N m per A) of an arm that logs motor
  currents, with their covariance, as the JSON ``--current-gains`` reads.

Registered by ``cli.robot``; errors are ComGraspError (exit status 2, a message).
"""

from __future__ import annotations

import argparse

import numpy as np

_DEFAULTS = argparse.ArgumentDefaultsHelpFormatter


def _robot(args):
    from comgrasp_pin.cli.robot import robot_of

    if args.ee_frame is None:
        args.ee_frame = _deepest_frame(args.urdf, args.package_dir)
    return robot_of(args)


def _deepest_frame(urdf, package_dirs) -> str:
    """The URDF's frame on the longest chain of joints (the flange of an arm without tool)."""
    from comgrasp_pin.robot import urdf_model

    model = urdf_model(urdf, package_dirs)

    def depth(jid: int) -> int:
        return 0 if jid == 0 else 1 + depth(model.parents[jid])

    frames = [f for f in model.frames if f.parentJoint > 0]
    return max(frames, key=lambda f: depth(f.parentJoint)).name


def _cmd_identify(args: argparse.Namespace) -> int:
    from comgrasp_pin.cli.dynamic import one_log, window
    from comgrasp_pin.cli.gains_args import gains_from_args
    from comgrasp_pin.cli.robot import write_json
    from comgrasp_pin.errors import LogError
    from comgrasp_pin.robot_io.from_motion.arm_model import arm_model_dict, identify_arm

    guessed = args.ee_frame is None
    robot = _robot(args)
    gains = gains_from_args(args, robot)
    try:
        log = one_log(args.bag, args.csv, robot, args.topic, gains)
    except LogError as exc:
        if not guessed:
            raise
        raise LogError(
            f"{exc}. The arm's end was taken as {args.ee_frame!r}, the end of the URDF's "
            "longest chain: give --ee-frame, the flange (e.g. tool0, panda_link8)"
        ) from None
    model = identify_arm(robot, log, window(args.window, "--window"), args.cutoff)
    write_json(args.out, arm_model_dict(model))
    n = robot.nq
    v = model.validation
    print(f"the arm's own model from a {model.duration_s:.1f} s motion of {log.source} "
          f"(joints {', '.join(robot.joint_names)})")  # fmt: skip
    print(f"  {len(model.base_columns)} base parameters (QR of Pinocchio's regressor), "
          f"viscous and Coulomb friction per joint")  # fmt: skip
    print(f"  residual RMS per joint {np.array2string(model.residual_rms_Nm, precision=3)} N m")
    print(f"  held out ({v['method']}): RMS {np.array2string(np.array(v['rms_Nm']), precision=3)}"
          f" N m, {100 * v['explained_total']:.1f} % of the torques explained")  # fmt: skip
    print(f"  Coulomb friction {np.array2string(model.params[-n:], precision=2)} N m")
    print(f"wrote {args.out}")
    return 0


def _cmd_calibrate(args: argparse.Namespace) -> int:
    from comgrasp_pin.cli.dynamic import one_log
    from comgrasp_pin.cli.gains_args import gains_from_args
    from comgrasp_pin.cli.robot import write_json
    from comgrasp_pin.robot_io.from_motion.gain_calibration import calibrate_gains
    from comgrasp_pin.robot_io.log_files.gains import Gains, gains_json

    robot = _robot(args)
    gains = gains_from_args(args, robot)
    if gains is None:  # the logs read as currents: gains of 1 N m per A
        gains = Gains(np.ones(robot.nq), np.zeros((robot.nq, robot.nq)), "unit gains")
    loaded = one_log(None, args.csv, robot, None, gains)
    empty = one_log(None, args.empty_csv, robot, None, gains)
    cal = calibrate_gains(robot, loaded, empty, args.known_mass, args.known_mass_std, args.cutoff)
    extra = {
        "known_mass_kg": cal.known_mass_kg,
        "known_mass_std_kg": cal.known_mass_std_kg,
        "nominal_gains_Nm_per_A": cal.nominal.tolist(),
        "com_m": cal.com_m.tolist(),
        "residual_rms_Nm": cal.residual_rms_Nm.tolist(),
        "alignment": cal.alignment,
        "loaded": str(args.csv),
        "empty": str(args.empty_csv),
    }
    write_json(args.out, gains_json(cal.gains, cal.cov, list(robot.joint_names), **extra))
    std = np.sqrt(np.diag(cal.cov))
    print(f"drive gains from {cal.known_mass_kg:g} kg moved {cal.duration_s:.1f} s, loaded "
          "and empty (N m per A):")  # fmt: skip
    for name, k, s, k0 in zip(robot.joint_names, cal.gains, std, cal.nominal, strict=True):
        print(f"  {name:24s} {k:8.4f} +- {s:.4f} ({100 * s / k:.1f} %), x{k / k0:.3f} nominal")
    print(f"wrote {args.out}")
    return 0


def _common(p: argparse.ArgumentParser, ee_required: bool) -> None:
    from comgrasp_pin.cli.gains_args import add_gains_args
    from comgrasp_pin.cli.robot import add_robot_args
    from comgrasp_pin.robot_io.from_motion.motion_signals import CUTOFF_HZ

    ee_help = (
        "the payload's frame (the flange or TCP)"
        if ee_required
        else "a frame at the arm's end (default: one on the URDF's longest chain; give the "
        "flange, e.g. tool0 or panda_link8, where the URDF has a gripper)"
    )
    add_robot_args(p, ee_help, ee_required)
    p.add_argument("--cutoff", type=float, default=CUTOFF_HZ, help="low-pass cutoff (Hz)")
    add_gains_args(p)


def add_arm_subcommands(sub: argparse._SubParsersAction) -> None:
    """Add `identify-arm` and `calibrate-gains` to the `comgrasp` subparsers ``sub``."""
    from comgrasp_pin.robot_io.log_files.joint_readers import DEFAULT_TOPIC

    ident = sub.add_parser(
        "identify-arm",
        help="the empty arm's own dynamics (base parameters, friction) from any motion, as "
        "ARM.json for estimate --dynamic --arm-model",
        description="Identify the empty arm's own dynamics from a log of any excitation "
        "motion: the base inertial parameters of the URDF's links (QR of Pinocchio's joint-"
        "torque regressor), viscous and Coulomb friction per joint, with their covariance and "
        "a held-out check. The URDF's values are a weak prior. `estimate --dynamic --arm-model "
        "ARM.json` then takes a loaded run of any motion, no empty run needed.",
        formatter_class=_DEFAULTS,
    )
    _common(ident, ee_required=False)
    run = ident.add_mutually_exclusive_group(required=True)  # the empty arm's run
    run.add_argument("--csv", default=None, help="the empty arm's run: CSV or UR recording")
    run.add_argument("--bag", default=None, help="the empty arm's run: ROS 2 bag or ROS 1 .bag")
    ident.add_argument("--topic", default=DEFAULT_TOPIC, help="JointState topic of --bag")
    ident.add_argument("--window", default=None, help="T0:T1, the part of the log to use (s)")
    ident.add_argument("--out", default="ARM.json", help="the arm model JSON")
    ident.set_defaults(func=_cmd_identify)

    cal = sub.add_parser(
        "calibrate-gains",
        help="weigh it once: an arm's drive gains (N m per A) from a known mass moved "
        "loaded and empty, as the JSON --current-gains reads",
        description="For arms that log motor currents (UR): the per-joint drive gains and "
        "their covariance from a loaded and an empty run of the same motion and the "
        "payload's weighed mass (its CoM and inertia need not be known). The runs are found "
        "and aligned on their positions.",
        formatter_class=_DEFAULTS,
    )
    _common(cal, ee_required=True)
    cal.add_argument("--csv", required=True, help="the loaded run (UR recording or CSV)")
    cal.add_argument("--empty-csv", required=True, help="the same motion with the empty arm")
    cal.add_argument("--known-mass", type=float, required=True, help="the payload's mass (kg)")
    cal.add_argument("--known-mass-std", type=float, default=0.0,
                     help="the scale's standard deviation (kg)")  # fmt: skip
    cal.add_argument("--out", default="GAINS.json", help="the gains JSON")
    cal.set_defaults(func=_cmd_calibrate)
