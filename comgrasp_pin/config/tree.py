"""The config tree: every number that tunes a run, nested (frozen dataclasses, SI units).

    EpisodeConfig
      trial:   TrialConfig     the trial grasp and its torque measurement
      regrasp: RegraspConfig   when to regrasp, how to retry, how to put the rod down
      motion:  MotionConfig    the skills: speeds, approach, gripper, carrying
      sensors: SensorConfig    torque sensor, depth cameras' errors, model error, the watch
                               (``config.sensors``: presets "ideal", "realistic", ...)
      world:   WorldConfig     the simulated world (physics, contacts, servo)

Skills and procedures take their numbers from this tree only (no defaults of their own), and
``run.json`` records it whole (``dataclasses.asdict``). Workcell geometry (table, drop box,
poses) is not tuning: it lives in ``sim/scene.xml`` and is read by ``comgrasp_pin.workcell``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from comgrasp_pin.config.sensors import SensorConfig
from comgrasp_pin.config.trial import TrialConfig

__all__ = ["EpisodeConfig", "MotionConfig", "RegraspConfig", "WorldConfig"]


@dataclass(frozen=True)
class WorldConfig:
    """Settings of the simulated world. SI units.

    Attributes:
        sim_dt: physics time step (s); the servo and the torque sensor run every step:
            2 ms is the 500 Hz of a UR5's real-time interface (grasps hold, turn and drop
            alike at 1 ms, checked by tests/test_grasp_physics.py).
        kp: stiffness of the arm's position servos (N m / rad).
        dampratio: damping ratio of the arm servos.
        servo_ki: integral rate of the servo (1/s): closes a static error in about 1/ki s.
        servo_tau_i_limit: anti-windup bound on the servo's integral term (N m).
        armature: reflected rotor inertia of each arm joint (kg m^2); it changes no static
            torque, it only makes the stiff servos well-behaved at ``sim_dt``.
        finger_armature: reflected inertia of each finger drive (kg).
        pad_friction: (sliding, torsional, rolling) friction of the finger pads.
            0.8: rubber pad on wood or steel. Torsional 0.002 m: the soft-finger patch of a
            pad on a rod (radius a of a few mm, mu_t ~ (2/3) mu a). Rolling 1e-4 m (unused
            with condim 4). With the box pads' two edge contacts (+-12 mm along the rod) a
            grasp resists a moment about the jaw axis of about 2 F (0.8 * 0.012 + 0.002)
            = 0.023 N m per N of grip force (``planning.holding``): 0.35 N m at 15 N, below
            m g l / 4 of every object (0.44-1.6 N m), so a centre grasp of a rod whose CoM
            is a quarter length off tilts while a CoM grasp holds.
        pad_condim: contact dimensionality of the pads: 4 (sliding + torsional friction).
        noslip_iterations, impratio: MuJoCo solver settings that make static friction hold
            (without noslip a rod held at its friction limit creeps by about 12 deg/s; with
            50 iterations by < 1 deg/s). The elliptic cone is set in sim/scene.xml.
        side_camera_fovy_deg: vertical field of view of the side camera (deg).
        settle_time: the rod settles on the table this long after the world is built (s).
    """

    sim_dt: float = 0.002
    kp: float = 2.0e4
    dampratio: float = 1.0
    servo_ki: float = 20.0
    servo_tau_i_limit: float = 50.0
    armature: tuple[float, ...] = (0.2, 0.2, 0.1, 0.05, 0.05, 0.05)
    finger_armature: float = 0.05
    pad_friction: tuple[float, float, float] = (0.8, 0.002, 0.0001)
    pad_condim: int = 4
    noslip_iterations: int = 50
    impratio: float = 10.0
    side_camera_fovy_deg: float = 75.0
    settle_time: float = 0.3


@dataclass(frozen=True)
class MotionConfig:
    """The skills' numbers: speeds, the grasp approach, the gripper, carrying and placing.

    Attributes:
        grip_force: force of each finger in every grasp (N); 15 N makes an off-CoM grasp
            tilt and a CoM grasp hold (see WorldConfig.pad_friction).
        carry_lift_height, carry_lift_time: a grasp that carries the rod away (the baseline's,
            the regrasp at the CoM) lifts the eelink this high above the table (m) in this
            time (s); the trial grasp lifts to ``TrialConfig.lift_height`` instead.
        v_max_holding, a_max_holding: joint speed and acceleration limits while the jaws
            grip (rad/s, rad/s^2): a third of the UR5's 3.15 rad/s, gentle on a held rod.
        v_max_empty, a_max_empty: the same with the jaws open (two thirds of the UR5's).
        approach: a grasp is approached from this far above it (m) ...
        approach_settle: ... where the arm settles this long (s) ...
        descend_time: ... then descends in a straight line in this time (s) ...
        grasp_pause: ... and waits this long before closing (s).
        ik_dt: straight-line moves solve IK every ik_dt seconds (s).
        open_force: force that opens the fingers (N).
        contact_force: gentle force while the jaws close onto the object (N per finger).
        close_ramp: then the force ramps to the grip force over this time (s).
        close_timeout: longest wait for the fingers to stop (s).
        still_speed, still_time: the fingers count as stopped below this speed (m/s)
            for this long (s).
        open_time: waiting time after opening the jaws (s).
        release_time: waiting time after opening the jaws to release an object (s).
        retreat, retreat_time: after a release the jaws rise this much (m) in this time (s).
        place_time: lowering time of a place (s).
        carry_height: height of the jaws above the drop box floor while carrying (m).
        carry_settle: the arm settles this long above the box (s).
        release_height: height of the jaws above the box floor at the release (m).
        park_rest: after parking with the rod delivered, the world runs this long (s).
    """

    grip_force: float = 15.0
    carry_lift_height: float = 0.30
    carry_lift_time: float = 1.0
    v_max_holding: float = 1.0
    a_max_holding: float = 2.0
    v_max_empty: float = 2.0
    a_max_empty: float = 6.0
    approach: float = 0.15
    approach_settle: float = 0.1
    descend_time: float = 1.0
    grasp_pause: float = 0.1
    ik_dt: float = 0.02
    open_force: float = 10.0
    contact_force: float = 2.0
    close_ramp: float = 0.1
    close_timeout: float = 1.5
    still_speed: float = 1e-3
    still_time: float = 0.03
    open_time: float = 0.3
    release_time: float = 0.4
    retreat: float = 0.15
    retreat_time: float = 0.6
    place_time: float = 1.0
    carry_height: float = 0.30
    carry_settle: float = 0.1
    release_height: float = 0.12
    park_rest: float = 0.3


@dataclass(frozen=True)
class RegraspConfig:
    """When to regrasp, how to retry a trial grasp, and how to put a rod down.

    Attributes:
        slip_tilt_deg: a tilt in the jaws above this (deg) counts as slip seen.
        max_com_offset: a CoM farther than this from the grasp point along the rod (m) is
            regrasped even without slip (the transport's accelerations add load).
        holding_margin: a CoM known to a 95 % interval within this share of the jaws'
            holding lever is good enough to regrasp at (``needs_another_pose``); beyond it
            the trial grasp measures one more pose first.
        pad_friction: (sliding, torsional) friction of the pads as the robot knows them
            (its gripper's data; the simulated world has its own, ``WorldConfig``).
        extra_rolls_deg: the candidate rolls about ee-x of that one more pose (deg); the
            D-optimal one (``planning.wrist_poses.best_next_pose``) is measured.
        attempts: careful trial grasps before the last, uncareful one.
        retry_shift: a turning rod is grasped again this fraction of its length further
            towards the end that went down (then bisected).
        rest_time: after a failed attempt the rod comes to rest this long (s).
        put_down_v_max, put_down_a_max: joint limits carrying a rod to be put down
            (rad/s, rad/s^2): the rod may be held near its slip limit.
        put_down_settle: the arm settles above the put-down spot this long (s).
        touch_clearance: the rod's low end is lowered to this far above the height the
            jaws end at when the rod lies flat (m).
        pad_clearance: the jaws stop this far above a lying rod's axis (m).
        descend_time: lowering to the touch (s): 0.4 m in 3 s peaks at 0.27 m/s^2.
        pivot_grip: force of each finger while the rod pivots on its low end (N).
        lay_time: the pivot that lays the rod flat (s).
        rest_after_put_down: the rod comes to rest this long before it is looked at (s).
        put_back_margin: a rod laid back when the side view cannot measure it
            (``procedures.put_back``) is aimed to lie with its ends at least this far inside
            the pick area (m): the top view measures the table's plane 1 cm inside its edge.
        min_seen_share: a rod seen whole before that now runs out of the top camera's view
            at one end (laid back or dropped at the view's edge) is completed with its
            known length and grasped when at least this share of it is in view (its
            centre and a grasp either side of it seen); less is refused.
        length_tolerance: a rod seen again whole but shorter than its first view by more
            than this (m) is refused: part of it is out of sight (the realistic top view's
            length is within 8 mm).
    """

    slip_tilt_deg: float = 2.0
    max_com_offset: float = 0.015
    holding_margin: float = 0.5
    pad_friction: tuple[float, float] = (0.8, 0.002)
    extra_rolls_deg: tuple[float, ...] = (-20.0, -30.0, 30.0)
    attempts: int = 4
    retry_shift: float = 0.15
    rest_time: float = 0.5
    put_down_v_max: float = 0.5
    put_down_a_max: float = 0.5
    put_down_settle: float = 0.2
    touch_clearance: float = 0.01
    pad_clearance: float = 0.003
    descend_time: float = 3.0
    pivot_grip: float = 4.0
    lay_time: float = 2.0
    rest_after_put_down: float = 0.5
    put_back_margin: float = 0.03
    min_seen_share: float = 0.6
    length_tolerance: float = 0.03


@dataclass(frozen=True)
class EpisodeConfig:
    """The whole tree (see the module docstring); ``asdict`` of it is a run's record."""

    trial: TrialConfig = field(default_factory=TrialConfig)
    regrasp: RegraspConfig = field(default_factory=RegraspConfig)
    motion: MotionConfig = field(default_factory=MotionConfig)
    sensors: SensorConfig = field(default_factory=SensorConfig)
    world: WorldConfig = field(default_factory=WorldConfig)
