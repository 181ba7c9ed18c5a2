"""A simulated FR3 that speaks libfranka's protocol (franky-sim, MuJoCo behind it).

A payload is attached mid-session, as a user would. The server runs in its own process on
the loopback address (127.0.0.1), as a robot would run on its own controller: the client
side (``live.franka``) cannot tell it from an FR3 and imports no MuJoCo. The payload is a body on
the arm's last link (``fr3_link7``, whose axes are the flange's) with the given mass, CoM
(flange frame) and inertia about the CoM; it weighs nothing until ``attach`` (the prompt's
"attach the payload now"), which sets its mass and inertia in the running model as a
person's hands would. ``fault`` makes the robot report an error (a joint reflex);
``lose_after_s`` ends the server abruptly, as a pulled cable would.
"""

from __future__ import annotations

import multiprocessing as mp
import os
import signal
import threading
from dataclasses import dataclass

import numpy as np

from comgrasp_pin._paths import fr3_urdf
from comgrasp_pin.errors import RobotError

HOST = "127.0.0.1"
LINK7, FLANGE_Z_M = "robot0_fr3_link7", 0.107  # the flange: 0.107 m along link 7's z
START_TIMEOUT_S = 120.0
JOINT_REFLEX = 6  # libfranka's Errors: the joint_reflex flag's index


@dataclass(frozen=True)
class SimPayload:
    """The payload to attach.

    Attributes:
        mass: kg.
        com_flange: (3,) CoM in the flange frame (m).
        inertia: (3, 3) inertia about the CoM in the flange's axes (kg m^2, symmetric
            positive definite).
    """

    mass: float
    com_flange: tuple[float, float, float]
    inertia: tuple[tuple[float, ...], ...] = ((1e-3, 0, 0), (0, 1e-3, 0), (0, 0, 1e-3))


class FrankaSim:
    """The simulated FR3's server process; a context manager (started on enter)."""

    def __init__(self, payload: SimPayload | None = None, fault: str | None = None,
                 lose_after_s: float | None = None):  # fmt: skip
        fr3_urdf()  # the extra is there, or a clear error before a process starts
        self.payload, self.fault, self.lose_after_s = payload, fault, lose_after_s
        ctx = mp.get_context("spawn")
        self._conn, child = ctx.Pipe()
        self._process = ctx.Process(target=_serve, args=(child, payload, fault, lose_after_s),
                                    daemon=True)  # fmt: skip

    def __enter__(self) -> FrankaSim:
        self._process.start()
        if not self._conn.poll(START_TIMEOUT_S):
            self.close()
            raise RobotError(f"the simulated FR3 did not start within {START_TIMEOUT_S:g} s")
        try:
            message = self._conn.recv()
        except EOFError:
            message = "its process ended (a script that starts it must do so under "
            message += "if __name__ == '__main__':, as multiprocessing's spawn requires)"
        if message != "ready":
            self.close()
            raise RobotError(f"the simulated FR3 failed to start: {message}")
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def attach(self) -> None:
        """Give the payload its mass and inertia (the user attaching it)."""
        if self.payload is None:
            return
        try:
            self._conn.send("attach")
            if self._conn.poll(10.0) and self._conn.recv() == "attached":
                return
        except (OSError, EOFError):
            pass
        raise RobotError("the simulated FR3 did not take the payload (its server is gone)")

    def close(self) -> None:
        """Stop the server process (killed if it does not end within 5 s)."""
        if self._process.is_alive():
            try:
                self._conn.send("stop")
            except OSError:
                pass
            self._process.join(5.0)
        if self._process.is_alive():
            self._process.kill()
            self._process.join(5.0)


def _serve(conn, payload: SimPayload | None, fault: str | None, lose_after_s: float | None):
    """The server process: build the scene, serve on 127.0.0.1, obey the pipe.

    Ctrl-C is the client's: the user stops the arm, not the robot's controller.
    """
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        import franky_sim
        from franky_sim.mujoco_simulator import MujocoSimulator

        sim = MujocoSimulator()
        sim.init()
        robot = sim.add_robot()
        if payload is not None:
            _add_payload_body(sim, payload)
        if fault is not None:
            _report_fault(robot)
        server = franky_sim.SimulationServer(sim, hostname_candidates=[HOST])
        server.init()
        server.run_async()
    except Exception as exc:  # reported to the parent, which raises it as a RobotError
        conn.send(f"{type(exc).__name__}: {exc}")
        return
    if lose_after_s is not None:
        threading.Timer(lose_after_s, os._exit, args=(0,)).start()
    conn.send("ready")
    while True:
        try:
            command = conn.recv()
        except EOFError:
            command = "stop"
        if command == "attach" and payload is not None:
            _give_mass(sim.model, payload)
            conn.send("attached")
        elif command == "stop":
            server.cleanup()
            return


def _add_payload_body(sim, payload: SimPayload) -> None:
    """A weightless body on link 7 at the payload's CoM (its mass comes with ``attach``)."""
    import xml.etree.ElementTree as ET

    link7 = next(b for b in sim.worldbody.iter("body") if b.get("name") == LINK7)
    pos = np.asarray(payload.com_flange, float) + [0.0, 0.0, FLANGE_Z_M]
    body = ET.SubElement(link7, "body", name="payload", pos=" ".join(f"{v:.9g}" for v in pos))
    ET.SubElement(body, "inertial", pos="0 0 0", mass="1e-9", diaginertia="1e-12 1e-12 1e-12")


def _give_mass(model, payload: SimPayload) -> None:
    """Set the payload body's mass and inertia in the running model.

    Its ancestors' subtree masses too, which MuJoCo computes once at compile time.
    """
    import mujoco

    b = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "payload")
    moments, axes = np.linalg.eigh(np.asarray(payload.inertia, float))
    if np.linalg.det(axes) < 0:
        axes[:, 0] *= -1
    quat = np.empty(4)
    mujoco.mju_mat2Quat(quat, axes.ravel())
    added = payload.mass - model.body_mass[b]
    model.body_inertia[b] = moments
    model.body_iquat[b] = quat
    model.body_mass[b] = payload.mass
    while b > 0:
        model.body_subtreemass[b] += added
        b = model.body_parentid[b]
    model.body_subtreemass[0] += added


def _report_fault(robot) -> None:
    """Make the simulated robot report a joint reflex in every state it sends."""
    base = type(robot)

    class Faulty(base):  # type: ignore[misc, valid-type]
        @property
        def state(self):
            s = super().state
            errors = list(s.current_errors)
            errors[JOINT_REFLEX] = True
            return s.replace(current_errors=tuple(errors), errors=tuple(errors))

    robot.__class__ = Faulty
