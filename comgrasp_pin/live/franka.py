"""A Franka arm over its own network protocol (libfranka, through franky).

Connect, check, move, read, set the load. Only what the robot reports is used: ``q``,
``dq``, ``tau_J`` (the joint torque sensors), ``O_F_ext_hat_K`` (its own external-wrench
estimate), its mode, errors and contact flags. Every sample read, during moves and holds
alike, goes into ``samples``, so a run that ends early (Ctrl-C, a reflex, a lost connection)
keeps what it recorded. Failures become a ``RobotError`` that says what happened; Ctrl-C
stops the motion (``robot.stop()``) first.
"""

from __future__ import annotations

import contextlib
import signal
import time
from dataclasses import dataclass, field

import numpy as np

from comgrasp_pin.config import LiveConfig
from comgrasp_pin.errors import MissingExtraError, RobotError
from comgrasp_pin.robot_io.at_rest.windows import MAX_SPEED, SPEED_SPAN, joint_speed

FRANKA_JOINTS = 7
INSTALL_HINT = 'pip install ".[franka]" (franky-control, and franky-sim for --sim)'


def import_franky():
    """The ``franky`` module, or MissingExtraError naming the extra."""
    try:
        import franky
    except ImportError as exc:
        raise MissingExtraError(
            f"the live Franka path needs franky: {INSTALL_HINT} ({exc})"
        ) from None
    return franky


@dataclass
class Samples:
    """The robot's state as read: one row per read, on the robot's clock (s)."""

    time: list[float] = field(default_factory=list)
    q: list[np.ndarray] = field(default_factory=list)
    dq: list[np.ndarray] = field(default_factory=list)
    tau_J: list[np.ndarray] = field(default_factory=list)
    wrench: list[np.ndarray] = field(default_factory=list)

    def __len__(self) -> int:
        return len(self.time)


class FrankaArm:
    """A connected Franka (``host``: its address) moved at ``config.dynamics_factor``."""

    def __init__(self, host: str, config: LiveConfig):
        franky = import_franky()
        self._franky, self.config, self.host = franky, config, host
        self.samples = Samples()
        try:
            self.robot = franky.Robot(host, realtime_config=franky.RealtimeConfig.Ignore)
        except Exception as exc:  # franky.NetworkException, IncompatibleVersionException
            raise RobotError(
                f"cannot connect to a Franka at {host}: {type(exc).__name__}: {exc}. Is the "
                "robot on, its FCI enabled in Desk, the address right (or --sim for the "
                "simulated FR3)?"
            ) from None
        self.robot.relative_dynamics_factor = config.dynamics_factor
        self.interrupted = False

    @contextlib.contextmanager
    def ctrl_c_stops(self):
        """Within: Ctrl-C stops the arm, then raises KeyboardInterrupt in ``move``/``hold``.

        franky turns a KeyboardInterrupt raised while it waits for a motion into a
        preempted motion (a ControlException), which would hide that the user stopped the
        arm; so the signal only sets ``interrupted``, which the loops check every read.
        """

        def handler(signum, frame):
            self.interrupted = True

        try:
            previous = signal.signal(signal.SIGINT, handler)
        except ValueError:  # not the main thread: Ctrl-C keeps Python's behaviour
            yield
            return
        try:
            yield
        finally:
            signal.signal(signal.SIGINT, previous)

    def _check_interrupt(self) -> None:
        if self.interrupted:
            self._stop_quietly()
            raise KeyboardInterrupt

    # -- checks ---------------------------------------------------------------------------

    def state(self):
        """The robot's latest state, or RobotError where the connection is gone."""
        try:
            return self.robot.state
        except Exception as exc:  # NetworkException: the connection was lost
            raise RobotError(f"lost the connection to {self.host}: {exc}") from None

    def check_ready(self) -> None:
        """RobotError where the robot reports errors, a reflex, a stop or a contact."""
        s = self.state()
        errors = [name for name in dir(s.current_errors) if _flag(s.current_errors, name)]
        mode = str(s.robot_mode).split(".")[-1]
        if errors or self.robot.has_errors:
            raise RobotError(
                f"the robot reports errors ({', '.join(errors) or 'has_errors'}), mode {mode}: "
                "clear them in Desk or with the robot's error recovery, then start again; "
                "nothing was moved"
            )
        if mode not in ("Idle", "Move"):
            raise RobotError(f"the robot is in mode {mode}, not Idle: nothing was moved")
        if any(s.joint_contact) or any(s.cartesian_contact):
            raise RobotError("the robot reports a contact: free the arm; nothing was moved")

    def configure(self) -> None:
        """Send the contact thresholds (the robot stops on a larger torque or force)."""
        c = self.config
        try:
            self.robot.set_collision_behavior(list(c.collision_torque_nm),
                                              list(c.collision_force_n))  # fmt: skip
        except Exception as exc:
            raise RobotError(f"the robot refused the contact thresholds: {exc}") from None

    # -- motion and readings ------------------------------------------------------------

    def read(self) -> None:
        """Append one reading of the state to ``samples``."""
        s = self.state()
        t = s.time
        self.samples.time.append(float(getattr(t, "to_sec", lambda: t)()))
        self.samples.q.append(np.array(s.q, dtype=float))
        self.samples.dq.append(np.array(s.dq, dtype=float))
        self.samples.tau_J.append(np.array(s.tau_J, dtype=float))
        self.samples.wrench.append(np.array(s.O_F_ext_hat_K, dtype=float))

    def move(self, q: np.ndarray) -> None:
        """Move to ``q`` (rad), reading the state meanwhile; Ctrl-C stops the arm."""
        motion = self._franky.JointMotion([float(v) for v in q])
        self._run(motion, f"the move to {np.round(q, 3)}", self.config.motion_timeout_s)

    def play(self, waypoints) -> None:
        """Play a planned motion (``protocol.Waypoints``) from its start, reading meanwhile.

        The robot's trajectory generator (Ruckig, in libfranka's client) passes each
        waypoint's position and velocity in turn, each segment as fast as the dynamics
        factor allows: the same path at the same pace in both runs. (With the waypoints'
        times as minimum durations, franky-sim's FR3 failed 2 of 5 plays with Ruckig's
        synchronisation error -111.) The arm must be at ``waypoints.start``.
        """
        franky = self._franky
        points = [franky.JointWaypoint(franky.JointState([float(v) for v in q],
                                                         [float(v) for v in qd]))
                  for q, qd in zip(waypoints.q, waypoints.qd)]  # fmt: skip
        timeout = waypoints.duration_s + self.config.motion_timeout_s
        self._run(franky.JointWaypointMotion(points), "the planned motion", timeout)

    def limits(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The robot's joint (velocity, acceleration, jerk) limits (rad/s, /s^2, /s^3)."""
        r = self.robot
        limits = (r.joint_velocity_limit, r.joint_acceleration_limit, r.joint_jerk_limit)
        v, a, j = (np.array(lim.max, dtype=float) for lim in limits)
        return v, a, j

    def _run(self, motion, what: str, timeout_s: float) -> None:
        """Run a franky motion, reading the state meanwhile; Ctrl-C stops the arm."""
        start = time.monotonic()
        try:
            self.robot.move(motion, asynchronous=True)
            while not self.robot.join_motion(self.config.sample_period_s):
                self.read()
                self._check_interrupt()
                if time.monotonic() - start > timeout_s:
                    self.robot.stop()
                    raise RobotError(f"{what} did not end within {timeout_s:g} s: stopped")
        except KeyboardInterrupt:
            self._stop_quietly()
            raise
        except RobotError:
            raise
        except Exception as exc:  # ControlException (a reflex), NetworkException
            self._stop_quietly()
            raise RobotError(f"{what} failed: {type(exc).__name__}: {exc}") from None

    def hold(self, seconds: float) -> tuple[float, float]:
        """Read the state for ``seconds`` (s) at rest; the (t0, t1) of the readings (s)."""
        first = len(self.samples)
        end = time.monotonic() + seconds
        try:
            while time.monotonic() < end:
                self.read()
                self._check_interrupt()
                time.sleep(self.config.sample_period_s)
        except KeyboardInterrupt:
            self._stop_quietly()
            raise
        return self.samples.time[first], self.samples.time[-1]

    def settle(self) -> None:
        """Read for ``settle_s``, then on until the joints are still (``still_speed``)."""
        c = self.config
        self.hold(c.settle_s)
        waited = c.settle_s
        while waited < c.max_settle_s and self.speed() > c.still_speed:
            self.hold(SPEED_SPAN)
            waited += SPEED_SPAN

    def speed(self) -> float:
        """The largest joint speed (rad/s) over the last ``SPEED_SPAN`` of readings.

        The static windows' ``joint_speed``, at the reading that span before the last.
        """
        t = np.asarray(self.samples.time[-int(4 * SPEED_SPAN / self.config.sample_period_s) :])
        q = np.asarray(self.samples.q[-len(t) :])
        early = np.flatnonzero(t <= t[-1] - SPEED_SPAN)
        return float(joint_speed(t, q)[early[-1]]) if len(early) else np.inf

    def record_still(self, seconds: float, tries: int = 3) -> tuple[float, float]:
        """Settle, then a window of ``seconds`` (s) that passes the static windows' check.

        The check is the offline estimate's (``windows.joint_speed`` at most ``MAX_SPEED``);
        a window that fails it (the arm still creeping) is recorded again, ``tries`` times
        at most. The (t0, t1) of the last window (s).
        """
        for _ in range(tries):
            self.settle()
            first = len(self.samples)
            t0, t1 = self.hold(seconds)
            t = np.asarray(self.samples.time[first:])
            q = np.asarray(self.samples.q[first:])
            if joint_speed(t, q).max() <= MAX_SPEED:
                break
        return t0, t1

    def _stop_quietly(self) -> None:
        try:
            self.robot.stop()
        except Exception:  # the connection may already be gone; the error says so
            pass

    # -- the load -------------------------------------------------------------------------

    def set_load(self, load: dict) -> tuple[float, np.ndarray, np.ndarray]:
        """Send ``load`` (``exports.franka_load``'s dict); (m_load, F_x_Cload, I_load) read back."""
        try:
            self.robot.set_load(load["mass"], load["F_x_Cload"], load["load_inertia"])
        except Exception as exc:
            raise RobotError(f"the robot refused set_load: {exc}") from None
        s = self.state()
        return float(s.m_load), np.array(s.F_x_Cload), np.array(s.I_load)


def _flag(errors, name: str) -> bool:
    """Whether ``errors.name`` is a raised error flag (franky's ``Errors`` fields are bools)."""
    if name.startswith("_"):
        return False
    value = getattr(errors, name, False)
    return isinstance(value, bool) and value
