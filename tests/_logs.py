"""Synthetic robot logs for the robot_io tests: a before/after session at k poses.

The efforts are static torques from an independent model (``torques(Q, loaded)`` callable:
Pinocchio RNEA with an appended payload body, or MuJoCo's qfrc_bias), plus white noise per
sample; the positions get encoder-size noise.
"""

from __future__ import annotations

import numpy as np

from comgrasp_pin.robot_io import JointLog

MOVE_S, HOLD_S = 0.6, 1.3


def session(
    Q: np.ndarray,
    torques,
    names,
    rate_hz: float = 200.0,
    noise: float = 0.05,
    seed: int = 0,
    q_shift_after: np.ndarray | None = None,
    hold_s: float = HOLD_S,
):
    """A log visiting the k poses of ``Q`` empty, a grasp, then the k poses loaded.

    Returns (log, before, after, grasp_time): windows of 1 s in the middle of each hold.
    ``torques(Qs, loaded)`` maps (m, n) configurations to (m, n) static torques.
    ``q_shift_after`` (n,): the after poses differ from the before ones by it (servo sag).
    """
    rng = np.random.default_rng(seed)
    dt = 1.0 / rate_hz
    k, n = Q.shape
    shift = np.zeros(n) if q_shift_after is None else q_shift_after
    segments_q, segments_loaded, before, after = [], [], [], []
    t, q_prev = 0.0, Q[0].copy()
    grasp_time = None
    for loaded in (False, True):
        for i in range(k):
            target = Q[i] + (shift if loaded else 0.0)
            m = int(round(MOVE_S * rate_hz))
            s = (1 - np.cos(np.linspace(0, np.pi, m, endpoint=False))) / 2
            segments_q.append(q_prev + s[:, None] * (target - q_prev))
            segments_loaded.append(np.full(m, loaded))
            t += m * dt
            h = int(round(hold_s * rate_hz))
            segments_q.append(np.tile(target, (h, 1)))
            segments_loaded.append(np.full(h, loaded))
            mid = t + hold_s / 2
            (after if loaded else before).append((mid - 0.5, mid + 0.5))
            t += h * dt
            q_prev = target
        if not loaded:
            grasp_time = t + 0.25
            h = int(round(0.5 * rate_hz))  # the grasp: static, gripper closes
            segments_q.append(np.tile(q_prev, (h, 1)))
            segments_loaded.append(np.arange(h) >= h // 2)
            t += h * dt
    q = np.concatenate(segments_q)
    loaded = np.concatenate(segments_loaded)
    tau = np.empty_like(q)
    tau[~loaded] = torques(q[~loaded], False)
    tau[loaded] = torques(q[loaded], True)
    time = np.arange(len(q)) * dt
    log = JointLog(
        time,
        tuple(names),
        q + 1e-5 * rng.standard_normal(q.shape),
        tau + noise * rng.standard_normal(q.shape),
        "synthetic",
    )
    return log, before, after, grasp_time


def rnea_torques(robot, mass, com_ee):
    """``torques(Qs, loaded)`` from Pinocchio RNEA with a payload body (tests/_payload)."""
    from _payload import payload_torques

    def torques(Qs, loaded):
        tb, ta = payload_torques(robot, Qs, mass, com_ee)
        return ta if loaded else tb

    return torques


def mujoco_torques(mass, com_ee, ee_body="eelink"):
    """``torques(Qs, loaded)`` for the project's UR5 from MuJoCo (independent of Pinocchio):
    qfrc_bias at zero velocity of the URDF compiled by MuJoCo, with a payload body of ``mass``
    at ``com_ee`` (ee frame) added to ``ee_body`` for ``loaded``."""
    import mujoco

    from comgrasp_pin.simulation.world import ARM_JOINTS, robot_spec

    models = []
    for loaded in (False, True):
        spec = robot_spec()
        if loaded:
            body = spec.body(ee_body).add_body(name="payload")
            body.mass = mass
            body.ipos = np.asarray(com_ee, float)
            body.inertia = [2e-3, 3e-3, 4e-3]
            body.explicitinertial = True
        models.append(spec.compile())

    def torques(Qs, loaded):
        m = models[int(loaded)]
        d = mujoco.MjData(m)
        qadr = [m.joint(j).qposadr[0] for j in ARM_JOINTS]
        vadr = [m.joint(j).dofadr[0] for j in ARM_JOINTS]
        out = np.empty((len(Qs), len(ARM_JOINTS)))
        for i, q in enumerate(Qs):
            d.qpos[qadr] = q
            d.qvel[:] = 0.0
            mujoco.mj_forward(m, d)
            out[i] = d.qfrc_bias[vadr]
        return out

    return torques


def simulated_session(Q, mass, com_ee, noise=0.05, seed=0, hold_s=2.0, move_s=0.8):
    """The project's UR5 in the MuJoCo world (servo, torque sensor at 500 Hz): the k poses of
    Q visited empty, then again with a payload body of ``mass`` at ``com_ee`` (eelink frame)
    welded to the eelink. Returns (log, before, after, grasp_time); windows of 1 s in the
    middle of each hold. Arm and sensor are the simulator's: the servo's settling, the
    fingers, the drives' torques as read by the noisy sensor."""
    from comgrasp_pin.config import TorqueSensorConfig
    from comgrasp_pin.simulation.sim import Simulation
    from comgrasp_pin.simulation.world import ARM_JOINTS, build_model

    def payload(spec):
        body = spec.body("eelink").add_body(name="payload")
        body.mass, body.ipos = mass, np.asarray(com_ee, float)
        body.inertia, body.explicitinertial = [2e-3, 3e-3, 4e-3], True

    sensor = TorqueSensorConfig(noise_std=noise)
    sims = [Simulation(build_model(), sensor=sensor, seed=seed),
            Simulation(build_model(extras=[payload]), sensor=sensor, seed=seed + 1)]  # fmt: skip
    times, qs, taus, before, after = [], [], [], [], []
    t = 0.0
    for loaded, sim in enumerate(sims):
        dt = sim.model.opt.timestep
        sim.reset_arm(Q[0])
        sim.grip_force = -5.0  # open, fingers at their limit (the model's neutral)
        q_prev = Q[0]
        for q in Q:
            n_move, n_hold = int(round(move_s / dt)), int(round(hold_s / dt))
            s = (1 - np.cos(np.linspace(0, np.pi, n_move))) / 2
            for i in range(n_move + n_hold):
                sim.q_des = q_prev + s[i] * (q - q_prev) if i < n_move else q
                sim.step()
                t += dt
                times.append(t)
                qs.append(sim.q)
                taus.append(sim.tau_measured.copy())
            mid = t - hold_s / 2
            (after if loaded else before).append((mid - 0.5, mid + 0.5))
            q_prev = q
        if not loaded:
            grasp_time = t + 0.5 * dt
    time = np.array(times) - times[0]
    shift = times[0]
    before = [(a - shift, b - shift) for a, b in before]
    after = [(a - shift, b - shift) for a, b in after]
    log = JointLog(time, tuple(ARM_JOINTS), np.array(qs), np.array(taus), "mujoco")
    return log, before, after, grasp_time - shift
