"""The arm's joint servo: MuJoCo position actuators plus gravity feed-forward and integral action.

MuJoCo's position actuator exerts ``kp (ctrl - q) - kv qdot`` (its damping is integrated
implicitly, so a stiff servo is stable at 500 Hz). Writing

    ctrl = q_des + (tau_ff + tau_i) / kp

turns it into a PD with feed-forward ``tau_ff`` (the model's gravity and Coriolis torques)
and an integral term ``tau_i`` that learns whatever the model does not know (a payload), so
the held configuration does not sag under load: in steady state ``q = q_des`` exactly and
the drive torque is the full static torque.
"""

from __future__ import annotations

import numpy as np


class ArmServo:
    """Integral + feed-forward wrapper around position actuators of stiffness ``kp``.

    Args:
        n: number of joints.
        kp: actuator stiffness (N m / rad), as compiled into the model.
        ki: integral rate (1/s): the integral term closes a static error with time
            constant about 1/ki.
        tau_i_limit: anti-windup bound on the integral term (N m).
    """

    def __init__(self, n: int, kp: float, ki: float, tau_i_limit: float):
        self.kp = kp
        self.ki = ki
        self.tau_i_limit = tau_i_limit
        self.tau_i = np.zeros(n)
        self._work = np.zeros(n)

    def reset(self) -> None:
        """Forget the integral term (after teleporting the arm)."""
        self.tau_i[:] = 0.0

    def ctrl(
        self,
        q: np.ndarray,
        q_des: np.ndarray,
        tau_ff: np.ndarray,
        dt: float,
        out: np.ndarray | None = None,
    ) -> np.ndarray:
        """Actuator command (rad) for one control step of length ``dt`` (s), written into
        ``out`` (n,) when given (a view of MjData's ctrl: no array made per step)."""
        tau_i, work = self.tau_i, self._work
        np.subtract(q_des, q, out=work)
        work *= self.ki * self.kp * dt
        tau_i += work
        np.minimum(tau_i, self.tau_i_limit, out=tau_i)  # np.clip costs more on 6 numbers
        np.maximum(tau_i, -self.tau_i_limit, out=tau_i)
        np.add(tau_ff, tau_i, out=work)
        work *= 1.0 / self.kp
        return np.add(q_des, work, out=out)
