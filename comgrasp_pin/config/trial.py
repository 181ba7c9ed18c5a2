"""The trial grasp's part of the config tree, and the procedure a real arm's sensors need.

``TrialConfig``, and ``hardware_trial`` (the realistic presets' procedure).

Re-exported by ``comgrasp_pin.config``; frozen dataclasses, SI units.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

from comgrasp_pin.errors import InvalidInputError

ESTIMATORS, TAU_BEFORE = ("lstsq", "ipopt"), ("measured", "model")


@dataclass(frozen=True)
class TrialConfig:
    """The trial grasp: grasp, lift, watch, measure.

    The grip force is ``MotionConfig.grip_force``, the same as every other grasp's.

    Attributes:
        lift_height: eelink height above the table at the measurement configuration (m).
        lift_time: duration of the lift to it (s); 0.41 m in 2.5 s peaks at 0.38 m/s^2,
            below the careful lift's test.
        roll_deg: roll about ee-x of the second measurement pose (deg); 0 measures at one
            pose only, as the paper does.
        empty_settle: the empty arm settles this long at a measurement pose (s).
        empty_first_last: measure the empty arm from the last measurement pose to the
            first, so that the first pose's empty window comes just before the grasp: the
            torque sensor then drifts over a shorter interval between the empty and the
            held window of the pose that matters most (benchmarks/drift_designs.py: 7 %
            less CoM error from drift on a 0.5 kg rod); False: the first pose first, as
            the paper.
        settle, window: hold time before averaging the torques, and averaging window (s).
        tau_before: "measured" (at the same configuration before grasping, as the paper)
            or "model" (RobotModel.gravity_torques).
        estimator: "ipopt" (the torque balance with the side view's prior on the CoM's
            distance from the rod's axis, ``procedures.measurement.axis_prior``) or
            "lstsq" (the closed form, no prior).
        return_time: from the lift to the first measurement pose (s).
        hold_before_measuring: the side camera watches the held rod this long (s).
        roll_time: move between the two measurement poses (s).
        max_depth_shift, max_depth_turn_deg: the most the grasp's compliance moves a held
            rod between two poses along the jaw axis (m) and out of their plane (deg); two
            views' depth lines that differ by more saw different parts of the handle and
            are not used (measured: 0.3-1.2 mm at the 1.7-2 N the rolled pose puts along
            the jaws); that motion is then taken as uniform within the bounds.
        roll_slip_deg: a tilt change above this between the two poses means the rod moved
            in the jaws (deg).
        still_turn_deg, still_attempts: a torque window during which the rod turned by
            more than this (deg; its creep is 0.1-0.5) is measured again, at most this
            many windows in all (the torques of a turning rod are not static).
        careful_lift: a careful trial grasp first lifts the rod this much (m) ...
        careful_lift_time: ... this briskly (s): its peak acceleration (10/sqrt(3) 0.04 /
            0.6^2 = 0.64 m/s^2) exceeds the lift's, so a grasp that passes holds through it;
        careful_hold: ... watches it this long (s) ...
        careful_abort_deg: ... and puts it back if it turned more than this (deg).
        careful_release_time: lowering time of that put-back (s).
        heavy_side_min_deg: a tilt below this tells nothing about which end is heavy (deg).
        approach_deg, approach_time: reach each measurement pose by way of the pose plus
            this much in every joint (deg), the last this long (s), so that every joint
            comes to rest moving the same way before and after the grasp (a current-based
            reading's friction then cancels; ``procedures.trial_steps.arrive``); 0: straight.
        window_sem, window_max: average on until every joint's measured standard error is
            below this (N m; 0: the fixed ``window``), the window at most this long (s).
        look_attempts, look_period: a side view refused as untrusted (a real camera's
            noise and holes, ``UntrustedImageError``) is taken again, this many frames in
            all, this far apart (s; a camera's frame period).
        put_back_margin, put_back_time: a rod the side camera cannot measure is laid back
            where it was grasped, let go this far above the table at its lower end (m),
            after lowering for this long (s) (``procedures.put_back``).
        torque_std_from: the averaged readings' std for the estimator: "spec" (the
            sensor's white noise over the samples) or "measured" (their spread, and the
            sensor's drift over the time between the empty and the held windows, as a full
            covariance of the poses' differences, which share drift where their intervals
            overlap; ``procedures.com_location.pair_noise``; the estimator then solves the
            generalised least squares).
    """

    lift_height: float = 0.45
    lift_time: float = 2.5
    roll_deg: float = 20.0
    empty_settle: float = 0.1
    empty_first_last: bool = False
    settle: float = 0.5
    window: float = 1.0
    tau_before: str = "measured"
    estimator: str = "ipopt"
    return_time: float = 0.3
    hold_before_measuring: float = 0.5
    roll_time: float = 1.0
    roll_slip_deg: float = 0.5
    still_turn_deg: float = 1.0
    still_attempts: int = 3
    max_depth_shift: float = 0.002
    max_depth_turn_deg: float = 2.0
    careful_lift: float = 0.04
    careful_lift_time: float = 0.6
    careful_hold: float = 0.3
    careful_abort_deg: float = 3.0
    careful_release_time: float = 0.1
    heavy_side_min_deg: float = 2.0
    approach_deg: float = 0.0
    approach_time: float = 1.0
    window_sem: float = 0.0
    window_max: float = 4.0
    torque_std_from: str = "spec"
    look_attempts: int = 5
    put_back_margin: float = 0.01
    put_back_time: float = 2.0
    look_period: float = 1.0 / 30.0

    def __post_init__(self) -> None:
        if self.torque_std_from not in ("spec", "measured"):
            raise InvalidInputError(
                f"torque_std_from must be 'spec' or 'measured', not {self.torque_std_from!r}"
            )
        if self.estimator not in ESTIMATORS:
            raise InvalidInputError(
                f"estimator must be one of {ESTIMATORS}, not {self.estimator!r}"
            )
        if self.tau_before not in TAU_BEFORE:
            raise InvalidInputError(
                f"tau_before must be one of {TAU_BEFORE}, not {self.tau_before!r}"
            )


def hardware_trial(trial: TrialConfig) -> TrialConfig:
    """``trial`` measured as a real arm needs (the realistic presets' procedure).

    Each measurement pose reached by way of the pose plus 1 deg in every joint, the last
    1 s (at up to 0.03 rad/s every joint moves above a drive's stiction speed, and comes to
    rest moving the same way before and after the grasp; 3 deg in 0.5 s shook near-slip
    grasps: of 18 accuracy grasps 3 fell and 6 turned by 20-60 deg more than without);
    windows averaged on until each joint's measured standard error is below 3 mN m, 4 s at
    most (a 0.1 N m current reading at 500 Hz needs 2.2 s; a 0.05 N m torque sensor's 1 s
    is enough); the estimator's noise from the windows' spread and the sensor's drift
    (its correlation across poses and windows included: ``procedures.com_location.pair_noise``);
    the empty arm measured at the first pose last (``empty_first_last``).
    """
    return replace(trial, approach_deg=1.0, approach_time=1.0, window_sem=0.003,
                   window_max=4.0, torque_std_from="measured",
                   empty_first_last=True)  # fmt: skip
