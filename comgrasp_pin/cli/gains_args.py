"""`--current-gains` and `--gain-std`: the drive gains a command reads a current log with.

The options are added to `comgrasp estimate` by ``cli.robot``; each path that reads a log
(static, ``--dynamic``) turns them into ``robot_io.log_files.gains.Gains`` with ``gains_from_args``.
"""

from __future__ import annotations

import argparse

CURRENT_GAINS_HELP = (
    "K1,...,Kn in N m per A, or the JSON of comgrasp calibrate-gains: turns a UR log's motor "
    "currents into joint torques (and a bag's or CSV's efforts, where they are currents)"
)
GAIN_STD_HELP = (
    "relative std of the gains, e.g. 0.1 for nominal values; enters the covariance (with a "
    "calibrate-gains JSON: replaces its covariance). Default: none given, the gains count as "
    "exact"
)


def add_gains_args(p: argparse.ArgumentParser | argparse._ArgumentGroup) -> None:
    """Add ``--current-gains`` and ``--gain-std`` to ``p``."""
    p.add_argument("--current-gains", default=None, metavar="K1,...,Kn|GAINS.json",
                   help=CURRENT_GAINS_HELP)  # fmt: skip
    p.add_argument("--gain-std", type=float, default=None, metavar="R", help=GAIN_STD_HELP)
    p.add_argument("--gain-correlation", type=float, default=None, metavar="RHO",
                   help="correlation of two joints' gain errors under --gain-std, 0 "
                   "(independent) to 1 (one common error); default 0.5: a torque "
                   "constant's temperature and data-sheet error is common, the unit spread "
                   "is not")  # fmt: skip


def gains_from_args(args: argparse.Namespace, robot):
    """The ``Gains`` of ``--current-gains`` / ``--gain-std`` for ``robot``, or None without.

    ``robot``: a ``RobotModel`` (its ``nq`` and ``joint_names`` check the gains' count and a
    JSON's joint names).

    Raises:
        InvalidInputError: see ``robot_io.log_files.gains.parse_gains``; ``--gain-std`` without
            gains.
    """
    from comgrasp_pin.errors import InvalidInputError
    from comgrasp_pin.robot_io.log_files.gains import parse_gains

    text = getattr(args, "current_gains", None)
    gain_std = getattr(args, "gain_std", None)
    if text is None:
        if gain_std is not None:
            raise InvalidInputError(
                "--gain-std R is the relative std of the drive gains: give them too "
                f"(--current-gains K1,...,K{robot.nq} or a calibrate-gains JSON), or leave "
                "--gain-std out"
            )
        return None
    from comgrasp_pin.robot_io.log_files.gains import GAIN_CORRELATION

    rho = getattr(args, "gain_correlation", None)
    return parse_gains(text, robot.nq, gain_std, robot.joint_names,
                       GAIN_CORRELATION if rho is None else rho)  # fmt: skip
