"""A planned motion played on a simulated arm holding a payload: the log a robot would record.

``simulate_motion`` drives a bare arm (``arm_worlds``) along a joint trajectory with a
torque-controlled servo and returns what the robot reports, as a ``JointLog``: positions,
velocities and joint torques with the sensors' errors, at ``rate_hz``. The same call with
``payload=None`` is the empty-arm run of the same motion.

- The servo is computed torque on the *empty* arm's model (Pinocchio's, what a controller
  knows): tau = M(q) (qdd_d + Kp e + Kd de) + b(q, qd), the gains of a critically damped
  loop at ``servo_hz``. The payload and the joint friction are not compensated: the PD
  absorbs them (a few mrad of tracking error).
- The drive applies tau (MuJoCo ``qfrc_applied``): an ideal torque source standing after the
  gear's friction. A link-side sensor (``TorqueSensorConfig.kind == "link"``) reads this
  torque: what the link and the friction between sensor and link (``arm_worlds``) take,
  i.e. M qdd + b + friction, never the gear's friction. A current-based sensor ("current")
  adds its own drive friction to it (``torque_sensor``).
- Positions are the simulator's with encoder noise; velocities are the simulator's with the
  noise of a drive's velocity estimate (``position_std``, ``velocity_std``).
- The arm rests ``rest_s`` at the first configuration before the motion and at the last one
  after it: static windows for a static estimate and for the sensor's offsets.

Two runs of one session (empty, then holding the payload) share the torque sensor's offsets
when given the same ``offsets_seed``; give them different ``seed``s for independent noise.

With ``wrench`` (a ``WrenchSensorConfig``) the run also returns what the wrist sensor at
``arm_worlds.SENSOR_FRAME[arm]`` read, as a ``WrenchLog``: MuJoCo's force and torque at that
site over the same motion, with the sensor's errors (``wrench_sensor``, its own random
streams: the joint log is the same with or without it), at the sensor's rate, beside the
joint log's positions, velocities and efforts at those times.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np
import pinocchio as pin
from scipy.interpolate import CubicHermiteSpline

from comgrasp_pin.config import TorqueSensorConfig, WrenchSensorConfig, sensor_preset
from comgrasp_pin.errors import InvalidInputError, UnstablePhysicsError
from comgrasp_pin.robot_io.log_files.joint_readers import JointLog
from comgrasp_pin.robot_io.log_files.log_types import WrenchLog
from comgrasp_pin.simulation.arm_worlds import SENSOR_FRAME, SIM_DT, arm_robot, arm_world
from comgrasp_pin.simulation.payloads import Payload
from comgrasp_pin.simulation.torque_sensor import make_torque_sensor
from comgrasp_pin.simulation.world import FT_SENSORS
from comgrasp_pin.simulation.wrench_sensor import WrenchSensor, wrench_from_sensors


@dataclass(frozen=True)
class MotionSimConfig:
    """Servo, timing and encoder settings of a simulated motion (SI units).

    Attributes:
        servo_hz: natural frequency of the computed-torque loop (Hz); Kp = (2 pi f)^2,
            Kd = 2 zeta (2 pi f).
        damping_ratio: zeta of the loop.
        rest_s: seconds at rest before and after the motion.
        position_std: white noise on each logged position (rad): a 19-20 bit encoder.
        velocity_std: white noise on each logged velocity (rad/s): a drive's filtered
            estimate (assumed).
        max_tracking_error: a run whose servo error exceeds this (rad) is refused.
        timestep_s: MuJoCo's step (s); the log's rate must divide 1 / timestep_s.
    """

    servo_hz: float = 30.0
    damping_ratio: float = 1.0
    rest_s: float = 3.0
    position_std: float = 2e-5
    velocity_std: float = 2e-3
    max_tracking_error: float = 0.05
    timestep_s: float = SIM_DT


def simulate_motion(
    arm: str,
    payload: Payload | None,
    t: np.ndarray,
    q: np.ndarray,
    qd: np.ndarray,
    qdd: np.ndarray,
    sensor: TorqueSensorConfig | None = None,
    rate_hz: float = 500.0,
    seed: int = 0,
    offsets_seed: int | None = None,
    config: MotionSimConfig | None = None,
    wrench: WrenchSensorConfig | None = None,
) -> JointLog | tuple[JointLog, WrenchLog]:
    """Play the trajectory (t, q, qd, qdd) on ``arm`` holding ``payload`` (None: empty).

    Args:
        arm: "ur5" or "panda" (``arm_worlds.ARMS``).
        payload: the body held in the ee frame, or None for the empty-arm run.
        t: (N,) increasing times (s) of the desired trajectory, sampled densely enough for
            cubic Hermite interpolation (100 Hz or more for a smooth motion).
        q, qd, qdd: (N, n) desired positions (rad), velocities (rad/s) and accelerations
            (rad/s^2), in the order of ``arm_robot(arm).joint_names``; at rest at both ends.
        sensor: the torque sensor's error model; default the "realistic" preset's.
        rate_hz: the log's sample rate (Hz); the simulation's rate (1 kHz) must be a whole
            multiple of it.
        seed: the run's noise (encoders, torque noise and drift).
        offsets_seed: the torque sensor's per-joint offsets are those of
            ``make_torque_sensor(n, sensor, offsets_seed)`` (default: ``seed``).
        config: servo, rest and encoder settings.
        wrench: the wrist sensor's error model, or None for no wrench log. Its rate must
            divide ``rate_hz``; its noise and drift are seeded by ``seed``.

    Returns:
        The log: time (s, from 0; the motion starts at ``config.rest_s``), the arm's joint
        names, position, effort (the torque sensor's readings, N m) and velocity. With
        ``wrench``, (that log, the wrench log): every k-th of its samples (k = rate_hz /
        wrench.rate_hz; the same positions, velocities and efforts) with the wrist sensor's
        readings (sensor frame ``SENSOR_FRAME[arm]``, the tool's wrench on the sensor).

    Raises:
        InvalidInputError: unknown arm, shapes, a trajectory outside the joint limits or
            that does not start and end at rest, a rate that does not divide the
            simulation's.
        UnstablePhysicsError: the servo lost track of the motion (``max_tracking_error``).
    """
    config = config or MotionSimConfig()
    sensor = sensor or sensor_preset("realistic").torque
    model, names, _ = arm_world(arm, payload)
    model.opt.timestep = config.timestep_s
    robot = arm_robot(arm)
    t, q, qd, qdd = _check_trajectory(t, q, qd, qdd, robot)
    dt = model.opt.timestep
    every = _stride(rate_hz, 1.0 / dt, "rate_hz", "the simulation's")
    if wrench is not None:
        _stride(wrench.rate_hz, rate_hz, "the wrist sensor's rate_hz", "the log's")
    times = np.arange(round((t[-1] - t[0] + 2 * config.rest_s) / dt) + 1) * dt
    q_d, qd_d, qdd_d = motion_reference(times, t, q, qd, qdd, config.rest_s)
    q_log, qd_log, tau_log, ft_log = _servo(model, robot, q_d, qd_d, qdd_d, every, config)

    error = np.abs(q_log - q_d[::every]).max(axis=0)
    if not np.all(np.isfinite(q_log)) or error.max() > config.max_tracking_error:
        raise UnstablePhysicsError(
            f"the servo lost track of the motion on {arm}: largest errors {error} rad per "
            f"joint exceed {config.max_tracking_error} rad (a trajectory beyond the arm's "
            "torque, or a payload too heavy for the servo's gains)"
        )
    rng = np.random.default_rng((seed, 7))  # apart from the torque sensor's own streams
    torque_sensor = make_torque_sensor(robot.nq, sensor, seed)
    if offsets_seed is not None:
        torque_sensor.offsets = make_torque_sensor(robot.nq, sensor, offsets_seed).offsets
    effort = torque_sensor.read_many(tau_log, every * dt, qd_log)
    position = q_log + config.position_std * rng.standard_normal(q_log.shape)
    velocity = qd_log + config.velocity_std * rng.standard_normal(qd_log.shape)
    source = f"mujoco:{arm}:{'empty' if payload is None else payload.name}"
    log = JointLog(times[::every], names, position, effort, source, velocity)
    if wrench is None:
        return log
    return log, _wrench_log(log, ft_log, wrench, rate_hz, SENSOR_FRAME[arm], seed)


def _wrench_log(log: JointLog, ft_log: np.ndarray, wrench: WrenchSensorConfig,
                rate_hz: float, sensor_frame: str, seed: int) -> WrenchLog:  # fmt: skip
    """The wrist sensor's log beside ``log`` (sampled at ``rate_hz``): its every k-th sample
    (k = rate_hz / wrench.rate_hz), the readings formed from MuJoCo's ``ft_log`` (N, 6)."""
    rows = slice(None, None, _stride(wrench.rate_hz, rate_hz, "rate_hz", "the log's"))
    truth = wrench_from_sensors(ft_log[rows])
    readings = WrenchSensor(wrench, seed).read(np.arange(len(truth)), truth)
    velocity = None if log.velocity is None else log.velocity[rows]
    return WrenchLog(log.time[rows], log.joint_names, log.position[rows], readings,
                     sensor_frame, log.source, velocity, log.effort[rows])  # fmt: skip


def _stride(rate: float, base_hz: float, what: str, base: str) -> int:
    """How many samples at ``base_hz`` one sample at ``rate`` (Hz) spans.

    Raises:
        InvalidInputError: ``rate`` does not divide ``base_hz``.
    """
    k = round(base_hz / rate) if rate > 0 else 0
    if k < 1 or abs(k * rate - base_hz) > 1e-9 * base_hz:
        raise InvalidInputError(f"{what} must divide {base} {base_hz:g} Hz; got {rate}")
    return k


def motion_reference(
    times: np.ndarray, t: np.ndarray, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray,
    rest_s: float,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:  # fmt: skip
    """The servo's set points at ``times`` (s) of a log whose motion starts at ``rest_s``:
    (q_d, qd_d, qdd_d), each (len(times), n); at rest at the ends before and after the
    motion. Positions and velocities by cubic Hermite interpolation of (q, qd),
    accelerations linearly."""
    s = np.clip(np.asarray(times, float) - rest_s + t[0], t[0], t[-1])
    spline = CubicHermiteSpline(t, q, qd, axis=0)
    qdd_d = np.column_stack([np.interp(s, t, a) for a in qdd.T])
    return spline(s), spline(s, 1), qdd_d


def _servo(model, robot, q_d, qd_d, qdd_d, every: int, config: MotionSimConfig):
    """Step the arm along the set points; (q, qd, tau, ft) at every ``every``-th step, each
    (steps // every + 1, n): the state before the step, the torque applied over it, and
    the wrist sensor's MuJoCo readings (6: force, torque) in that state.
    The model's qpos and qvel are the arm's joints in ``robot``'s order (``arm_world``)."""
    data = mujoco.MjData(model)
    data.qpos[:] = q_d[0]
    omega = 2 * np.pi * config.servo_hz
    kp, kd = omega**2, 2 * config.damping_ratio * omega
    n_samples = (len(q_d) - 1) // every + 1
    q_log, qd_log, tau_log = (np.empty((n_samples, robot.nq)) for _ in range(3))
    ft_log = np.empty((n_samples, 6))
    adr = model.sensor(FT_SENSORS[0]).adr[0]
    ft = data.sensordata[adr : adr + 6]  # force then torque (added one after the other)
    for k in range(len(q_d)):
        qk, vk = data.qpos.copy(), data.qvel.copy()
        a_servo = qdd_d[k] + kp * (q_d[k] - qk) + kd * (qd_d[k] - vk)
        tau = pin.rnea(robot.model, robot.data, qk, vk, a_servo)  # M a + b of the empty arm
        data.qfrc_applied[:] = tau
        if k % every == 0:
            i = k // every
            q_log[i], qd_log[i], tau_log[i] = qk, vk, tau
        mujoco.mj_step(model, data)
        if k % every == 0:
            ft_log[k // every] = ft  # computed in the step's forward pass, before integrating
    return q_log, qd_log, tau_log, ft_log


def _check_trajectory(t, q, qd, qdd, robot):
    """The trajectory as float arrays, checked: shapes, finite, increasing, within the
    robot's joint limits, at rest at both ends."""
    n = robot.nq
    t = np.asarray(t, dtype=float)
    arrays = [np.asarray(x, dtype=float) for x in (q, qd, qdd)]
    if t.ndim != 1 or len(t) < 2 or any(x.shape != (len(t), n) for x in arrays):
        raise InvalidInputError(
            f"t must be (N,) and q, qd, qdd (N, {n}); got {t.shape} and {[x.shape for x in arrays]}"
        )
    if not all(np.all(np.isfinite(x)) for x in (t, *arrays)) or np.any(np.diff(t) <= 0):
        raise InvalidInputError("the trajectory must be finite with strictly increasing t")
    outside = (arrays[0] < robot.q_lower) | (arrays[0] > robot.q_upper)
    if np.any(outside):
        joints = [robot.joint_names[j] for j in np.flatnonzero(outside.any(axis=0))]
        raise InvalidInputError(f"the trajectory leaves the joint limits of {joints}")
    ends = np.abs(arrays[1][[0, -1]]).max()
    if ends > 1e-6:
        raise InvalidInputError(
            f"the trajectory must start and end at rest: |qd| reaches {ends:.3g} rad/s at an end"
        )
    return t, *arrays
