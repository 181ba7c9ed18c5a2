"""A wrist sensor's wrench over a motion: a linear system in the payload's ten parameters.

The tool side (gripper and payload, one rigid body beyond the sensor) needs the wrench
Phi(v_s, a_s - g_s) pi_s from the sensor to move as it does (Newton-Euler at the sensor frame
s, Pinocchio's ``bodyRegressor``: v_s, a_s the frame's spatial velocity and acceleration,
g_s the model's gravity, all in s; pi_s its parameters about s's origin in s's axes, order
m, m c, Ixx, Ixy, Iyy, Ixz, Iyz, Izz). It applies the opposite to the sensor, which is what a
``WrenchLog`` holds; per kept sample

    wrench_s(t) = -Phi(v_s, a_s - g_s) X pi_ee + bias + drift(t) - d dwrench_s/dt

with pi_ee the body's parameters in the ee frame (``params_map``: X = the parameters moved
from the ee frame to the sensor's, which must be rigidly joined), per axis a bias and its
drift over the motion (the joint path's Legendre polynomials, ``motion_system``), and one
delay d (s) of the wrench behind the positions (``motion_system.delay_column``). The wrench
goes through the joint path's zero-phase filter (it rides as the efforts of a ``JointLog``),
and Phi is computed on the differentiated signals and low-passed by the same filter
(``motion_system``: parallel filtering, so filter(wrench) = filter(Phi) X pi holds exactly).

The tool's part (``tool_of``): its parameters fitted from an empty run, given, or
``nominal_tool``: the URDF's links beyond the sensor frame, the last resort for the tool's
own wrench. ``observable``: a motion that does not determine the parameters, said in its
own terms (which joints barely move, how far gravity turns in the sensor frame).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from comgrasp_pin import validate
from comgrasp_pin.errors import InvalidInputError, UnobservableError
from comgrasp_pin.robot import RobotModel
from comgrasp_pin.robot_io.at_rest.wrench_static import tool_beyond
from comgrasp_pin.robot_io.from_motion.dynamic_fit import error_sources
from comgrasp_pin.robot_io.from_motion.motion_signals import (
    MIN_PEAK_SPEED,
    MotionSamples,
    motion_samples,
)
from comgrasp_pin.robot_io.from_motion.motion_system import (
    delay_column,
    fast_signals,
    joint_columns,
    lowpassed,
    offset_columns,
    row_noise,
)
from comgrasp_pin.robot_io.log_files.log_types import JointLog, WrenchLog
from comgrasp_pin.robot_io.payload_files.payload import T_flange_ee
from comgrasp_pin.robot_io.results.estimate_result import TOOL_EMPTY_RUN, TOOL_GIVEN, TOOL_NOMINAL

AXES = ("force_x", "force_y", "force_z", "torque_x", "torque_y", "torque_z")
"""The wrench's six rows per sample, in ``WrenchLog.wrench``'s column order (N, N m)."""

_LOCAL = pin.ReferenceFrame.LOCAL


@dataclass(frozen=True)
class WrenchSystem:
    """A log's wrench rows: ``b = A_pi pi_ee + A_x x`` (rows sample-major, 6 per sample).

    Attributes:
        S: the kept samples (``motion_samples``); ``S.tau`` is the filtered wrench (k, 6).
        A_pi: (k, 6, 10) the wrench per unit of each of the ee frame's parameters.
        b: (k, 6) the wrench as measured, filtered (N, N m).
        A_x: (6 k, e) the bias (6), its drift (6 per degree) and the delay (1).
        sensor_frame: the URDF frame the wrench is measured in.
        T_sensor_ee: the ee frame's pose in the sensor frame (fixed).
    """

    S: MotionSamples
    A_pi: np.ndarray
    b: np.ndarray
    A_x: np.ndarray
    sensor_frame: str
    T_sensor_ee: pin.SE3


def as_joint_log(log: WrenchLog, which: str) -> JointLog:
    """``log`` as a JointLog, its wrench or its joint torques in the efforts' place.

    ``which="wrench"``: the wrench, filtered like efforts; ``"effort"``: the joint torques.
    """
    effort = log.wrench if which == "wrench" else log.effort
    if effort is None:
        raise InvalidInputError(f"{log.source or 'the wrench log'} holds no joint torques")
    return JointLog(log.time, tuple(log.joint_names), log.position, effort, log.source,
                    log.velocity)  # fmt: skip


def sensor_placement(robot: RobotModel, sensor_frame: str) -> tuple[int, pin.SE3]:
    """(the sensor frame's id in ``robot.model``, T_sensor_ee).

    Raises:
        InvalidInputError: the frame is not in the URDF, or it does not move rigidly with the
            ee frame (``payload.T_flange_ee``).
    """
    T_sensor_ee = pin.SE3(T_flange_ee(robot, sensor_frame))
    return robot.model.getFrameId(sensor_frame), T_sensor_ee


def params_map(T_a_b: pin.SE3) -> np.ndarray:
    """(10, 10) X with pi_a = X pi_b: a body's parameters moved from frame b to frame a.

    pi_b about b's origin in b's axes, pi_a about a's in a's; the map is Pinocchio's
    ``SE3.act`` on an ``Inertia``, which is linear in the parameters.
    """
    base = np.array([1.0, 0, 0, 0, 1, 0, 1, 0, 0, 1])  # 1 kg at the origin: any m > 0 will do

    def moved(p):
        return T_a_b.act(pin.Inertia.FromDynamicParameters(p)).toDynamicParameters()

    p0 = moved(base)
    return np.column_stack([moved(base + e) - p0 for e in np.eye(10)])


def sensor_regressor(robot: RobotModel, sensor_id: int, F: MotionSamples) -> np.ndarray:
    """(K, 6, 10) Phi(v_s, a_s - g_s) at the samples of ``F``.

    The wrench the sensor applies to a body held in its frame, per unit of the body's
    parameters about the sensor frame (Pinocchio's ``bodyRegressor``).
    """
    model, data = robot.model, robot.data
    out = np.empty((len(F.t), 6, 10))
    for i, (q, qd, qdd) in enumerate(zip(F.q, F.qd, F.qdd)):
        pin.forwardKinematics(model, data, q, qd, qdd)
        M_world_s = pin.updateFramePlacement(model, data, sensor_id)
        v = pin.getFrameVelocity(model, data, sensor_id, _LOCAL)
        a = pin.getFrameAcceleration(model, data, sensor_id, _LOCAL)
        out[i] = pin.bodyRegressor(v, a - M_world_s.actInv(model.gravity))
    return out


def gravity_in_sensor(robot: RobotModel, sensor_id: int, Q: np.ndarray) -> np.ndarray:
    """(k, 3) the model's gravity in the sensor frame at configurations ``Q`` (m/s^2)."""
    model, data = robot.model, robot.data
    out = np.empty((len(Q), 3))
    for i, q in enumerate(Q):
        pin.forwardKinematics(model, data, q)
        out[i] = pin.updateFramePlacement(model, data, sensor_id).rotation.T @ model.gravity.linear
    return out


def wrench_system(
    robot: RobotModel,
    log: WrenchLog,
    window: tuple[float, float] | None,
    cutoff_hz: float,
    crop: bool = False,
) -> WrenchSystem:
    """The wrench rows of ``log`` (``window`` and ``crop`` as ``motion_samples``).

    Raises:
        InvalidInputError: the sensor frame (``sensor_placement``).
        MotionLogError: the log is too short, still, jerky, at a joint limit, with gaps.
    """
    sid, T_sensor_ee = sensor_placement(robot, log.sensor_frame)
    as_efforts = as_joint_log(log, "wrench")
    S = motion_samples(robot, as_efforts, window, cutoff_hz, crop=crop)
    fast = fast_signals(robot, as_efforts, window, cutoff_hz)
    Phi = lowpassed(fast, cutoff_hz, lambda F: sensor_regressor(robot, sid, F), S.t)
    A_pi = -np.einsum("kri,ij->krj", Phi, params_map(T_sensor_ee))
    k = len(S.t)
    per_axis = [np.repeat(c[:, :1], 6, axis=1) for c in offset_columns(S)]  # bias, drift
    A_x = np.column_stack([joint_columns(per_axis), delay_column(fast, S)])
    return WrenchSystem(S, A_pi, S.tau.reshape(k, 6), A_x, log.sensor_frame, T_sensor_ee)


def nominal_tool(robot: RobotModel, sensor_frame: str) -> np.ndarray:
    """(10,) the URDF's links beyond ``sensor_frame`` as one body's parameters, ee frame.

    The links are ``wrench_static.tool_beyond``'s.
    """
    _, T_sensor_ee = sensor_placement(robot, sensor_frame)
    return T_sensor_ee.actInv(tool_beyond(robot, sensor_frame)).toDynamicParameters()


@dataclass(frozen=True)
class Tool:
    """The tool beyond the sensor: its parameters (ee frame), their covariance, their source."""

    params: np.ndarray  # (10,) ee frame
    cov: np.ndarray  # (10, 10)
    source: str


def tool_of(robot, log, empty_log, empty_window, cutoff_hz, tool_params, tool_cov) -> Tool:
    """The tool's parameters beyond the sensor (ee frame) and their covariance."""
    if empty_log is not None and tool_params is not None:
        raise InvalidInputError("give an empty run or the tool's parameters, not both")
    if tool_params is not None:
        p = validate.real_array(tool_params, "tool_params")
        c = np.zeros((10, 10)) if tool_cov is None else validate.real_array(tool_cov, "tool_cov")
        if p.shape != (10,) or c.shape != (10, 10) or not np.all(np.isfinite(c)):
            raise InvalidInputError(
                f"tool_params must be (10,) (m, m c, I at the ee origin) and tool_cov (10, 10), "
                f"finite; got shapes {p.shape} and {c.shape}"
            )
        return Tool(p, 0.5 * (c + c.T), TOOL_GIVEN)
    if empty_log is None:
        return Tool(nominal_tool(robot, log.sensor_frame), np.zeros((10, 10)), TOOL_NOMINAL)
    if empty_log.sensor_frame != log.sensor_frame:
        raise InvalidInputError(
            f"the empty run's sensor frame {empty_log.sensor_frame!r} is not the loaded run's "
            f"{log.sensor_frame!r}: both must be the same sensor"
        )
    E = wrench_system(robot, empty_log, empty_window, cutoff_hz)
    k = len(E.S.t)
    A, b = np.column_stack([E.A_pi.reshape(-1, 10), E.A_x]), E.b.reshape(-1)
    w = np.tile(1 / row_noise(A, b, k, 6), k)
    err = observable(robot, E, lambda: error_sources(
        A, b, w, (k, 6), float(E.S.t[-1] - E.S.t[0]), None, None, None, None),
        "the empty run")  # fmt: skip
    return Tool(err.sensitivity @ b, err.data_cov,
                 TOOL_EMPTY_RUN)  # fmt: skip


def observable(robot, W, solve, what="the loaded run"):
    """``solve()``, its UnobservableError said in the motion's terms: what to move."""
    try:
        return solve()
    except UnobservableError as exc:
        peak = np.max(np.abs(W.S.qd), axis=0)
        still = [f"{n} ({p:.2f} rad/s)" for n, p in zip(robot.joint_names, peak)
                 if p < MIN_PEAK_SPEED]  # fmt: skip
        sid = robot.model.getFrameId(W.sensor_frame)
        g = gravity_in_sensor(robot, sid, W.S.q)
        g /= np.linalg.norm(g, axis=1, keepdims=True)
        mean = g.mean(axis=0) / np.linalg.norm(g.mean(axis=0))
        turn = float(np.degrees(np.arccos(np.clip(g @ mean, -1, 1)).max()))
        raise UnobservableError(
            f"{what}'s wrench: {exc}. Gravity turns by at most {turn:.0f} deg in the sensor "
            f"frame (the mass, the CoM and the bias need it turned by tens of degrees about two "
            f"axes); joints below {MIN_PEAK_SPEED} rad/s: {', '.join(still) or 'none'}. Move "
            "every joint, tilt and spin the wrist (comgrasp plan-motion plans such a motion)"
        ) from None
