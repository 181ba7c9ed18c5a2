"""An excitation motion for any arm: the payload's ten inertial parameters made observable.

The motion is a rest-to-rest finite Fourier series (``motion.fourier``), repeated
``periods`` times within ``duration_s`` (at most 20 s), about a start configuration. Each
joint stays within its URDF position limits (``position_margin_rad`` inside) and within a
box about the start: ``wrist_range_rad`` for the last ``wrist_joints`` joints, which do most
of the work, ``arm_range_rad`` for the others; within ``velocity_scale`` of its URDF velocity
limit and within ``acceleration_limit`` (URDFs carry none). Along the motion the arm is free
of self-collision and its wrist and ee stay ``min_height_m`` above the floor plane
(``planning.feasible``).

Observability: the condition number of the stacked payload regressor
(``estimation.payload_regressor``) with its columns scaled by a typical payload's parameter
magnitudes (``parameter_scale(typical_length_m)``: m, m L, m L^2), so that every column is
one parameter's typical torque. The unscaled (SI) number is reported as well.

The search (``excitation_search``): ``n_random`` random motions, each scaled joint by joint
to its tightest limit; the ``n_starts`` best (smallest scaled condition number) that are
free of collision seed CasADi + IPOPT, which minimises log tr(M) + log tr(M^-1) (M = A^T A of
the scaled regressor, a smooth bound on cond(M)) under the limits as linear constraints on a
grid of ``samples_per_period`` points, its gradient by finite differences of the Pinocchio
regressor. A refined motion that collides is pulled back towards its seed until it is free.
The best is checked on the output grid (``sample_period_s``): limits (scaled down if a peak
between the optimiser's grid points exceeds one), collision, floor.

Where an excitation motion may go: its joints' limits, its start, its final scaling.

``excitation_limits`` takes the URDF's position and velocity limits with the settings'
margins, range boxes and rate scales; ``check_start`` refuses a start outside them, in
collision or below the floor; ``within_limits`` scales a planned series down about its
start where a peak between the search's grid points exceeds a limit. Joint units (rad, or m
for a prismatic joint), s.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from comgrasp_pin import validate
from comgrasp_pin.errors import CollisionError, InvalidInputError, UnobservableError
from comgrasp_pin.estimation.payload_regressor import (
    condition_number,
    parameter_scale,
    payload_regressor,
)
from comgrasp_pin.motion.fourier import FourierMotion
from comgrasp_pin.planning.collision import SelfCollision
from comgrasp_pin.planning.excitation_search import (
    ExcitationSettings,
    Limits,
    checked_settings,
    search,
)
from comgrasp_pin.planning.measurement_poses import feasible, floor_heights
from comgrasp_pin.robot import RobotModel

MAX_DURATION_S = 20.0
MIN_DURATION_S = 4.0
MIN_JOINTS = 6  # fewer joints see less than the payload's full wrench
UR_JOINT_NAMES = ("shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint",
                  "wrist_1_joint", "wrist_2_joint", "wrist_3_joint")  # fmt: skip
UR_HOME = (0.0, -np.pi / 2, np.pi / 2, -np.pi / 2, -np.pi / 2, 0.0)
"""A UR arm's start when none is given: elbow up, tool pointing down."""
SRDF_STATES = ("home", "default", "ready")


@dataclass(frozen=True)
class ExcitationMotion:
    """A planned excitation motion, sampled every ``settings.sample_period_s``.

    Attributes:
        t: (k,) time (s), 0 to ``duration_s``.
        q, qd, qdd: (k, n) joint positions (rad / m), velocities, accelerations.
        series: the Fourier series (start ``series.q0``, coefficients ``a``, ``b`` (n, L)
            in rad/s, ``period_s``): evaluate it at any rate.
        joint_names, ee_frame: the arm's joints (columns) and the payload's frame.
        duration_s: length of the motion (s), ``settings.periods`` periods.
        condition_number: of the stacked payload regressor over ``t``, columns scaled by
            ``parameter_scale`` (10,), the typical payload's magnitudes.
        condition_number_si: the same, columns in SI units (unscaled).
        velocity_limit, acceleration_limit: (n,) limits used (rad/s, rad/s^2).
        q_lower, q_upper: (n,) position bounds used (URDF margin and range box, rad).
        peak_velocity_share, peak_acceleration_share: (n,) max |qd| / limit, max |qdd| / limit.
        min_height_m: lowest height of the wrist joints and ee over the motion (m, world z).
        gravity: (3,) the model's gravity, world frame (m/s^2).
        settings: the tuning numbers.
        solver_status: IPOPT's return_status per refinement (``"random"``: none ran).
        plan_time_s: wall time of the search (s).
    """

    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray
    series: FourierMotion
    joint_names: tuple[str, ...]
    ee_frame: str
    duration_s: float
    condition_number: float
    condition_number_si: float
    parameter_scale: np.ndarray
    velocity_limit: np.ndarray
    acceleration_limit: np.ndarray
    q_lower: np.ndarray
    q_upper: np.ndarray
    peak_velocity_share: np.ndarray
    peak_acceleration_share: np.ndarray
    min_height_m: float
    gravity: np.ndarray
    settings: ExcitationSettings = field(default_factory=ExcitationSettings)
    solver_status: tuple[str, ...] = ()
    plan_time_s: float = 0.0


def default_start(robot: RobotModel, checker: SelfCollision) -> np.ndarray:
    """The start when none is given (n,), rad.

    The SRDF's ``home``/``default``/``ready`` state, a UR arm's ``UR_HOME``, else neutral.
    """
    import pinocchio as pin

    if checker.srdf is not None:
        model = pin.Model(checker.model)
        pin.loadReferenceConfigurations(model, str(checker.srdf), False)
        for name in SRDF_STATES:
            try:
                q_full = np.array(model.referenceConfigurations[name])
            except (KeyError, IndexError, TypeError):
                continue
            model = checker.model
            return q_full[[model.idx_qs[model.getJointId(n)] for n in robot.joint_names]]
    if tuple(robot.joint_names) == UR_JOINT_NAMES:
        return np.array(UR_HOME)
    return pin.neutral(robot.model)


def plan_excitation(
    robot: RobotModel,
    duration_s: float = MAX_DURATION_S,
    start: np.ndarray | None = None,
    settings: ExcitationSettings | None = None,
    seed: int = 0,
    srdf: str | None = None,
    progress: Callable[[str], None] | None = None,
) -> ExcitationMotion:
    """The excitation motion of ``duration_s`` seconds about ``start`` (see the module).

    Args:
        robot: the arm, with its URDF's collision geometry; gravity from its model.
        duration_s: length (s), ``MIN_DURATION_S`` to ``MAX_DURATION_S``.
        start: (n,) start and end configuration (rad); default ``default_start``.
        settings: tuning numbers; default ``ExcitationSettings()``.
        seed: random seed of the search.
        srdf: SRDF whose disabled collision pairs are not checked (see ``collision``).
        progress: called with a line of text at each stage, or None.

    Raises:
        InvalidInputError: a duration out of range, a start outside the limits, bad settings.
        CollisionError: the start collides or is below the floor, or no random motion is free.
        UnobservableError: fewer than ``MIN_JOINTS`` joints, or a motion of rank < 10.
        SolverError: every IPOPT refinement failed.
    """
    s = checked_settings(settings or ExcitationSettings())
    say = progress or (lambda _text: None)
    duration_s = validate.number(duration_s, "duration_s", low=MIN_DURATION_S, high=MAX_DURATION_S)
    if robot.nq < MIN_JOINTS:
        raise UnobservableError(
            f"the chain to {robot.ee_frame!r} has {robot.nq} joints: with fewer than "
            f"{MIN_JOINTS} the joint torques see only part of the payload's wrench, and its ten "
            "inertial parameters are not all observable (mass and CoM from static poses are)"
        )
    t0 = time.perf_counter()
    checker = SelfCollision(robot, srdf)
    start = default_start(robot, checker) if start is None else robot.check_q(start)
    lim = excitation_limits(robot, start, s)
    check_start(robot, checker, start, s)
    period_s = duration_s / s.periods
    scale = parameter_scale(s.typical_length_m)
    t = np.linspace(0.0, duration_s, int(round(duration_s / s.sample_period_s)) + 1)

    def is_free(series: FourierMotion, times: np.ndarray) -> bool:
        q = series.evaluate(times)[0]
        return all(feasible(robot, checker, qi, s.min_height_m) for qi in q)

    series, status = search(robot, start, period_s, lim, scale, s, seed, is_free, say)
    series = within_limits(series, t, lim)
    say(f"checking the motion at {len(t)} samples (limits, self-collision, floor)")
    if not is_free(series, t):
        raise CollisionError("the planned motion collides between the search's grid points")
    q, qd, qdd = series.evaluate(t)
    Y = payload_regressor(robot, q, qd, qdd)
    rank = np.linalg.matrix_rank(Y.reshape(-1, 10) * scale)
    if rank < 10:
        raise UnobservableError(f"the planned motion's regressor has rank {rank} < 10")
    heights = np.array([floor_heights(robot, qi) for qi in q])
    return ExcitationMotion(
        t=t, q=q, qd=qd, qdd=qdd, series=series, joint_names=tuple(robot.joint_names),
        ee_frame=robot.ee_frame, duration_s=duration_s,
        condition_number=condition_number(Y, scale), condition_number_si=condition_number(Y),
        parameter_scale=scale, velocity_limit=lim.velocity, acceleration_limit=lim.acceleration,
        q_lower=lim.lower, q_upper=lim.upper,
        peak_velocity_share=np.abs(qd).max(axis=0) / lim.velocity,
        peak_acceleration_share=np.abs(qdd).max(axis=0) / lim.acceleration,
        min_height_m=float(heights.min()), gravity=robot.model.gravity.linear.copy(),
        settings=s, solver_status=tuple(status), plan_time_s=time.perf_counter() - t0,
    )  # fmt: skip


def excitation_limits(robot: RobotModel, start: np.ndarray, s: ExcitationSettings) -> Limits:
    """The per-joint limits the motion keeps, from the URDF and the settings."""
    v_urdf = robot.model.velocityLimit
    bad = [n for n, v in zip(robot.joint_names, v_urdf) if not (0 < v < 1e10)]
    if bad:
        raise InvalidInputError(f"the URDF gives no velocity limit for the joints {bad}")
    n_wrist = min(s.wrist_joints, robot.nq)
    n_arm = robot.nq - n_wrist
    box = np.r_[np.full(n_arm, s.arm_range_rad), np.full(n_wrist, s.wrist_range_rad)]
    rate = np.r_[np.full(n_arm, s.arm_rate_scale), np.ones(n_wrist)]
    lower = np.maximum(robot.q_lower + s.position_margin_rad, start - box)
    upper = np.minimum(robot.q_upper - s.position_margin_rad, start + box)
    return Limits(lower, upper, rate * s.velocity_scale * v_urdf, rate * s.acceleration_limit)


def check_start(
    robot: RobotModel, checker: SelfCollision, start: np.ndarray, s: ExcitationSettings
) -> None:
    """Refuse a ``start`` (n,) that the motion cannot leave from.

    InvalidInputError: not ``position_margin_rad`` inside the joint limits. CollisionError:
    in self-collision, or with the wrist or ee below ``min_height_m``.
    """
    inside = robot.q_lower + s.position_margin_rad, robot.q_upper - s.position_margin_rad
    if np.any(start < inside[0]) or np.any(start > inside[1]):
        raise InvalidInputError(
            f"the start {np.round(start, 4).tolist()} is not {s.position_margin_rad} rad inside "
            f"the joint limits {robot.q_lower.tolist()} .. {robot.q_upper.tolist()}"
        )
    if not feasible(robot, checker, start, s.min_height_m):
        raise CollisionError(
            f"the start configuration collides ({checker.colliding_pairs(start)}) or puts the "
            f"wrist or ee below {s.min_height_m} m: give another --start"
        )


def within_limits(series: FourierMotion, t: np.ndarray, lim: Limits) -> FourierMotion:
    """``series`` scaled down about its start where a peak on ``t`` exceeds a limit.

    The search kept the limits on a coarser grid.
    """
    q, qd, qdd = series.evaluate(t)
    dq = q - series.q0
    with np.errstate(divide="ignore", invalid="ignore"):
        ratios = np.nan_to_num(
            np.vstack(
                [
                    dq / (lim.upper - series.q0),
                    dq / (lim.lower - series.q0),
                    np.abs(qd) / lim.velocity,
                    np.abs(qdd) / lim.acceleration,
                ]
            ),  # fmt: skip
            nan=0.0,
            posinf=np.inf,
        )
    worst = float(ratios.max())
    if worst <= 1.0:
        return series
    return FourierMotion(series.q0, series.a / worst, series.b / worst, series.period_s)
