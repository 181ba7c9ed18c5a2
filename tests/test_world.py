"""Pinocchio (the estimator's model) and MuJoCo (the world) are the same robot."""

import mujoco
import numpy as np
import pinocchio as pin

from comgrasp_pin.simulation import Simulation
from comgrasp_pin.simulation.world import ARM_JOINTS, EE_SITE, FINGER_JOINTS


def _set(model, data, q_arm, finger):
    for name, value in zip(ARM_JOINTS, q_arm):
        data.qpos[model.joint(name).qposadr[0]] = value
    for name in FINGER_JOINTS:
        data.qpos[model.joint(name).qposadr[0]] = finger
    data.qvel[:] = 0.0
    mujoco.mj_forward(model, data)


def test_gravity_and_ee_pose_agree_at_random_configurations(ur5, world_model):
    m, d = world_model, mujoco.MjData(world_model)
    dofs = [m.joint(name).dofadr[0] for name in ARM_JOINTS]
    site = m.site(EE_SITE).id
    rng = np.random.default_rng(2)
    worst_tau = worst_p = worst_r = 0.0
    for k in range(50):
        q = ur5.random_configuration(rng)
        finger = 0.0 if k % 2 == 0 else 0.03  # symmetric fingers leave the arm's gravity alone
        _set(m, d, q, finger)
        worst_tau = max(worst_tau, np.abs(d.qfrc_bias[dofs] - ur5.gravity_torques(q)).max())
        T = ur5.ee_pose(q)
        worst_p = max(worst_p, np.abs(d.site_xpos[site] - T[:3, 3]).max())
        R_err = d.site_xmat[site].reshape(3, 3).T @ T[:3, :3]
        worst_r = max(worst_r, np.linalg.norm(pin.log3(R_err)))
    assert worst_tau < 1e-6, worst_tau
    assert worst_p < 1e-9, worst_p
    assert worst_r < 1e-9, worst_r


def test_link_masses_and_centres_agree(ur5, world_model):
    """Per rigid group (Pinocchio merges fixed links into their joint; MuJoCo welds them)."""
    full = ur5.full_model
    data = full.createData()
    m, d = world_model, mujoco.MjData(world_model)
    rng = np.random.default_rng(3)
    q_arm = ur5.random_configuration(rng)
    finger = 0.02
    q_full = pin.neutral(full)
    for name, value in list(zip(ARM_JOINTS, q_arm)) + [(n, finger) for n in FINGER_JOINTS]:
        q_full[full.joints[full.getJointId(name)].idx_q] = value
    pin.forwardKinematics(full, data, q_full)
    _set(m, d, q_arm, finger)
    for jid in range(1, full.njoints):
        body = m.joint(full.names[jid]).bodyid[0]
        group = [b for b in range(m.nbody) if m.body_weldid[b] == m.body_weldid[body]]
        mass_mj = m.body_mass[group].sum()
        com_mj = (m.body_mass[group, None] * d.xipos[group]).sum(0) / mass_mj
        inertia = full.inertias[jid]
        assert abs(inertia.mass - mass_mj) < 1e-12, full.names[jid]
        np.testing.assert_allclose(data.oMi[jid].act(inertia.lever), com_mj, atol=1e-9)
    # The base (welded to the world) and total mass.
    assert (
        abs(sum(i.mass for i in full.inertias) - m.body_mass[m.body("base_link").id :].sum()) < 1e-9
    )


def test_held_configuration_does_not_drift(ur5):
    """The servo holds q exactly (integral action), with and without gravity load changes."""
    sim = Simulation()
    q = np.array([0.2, -1.7, 1.8, -1.7, -1.57, 0.4])
    sim.reset_arm(q + 0.03)
    sim.q_des = q
    sim.hold(1.0)
    np.testing.assert_allclose(sim.q, q, atol=1e-6)
    np.testing.assert_allclose(sim.qd, 0.0, atol=1e-5)


def test_saved_world_xml_is_the_world_the_experiments_run(tmp_path):
    """`comgrasp scene` writes one MJCF file; MuJoCo reading it back gives the same world:
    the same bodies at the same places at the home keyframe, the same masses and options."""
    from comgrasp_pin.simulation.objects import add_object, get_object
    from comgrasp_pin.simulation.scene import Scene, save_world_xml
    from comgrasp_pin.simulation.world import build_spec

    path = save_world_xml(tmp_path / "world.xml", "obj3", seed=4)
    saved = mujoco.MjModel.from_xml_path(str(path))
    scene = Scene.sample("obj3", 4)
    rod = get_object("obj3").scaled(scene.length)
    spec = build_spec(extras=[lambda s: add_object(s, rod, (scene.x, scene.y, scene.yaw),
                                                   pos_real=scene.pos_real)])  # fmt: skip
    built = spec.compile()
    assert [saved.body(i).name for i in range(saved.nbody)] == [
        built.body(i).name for i in range(built.nbody)
    ]
    np.testing.assert_allclose(saved.body_mass, built.body_mass, rtol=1e-9)
    assert saved.opt.timestep == built.opt.timestep
    assert saved.opt.noslip_iterations == built.opt.noslip_iterations
    datas = []
    for model in (saved, built):
        data = mujoco.MjData(model)
        mujoco.mj_resetDataKeyframe(model, data, model.key("home").id)
        mujoco.mj_forward(model, data)
        datas.append(data)
    # MuJoCo writes 6 significant digits: the rod's pose comes back to within a micrometre
    np.testing.assert_allclose(datas[0].xpos, datas[1].xpos, atol=1e-6)
    np.testing.assert_allclose(datas[0].qfrc_bias, datas[1].qfrc_bias, atol=1e-5)
