"""The live measurement's numbers: how a connected arm is moved, held and read.

``comgrasp live`` records them in its ``live.json`` beside the log it writes. SI units.
"""

from __future__ import annotations

from dataclasses import dataclass, field


@dataclass(frozen=True)
class LiveConfig:
    """How ``comgrasp live`` moves, holds and reads a Franka arm.

    Attributes:
        dynamics_factor: share of the arm's velocity, acceleration and jerk limits every
            move uses (libfranka's relative dynamics factor), in (0, max_dynamics_factor].
        max_dynamics_factor: the cap; a larger ``dynamics_factor`` is refused. Slow moves
            keep a person beside the arm safe and the torques at rest free of the moves'
            after-effects.
        approach_rad: each pose is reached twice, from q + approach and from q - approach on
            every joint (rad): a joint's stuck friction has opposite signs on the two sides
            and cancels in their mean (``windows.read_joined``).
        settle_s: wait after a move before recording (s), and then on until every joint
            is slower than ``still_speed`` (at most ``max_settle_s``).
        still_speed: the joint speed (rad/s, over 0.1 s) below which the arm is still.
            Below the static windows' threshold (``windows.MAX_SPEED``, 0.01): a joint that
            stops holds friction, which relaxes while it creeps the last fraction of a
            milliradian; what the two sides' mean leaves of it is weighed and widens the
            interval (``static_errors.side_friction_cov``). franky-sim's FR3, the same 10
            payloads: at 1e-4 the CoM within 1.5 mm (rms 0.8), 56 s per identification; at
            3e-4 within 2.2 mm (rms 1.2), 50 s; at 1e-3 within 2.7 mm (rms 1.6), 45 s.
        max_settle_s: the longest wait for the arm to be still (s); past it, the window is
            recorded anyway and the estimate's static check judges it.
        record_s: the window recorded at each side of each pose (s).
        sample_period_s: the period at which the robot's state is read (s).
        n_poses: measurement poses planned when none are given.
        max_pose_offset_rad: planned poses lie within this of the start on every joint (rad).
        joint_margin_rad: planned poses keep this from the joint limits, beside the approach
            (rad).
        min_height_m: the flange and wrist joints stay this high above the base (m).
        collision_torque_nm: the contact thresholds sent to the robot before it moves
            (libfranka's collision behaviour), per joint (N m).
        collision_force_n: the same for the Cartesian wrench (N, N m).
        load_tolerance: set_load's read-back must match what was sent within this (kg, m,
            kg m^2).
        motion_timeout_s: a move that has not ended after this is stopped (s); a planned
            motion (``--motion``) gets its own played length on top.
        waypoint_period_s: a planned motion is played through joint waypoints (position and
            velocity) taken this far apart in its time (s); its highest harmonic's period is
            0.5 s at plan-motion's defaults. (Every 0.1 or 0.25 s, franky-sim's joint 7 chattered by
            +-24 N m.)
        motion_limit_share: a planned motion is played slower than planned where its peak
            velocity, acceleration or jerk exceeds this share of ``dynamics_factor`` times
            the robot's limits (the margin lets the robot's trajectory generator reach
            every waypoint's velocity).
        motion_hold_s: the arm is held still this long before and after a planned motion,
            inside its window (s).
    """

    dynamics_factor: float = 0.2
    max_dynamics_factor: float = 0.3
    approach_rad: float = 0.04
    settle_s: float = 0.3
    still_speed: float = 3e-4
    max_settle_s: float = 4.0
    record_s: float = 0.5
    sample_period_s: float = 0.002
    n_poses: int = 4
    max_pose_offset_rad: float = 0.6
    joint_margin_rad: float = 0.1
    min_height_m: float = 0.15
    collision_torque_nm: tuple[float, ...] = field(default=(25.0,) * 7)
    collision_force_n: tuple[float, ...] = field(default=(30.0,) * 6)
    load_tolerance: float = 1e-4
    motion_timeout_s: float = 30.0
    waypoint_period_s: float = 0.5
    motion_limit_share: float = 0.9
    motion_hold_s: float = 0.5
