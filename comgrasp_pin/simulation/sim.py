"""A running world: MuJoCo model and data, the arm servo, the gripper and the raw readings."""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import contextmanager

import mujoco
import numpy as np

from comgrasp_pin.config import TorqueSensorConfig, WorldConfig, WrenchSensorConfig
from comgrasp_pin.errors import InvalidInputError, UnstablePhysicsError
from comgrasp_pin.procedures.cell import TorqueMeasurement
from comgrasp_pin.simulation.servo import ArmServo
from comgrasp_pin.simulation.torque_sensor import make_torque_sensor
from comgrasp_pin.simulation.world import (
    ARM_JOINTS,
    EE_SITE,
    FINGER_JOINTS,
    FT_SENSORS,
    build_model,
)
from comgrasp_pin.simulation.wrench_sensor import (
    WrenchMeasurement,
    WrenchSensor,
    steps_per_sample,
    window_measurement,
    wrench_from_sensors,
)

_W = mujoco.mjtWarning
UNSTABLE = slice(int(_W.mjWARN_BADQPOS), int(_W.mjWARN_BADCTRL) + 1)
"""MuJoCo's warnings of a state gone bad (mjWARN_BADQPOS, BADQVEL, BADQACC, BADCTRL): MuJoCo
then resets the state and goes on, so a trial would go on from nonsense; they are raised."""
assert [_W(i).name for i in range(UNSTABLE.start, UNSTABLE.stop)] == [
    "mjWARN_BADQPOS", "mjWARN_BADQVEL", "mjWARN_BADQACC", "mjWARN_BADCTRL"
]  # fmt: skip


class Simulation:
    """Steps the physics with the arm servo in the loop.

    Every ``step`` runs the servo once and ``mj_step`` once (``config.sim_dt``), so the
    controller and the torque sensor run at 1/sim_dt (500 Hz by default, a UR5's control rate).

    Attributes:
        model, data: the MuJoCo model and data.
        q_des: (6,) commanded arm configuration (rad).
        grip_force: commanded force of each finger (N); positive closes, negative opens.
        tau_measured: (6,) the torque sensor's latest sample (N m), noisy (formed when
            read: samples nobody reads only advance the sensor's noise and drift).
        wrench_sensor: the wrist force/torque sensor (``wrench_sensor.WrenchSensor``),
            sampling every ``wrench_steps``-th step; read by ``measure``.
        observers: callables ``f(sim)`` run after every physics step (video recording, slip
            monitoring); each should return at once unless it is its time to act.
    """

    def __init__(
        self,
        model: mujoco.MjModel | None = None,
        config: WorldConfig | None = None,
        sensor: TorqueSensorConfig | None = None,
        seed: int | None = None,
        wrench: WrenchSensorConfig | None = None,
    ):
        self.config = config or WorldConfig()
        self.model = build_model(config) if model is None else model
        self.data = mujoco.MjData(self.model)
        m = self.model
        self._arm_qadr = np.array([m.joint(j).qposadr[0] for j in ARM_JOINTS])
        self._arm_vadr = np.array([m.joint(j).dofadr[0] for j in ARM_JOINTS])
        self._finger_qadr = np.array([m.joint(j).qposadr[0] for j in FINGER_JOINTS])
        self._arm_act = np.array([m.actuator(j).id for j in ARM_JOINTS])
        self._finger_act = np.array([m.actuator(j).id for j in FINGER_JOINTS])
        self._tau_adr = np.array([m.sensor(f"tau_{j}").adr[0] for j in ARM_JOINTS])
        self._ee_site = m.site(EE_SITE).id
        kp = float(m.actuator_gainprm[self._arm_act[0], 0])
        c = self.config
        self.servo = ArmServo(len(ARM_JOINTS), kp, c.servo_ki, c.servo_tau_i_limit)
        self._arm_qadr, self._arm_vadr, self._arm_act, self._tau_adr = (
            _contiguous(a, name)
            for a, name in zip(
                (self._arm_qadr, self._arm_vadr, self._arm_act, self._tau_adr),
                ("qpos", "qvel", "actuator", "torque sensor"),
                strict=True,
            )
        )
        self.q_des = np.zeros(len(ARM_JOINTS))
        self.grip_force = 0.0
        self.sensor = make_torque_sensor(len(ARM_JOINTS), sensor or TorqueSensorConfig(), seed)
        wrench = wrench or WrenchSensorConfig()
        self.wrench_sensor = WrenchSensor(wrench, seed)
        self.wrench_steps = steps_per_sample(wrench, m.opt.timestep)
        adr = m.sensor(FT_SENSORS[0]).adr[0]
        if m.sensor(FT_SENSORS[1]).adr[0] != adr + 3:
            raise InvalidInputError("the wrist sensor's force and torque must be adjacent")
        mujoco.mj_forward(m, self.data)
        self._tau = self.joint_torques()
        self._unread = 0  # control steps since the sensor's last formed sample
        d = self.data
        # Views into MjData (its arrays live as long as it does): no copy, no index per step.
        self._q_arm, self._qd_arm = d.qpos[self._arm_qadr], d.qvel[self._arm_vadr]
        self._bias_arm, self._ctrl_arm = d.qfrc_bias[self._arm_vadr], d.ctrl[self._arm_act]
        self._tau_true = d.sensordata[self._tau_adr]
        self._ft_true = d.sensordata[adr : adr + 6]  # MuJoCo's convention: the arm's on the tool
        self.observers: list[Callable[[Simulation], None]] = []
        self._unstable_counts = self.data.warning.number[UNSTABLE]  # a live view

    @property
    def time(self) -> float:
        return float(self.data.time)

    @property
    def tau_measured(self) -> np.ndarray:
        """(6,) the torque sensor's sample at the last control step (N m)."""
        if self._unread:
            self._catch_up(self._tau_true[None])
        return self._tau

    def _catch_up(self, tau_true: np.ndarray) -> np.ndarray:
        """(N, 6) the sensor's samples of the last N control steps, from their true torques
        ``tau_true`` (N, 6); the unread steps before them only advance the sensor."""
        dt = self.model.opt.timestep
        self.sensor.skip(self._unread - len(tau_true), dt)
        taus = self.sensor.read_many(tau_true, dt)
        self._tau, self._unread = taus[-1].copy(), 0
        return taus

    @property
    def q(self) -> np.ndarray:
        """(6,) arm joint positions (rad)."""
        return self.data.qpos[self._arm_qadr].copy()

    @property
    def qd(self) -> np.ndarray:
        """(6,) arm joint velocities (rad/s)."""
        return self.data.qvel[self._arm_vadr].copy()

    @property
    def finger_q(self) -> np.ndarray:
        """(2,) finger closings (m); 0 is fully open."""
        return self.data.qpos[self._finger_qadr].copy()

    def joint_torques(self) -> np.ndarray:
        """(6,) torque each arm drive exerts now (N m): the truth behind the sensor."""
        return self.data.sensordata[self._tau_adr].copy()

    def wrench_true(self) -> np.ndarray:
        """(6,) the true wrench the tool side applies to the wrist sensor now (force N,
        torque N m, ``ft_sensor`` frame): the truth behind the wrist sensor."""
        return wrench_from_sensors(self._ft_true)

    def ee_pose(self) -> np.ndarray:
        """(4, 4) T_world_ee of the eelink site."""
        T = np.eye(4)
        T[:3, :3] = self.data.site_xmat[self._ee_site].reshape(3, 3)
        T[:3, 3] = self.data.site_xpos[self._ee_site]
        return T

    def reset_arm(self, q: np.ndarray, finger_q: float = 0.0) -> None:
        """Teleport the arm to ``q`` at rest, command it to stay there, forget the integral."""
        q = np.asarray(q, dtype=float)
        self.data.qpos[self._arm_qadr] = q
        self.data.qvel[self._arm_vadr] = 0.0
        self.data.qpos[self._finger_qadr] = finger_q
        self.q_des = q.copy()
        self.servo.reset()
        mujoco.mj_forward(self.model, self.data)

    def step(self, n: int = 1) -> None:
        """Advance ``n`` physics steps with the servo and gripper in the loop.

        Raises:
            UnstablePhysicsError: the state went bad (NaN, inf or huge positions,
                velocities, accelerations or controls; MuJoCo's ``mjWARN_BAD*`` warnings).
        """
        self._advance(n, None)

    def track(self, q_des: np.ndarray) -> None:
        """One physics step per row of ``q_des`` (N, 6) (rad), each row commanded in turn
        (``step`` with ``q_des`` set before each step)."""
        self._advance(len(q_des), q_des)

    def _advance(self, n: int, q_path: np.ndarray | None) -> None:
        m, d = self.model, self.data
        dt = m.opt.timestep
        d.ctrl[self._finger_act] = self.grip_force
        q, qd, bias, ctrl, tau_true = (self._q_arm, self._qd_arm, self._bias_arm,
                                       self._ctrl_arm, self._tau_true)  # fmt: skip
        servo, observers = self.servo.ctrl, self.observers
        read_each_step = self.sensor.needs_velocity
        for i in range(n):
            if q_path is not None:
                self.q_des = q_path[i]
            servo(q, self.q_des, bias, dt, ctrl)
            mujoco.mj_step(m, d)
            if read_each_step:
                self._tau = self.sensor.read(tau_true, dt, qd)
            else:
                self._unread += 1
            for observer in observers:
                observer(self)
        if self._unstable_counts.any():
            self._raise_unstable()

    def _raise_unstable(self) -> None:
        counts = self._unstable_counts
        names = [_W(UNSTABLE.start + i).name for i in np.flatnonzero(counts)]
        raise UnstablePhysicsError(
            f"the simulation went unstable by t = {self.time:.3f} s ({', '.join(names)}: "
            "NaN, inf or huge state or control; MuJoCo reset it): the trial cannot go on"
        )

    @contextmanager
    def observing(self, observer: Callable[[Simulation], None]) -> Iterator[None]:
        """Run ``observer`` after every physics step while the ``with`` block lasts."""
        self.observers.append(observer)
        try:
            yield
        finally:
            self.observers.remove(observer)

    def hold(self, duration: float) -> None:
        """Keep the commanded configuration for ``duration`` seconds."""
        self.step(int(round(duration / self.model.opt.timestep)))

    def measure_torques(self, settle: float, window: float) -> TorqueMeasurement:
        """Hold still for ``settle`` s, then average the torque sensor over ``window`` s."""
        return self.measure(settle, window, wrench=False)[0]

    def measure_wrench(self, settle: float, window: float) -> WrenchMeasurement:
        """Hold still for ``settle`` s, then average the wrist sensor over ``window`` s."""
        return self.measure(settle, window)[1]

    def measure(
        self, settle: float, window: float, wrench: bool = True
    ) -> tuple[TorqueMeasurement, WrenchMeasurement | None]:
        """Hold still for ``settle`` s, then average the joint torques and (``wrench``) the
        wrist sensor over the same ``window`` s: the torque sensor's samples of every step,
        the wrist sensor's of every ``wrench_steps``-th; both at the window's mean ``q``."""
        self.hold(settle)
        start = self.time
        dt = self.model.opt.timestep
        n = max(1, int(round(window / dt)))
        taus = np.empty((n, len(ARM_JOINTS)))
        qs = np.empty((n, len(ARM_JOINTS)))
        wrenches = np.empty((n, 6)) if wrench else None
        # Without observers (which may read the sensor) the window's samples are formed at
        # once from the true torques, as the sensor would have formed them step by step.
        at_once = not (self.sensor.needs_velocity or self.observers)
        for k in range(n):
            self.step()
            taus[k] = self._tau_true if at_once else self.tau_measured
            qs[k] = self._q_arm
            if wrenches is not None:
                wrenches[k] = self._ft_true
        if at_once:
            taus = self._catch_up(taus)
        std_error = taus.std(axis=0, ddof=1) / np.sqrt(n) if n > 1 else np.full(6, np.inf)
        q = qs.mean(axis=0)
        torques = TorqueMeasurement(taus.mean(axis=0), std_error, q, n, n * dt, start)
        if wrenches is None:
            return torques, None
        first = int(round(start / dt))  # the step count of the first step's state
        return torques, window_measurement(self.wrench_sensor, wrench_from_sensors(wrenches),
                                           first, self.wrench_steps, q, dt, start)  # fmt: skip


def _contiguous(index: np.ndarray, what: str) -> slice:
    """The arm's contiguous ``index`` array as a slice (indexing by a slice is a view)."""
    if len(index) == 0 or not np.array_equal(index, np.arange(index[0], index[0] + len(index))):
        raise InvalidInputError(
            f"the arm's {what} addresses {index} are not contiguous in the model: its six "
            "joints, actuators and torque sensors must each be declared in one block"
        )
    return slice(int(index[0]), int(index[0]) + len(index))
