"""The payload's inertia from a motion's wrench (robot_io.from_motion.wrench_dynamic and its
modules).

Independent reference: the wrench is Pinocchio's RNEA of the arm with everything beyond the
sensor (tool and payload) on a locked joint at the sensor frame: the force that joint passes
(``data.f``), negated, is the tool side's wrench on the sensor; its joint torques are the
loaded arm's. No payload regressor, no bodyRegressor. The convention is checked at rest
against f = m g, tau = c x m g written out here; the parameters' frame change against the
parallel-axis theorem.
"""

import json

import numpy as np
import pinocchio as pin
import pytest
from test_dynamic_estimate import normal_score

from comgrasp_pin.errors import InvalidInputError, LogError, MotionLogError, UnobservableError
from comgrasp_pin.estimation.inertial_fit import pseudo_inertia
from comgrasp_pin.robot import RobotModel
from comgrasp_pin.robot_io.from_motion.wrench_dynamic import estimate_wrench_dynamic
from comgrasp_pin.robot_io.from_motion.wrench_system import nominal_tool, params_map
from comgrasp_pin.robot_io.log_files.log_types import WrenchLog
from comgrasp_pin.robot_io.results.estimate_result import TOOL_EMPTY_RUN, TOOL_GIVEN, TOOL_NOMINAL
from comgrasp_pin.robot_io.results.result_file import result_dict

RATE = 250.0
SENSOR = "ft_sensor"
PAYLOAD = pin.Inertia(0.8, np.array([0.02, -0.01, 0.08]), np.diag([4e-3, 5e-3, 3e-3]))
BIAS = np.array([1.5, -2.0, 3.0, 0.1, -0.05, 0.2])
# wrist_3_link's own inertial, as the URDF writes it (the rest of the last link is the tool)
WRIST_3 = pin.Inertia(0.1879, np.zeros(3), np.diag([0.0171364731454, 0.0171364731454, 0.033822]))


@pytest.fixture(scope="module")
def robot():
    return RobotModel.ur5()


def fourier_motion(robot, duration=16.0, seed=0, amplitude=0.5, joints=None):
    """A smooth motion at rest at both ends: each moving joint four windowed harmonics."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, duration, 1 / RATE)
    w = 2 * np.pi / (duration / 2)
    q = np.tile([0.0, -1.6, 1.6, -1.57, -1.57, 0.0], (len(t), 1))
    window = np.sin(np.pi * t / duration) ** 2
    for j in range(robot.nq) if joints is None else joints:
        for h in range(1, 5):
            a, b = rng.normal(0, amplitude / h / 2, 2)
            q[:, j] += window * (a * np.sin(h * w * t) + b * (np.cos(h * w * t) - 1))
    qd = np.gradient(q, t, axis=0)
    return t, q, qd, np.gradient(qd, t, axis=0)


def urdf_tool_in_sensor(robot):
    """The URDF's tool: the last link's merged body less wrist_3_link's own, sensor frame."""
    model = robot.model
    s = model.frames[model.getFrameId(SENSOR)]
    merged = model.inertias[s.parentJoint].toDynamicParameters()
    tool_joint = pin.Inertia.FromDynamicParameters(merged - WRIST_3.toDynamicParameters())
    return s.placement.actInv(tool_joint)


def T_sensor_ee(robot):
    model = robot.model
    s = model.frames[model.getFrameId(SENSOR)]
    return s.placement.actInv(model.frames[robot.ee_frame_id].placement)


def reference(robot, payload_ee, tool_sensor=None):
    """(model, id of the locked joint at the sensor carrying the tool and the payload)."""
    model = pin.Model(robot.model)
    s = model.frames[model.getFrameId(SENSOR)]
    body = urdf_tool_in_sensor(robot) if tool_sensor is None else tool_sensor
    if payload_ee is not None:
        body = body + T_sensor_ee(robot).act(payload_ee)
    model.inertias[s.parentJoint] = WRIST_3
    jid = model.addJoint(s.parentJoint, pin.JointModelRZ(), s.placement, "sensor_lock")
    model.appendBodyToJoint(jid, body, pin.SE3.Identity())
    return model, jid


def wrench_log(robot, payload_ee, motion, tool_sensor=None, noise=(0.1, 0.005), drift=0.0,
               seed=0, tau_std=0.05, tau_payload_ee="same", q_std=1e-5, effort=True):  # fmt: skip
    """The sensor's wrench (+ BIAS, a linear drift, white noise) and the joint torques
    (+ friction, an offset, noise) along ``motion``; ``tau_payload_ee`` another payload for
    the joint torques (an arm model that is wrong)."""
    t, q, qd, qdd = motion
    rng = np.random.default_rng(seed)
    model, jid = reference(robot, payload_ee, tool_sensor)
    data = model.createData()
    z = np.zeros(1)
    W = np.empty((len(t), 6))
    tau = np.empty((len(t), robot.nq))
    for i, (a, b, c) in enumerate(zip(q, qd, qdd)):
        tau[i] = pin.rnea(model, data, np.r_[a, z], np.r_[b, z], np.r_[c, z])[: robot.nq]
        W[i] = -data.f[jid].vector
    if not (isinstance(tau_payload_ee, str) and tau_payload_ee == "same"):
        other, _ = reference(robot, tau_payload_ee, tool_sensor)
        d = other.createData()
        tau = np.array([pin.rnea(other, d, np.r_[a, z], np.r_[b, z], np.r_[c, z])[: robot.nq]
                        for a, b, c in zip(q, qd, qdd)])  # fmt: skip
    f_std, t_std = noise
    W += BIAS + drift * (t / t[-1])[:, None]
    W += rng.standard_normal(W.shape) * np.r_[[f_std] * 3, [t_std] * 3]
    tau += 0.3 * np.tanh(qd / 0.01) + 0.5 * qd + 0.2 + tau_std * rng.standard_normal(tau.shape)
    q_read = q + q_std * rng.standard_normal(q.shape)
    return WrenchLog(t, tuple(robot.joint_names), q_read, W, SENSOR, "synthetic", None,
                     tau if effort else None)  # fmt: skip


def test_the_reference_reads_m_g_and_c_cross_m_g_at_rest(robot):
    """The wrench log's convention (the tool side's wrench on the sensor), checked by hand."""
    q = np.array([0.3, -1.2, 1.4, -0.7, -1.1, 0.4])
    motion = (np.array([0.0, 1.0]), np.tile(q, (2, 1)), np.zeros((2, 6)), np.zeros((2, 6)))
    log = wrench_log(robot, PAYLOAD, motion, noise=(0, 0))
    body = urdf_tool_in_sensor(robot) + T_sensor_ee(robot).act(PAYLOAD)
    s_id = robot.model.getFrameId(SENSOR)
    pin.framesForwardKinematics(robot.model, robot.data, q)
    g_s = robot.data.oMf[s_id].rotation.T @ np.array([0, 0, -9.81])
    np.testing.assert_allclose(robot.model.gravity.linear, [0, 0, -9.81])
    expected = np.r_[body.mass * g_s, np.cross(body.lever, body.mass * g_s)] + BIAS
    np.testing.assert_allclose(log.wrench[0], expected, atol=1e-9)


def test_parameters_move_between_frames_by_the_parallel_axis_theorem():
    rng = np.random.default_rng(3)
    T = pin.SE3(pin.exp3(rng.normal(size=3)), rng.normal(size=3))
    m, c_b = 1.3, rng.normal(size=3) * 0.1
    I_c = np.diag([0.01, 0.02, 0.025])
    pi_b = pin.Inertia(m, c_b, I_c).toDynamicParameters()
    pi_a = params_map(T) @ pi_b
    c_a = T.rotation @ c_b + T.translation
    I_origin = T.rotation @ I_c @ T.rotation.T + m * (c_a @ c_a * np.eye(3) - np.outer(c_a, c_a))
    expected = np.r_[m, m * c_a, I_origin[0, 0], I_origin[0, 1], I_origin[1, 1],
                     I_origin[0, 2], I_origin[1, 2], I_origin[2, 2]]  # fmt: skip
    np.testing.assert_allclose(pi_a, expected, atol=1e-12)


def test_the_nominal_tool_and_the_wrist_link_make_the_last_links_body(robot):
    """What lies beyond the sensor plus wrist_3_link's own inertial (the URDF's numbers) is
    the body Pinocchio's parser merged onto the last joint."""
    tool_ee = pin.Inertia.FromDynamicParameters(nominal_tool(robot, SENSOR))
    ee = robot.model.frames[robot.ee_frame_id]
    merged = robot.model.inertias[ee.parentJoint].toDynamicParameters()
    total = (ee.placement.act(tool_ee) + WRIST_3).toDynamicParameters()
    np.testing.assert_allclose(total, merged, atol=1e-12)
    assert tool_ee.mass == pytest.approx(0.65 + 3 * 0.08)  # palm, fingers, side camera


def _check_payload(est, truth=PAYLOAD, z_max=4.5):
    t = truth.toDynamicParameters()
    z = (est.inertia.params - t) / np.sqrt(np.diag(est.inertia.params_cov))
    assert np.all(np.abs(z) < z_max), z
    assert abs(est.mass - truth.mass) < 0.01 * truth.mass
    assert np.linalg.norm(est.com_ee - truth.lever) < 2e-3
    assert np.linalg.eigvalsh(pseudo_inertia(est.inertia.params)).min() > -1e-12  # consistent
    e = np.linalg.eigvalsh(est.inertia.inertia_com_ee)
    assert e.min() >= -1e-12 and e[0] + e[1] >= e[2] * (1 - 1e-9)


def test_payload_and_bias_from_the_wrench_within_their_stated_uncertainty(robot):
    motion = fourier_motion(robot)
    log = wrench_log(robot, PAYLOAD, motion, drift=0.6, seed=1)
    est = estimate_wrench_dynamic(robot, log, combine_joint_torques=False)
    _check_payload(est)
    # the bias is the mean over the fitted samples of BIAS + the linear drift
    u = est.motion.t / motion[0][-1]
    z_bias = (est.wrench.sensor_bias - BIAS - 0.6 * u.mean()) / est.wrench.sensor_bias_std
    assert np.all(np.abs(z_bias) < 4.5), z_bias
    np.testing.assert_allclose(est.wrench.sensor_bias_drift, 0.6 * (u[-1] - u[0]), atol=0.03)
    assert abs(est.wrench.delay_s) < 2e-3
    assert est.wrench.tool == TOOL_NOMINAL and est.joint_torques is None
    assert set(est.sources) == {"wrench"}
    assert est.sources["wrench"]["mass_kg"] == pytest.approx(1.0)
    assert est.verdict == "unreliable"  # the URDF's tool is never trusted blindly
    assert len(est.reasons) == 1 and "URDF's links beyond the sensor" in est.reasons[0]
    assert est.motion.validation.explained_total > 0.99


@pytest.mark.parametrize("how", ["empty run", "given"])
def test_a_tool_the_urdf_does_not_know_is_fitted_from_an_empty_run_or_given(robot, how):
    """The real tool carries 0.2 kg more than the URDF's (a cable clamp 6 cm out)."""
    clamp = pin.Inertia(0.2, np.array([0.06, 0.0, 0.03]), np.diag([1e-4, 1e-4, 1e-4]))
    tool = urdf_tool_in_sensor(robot) + clamp
    log = wrench_log(robot, PAYLOAD, fourier_motion(robot), tool_sensor=tool, seed=2)
    if how == "empty run":  # another motion, the same sensor with its own noise
        empty = wrench_log(robot, None, fourier_motion(robot, seed=5), tool_sensor=tool, seed=3)
        est = estimate_wrench_dynamic(robot, log, empty_log=empty, combine_joint_torques=False)
        assert est.wrench.tool == TOOL_EMPTY_RUN
        assert any(k.startswith("tool") for k in est.std_parts)
    else:
        tool_ee = T_sensor_ee(robot).actInv(tool).toDynamicParameters()
        est = estimate_wrench_dynamic(robot, log, tool_params=tool_ee,
                                      combine_joint_torques=False)  # fmt: skip
        assert est.wrench.tool == TOOL_GIVEN
    _check_payload(est)
    assert est.verdict == "identified", est.reasons
    nominal = estimate_wrench_dynamic(robot, log, combine_joint_torques=False)
    assert nominal.mass == pytest.approx(PAYLOAD.mass + 0.2, abs=0.01)  # the URDF's tool: wrong


def test_both_sources_used_their_shares_follow_their_noise(robot):
    motion = fourier_motion(robot)
    log = wrench_log(robot, PAYLOAD, motion, seed=4)
    both = estimate_wrench_dynamic(robot, log)
    wrench_only = estimate_wrench_dynamic(robot, log, combine_joint_torques=False)
    _check_payload(both)
    assert both.joint_torques is not None and both.joint_torques.arm_model.startswith("URDF")
    for quantity in ("mass_kg", "com_m", "principal_moments_kgm2"):
        total = np.add(both.sources["wrench"][quantity],
                       both.sources["joint_torques"][quantity])  # fmt: skip
        np.testing.assert_allclose(total, 1.0, atol=1e-9)
    # a 0.1 N sensor against 0.05 N m joint torques: the wrench carries most of the mass
    assert both.sources["wrench"]["mass_kg"] > 0.8
    assert both.wrench.agreement["disagree"] is False
    assert both.cov[0, 0] <= wrench_only.cov[0, 0] * 1.05
    # a sensor 100 times noisier: the joint torques carry most of it
    noisy = wrench_log(robot, PAYLOAD, motion, noise=(10.0, 0.5), seed=4)
    est = estimate_wrench_dynamic(robot, noisy)
    assert est.sources["joint_torques"]["mass_kg"] > 0.8
    assert abs(est.mass - PAYLOAD.mass) < 5 * np.sqrt(est.cov[0, 0])


def test_a_static_prior_is_a_source_of_its_own(robot):
    """A static estimate of the mass to 1 g (and the CoM to 1 mm) beside a noisy sensor: the
    prior carries most of the mass, and the shares still sum to one."""
    log = wrench_log(robot, PAYLOAD, fourier_motion(robot), noise=(2.0, 0.1), seed=8)
    prior = (np.r_[PAYLOAD.mass, PAYLOAD.lever], np.diag([1e-3, 1e-3, 1e-3, 1e-3]) ** 2)
    est = estimate_wrench_dynamic(robot, log, combine_joint_torques=False, prior=prior,
                                  tool_params=nominal_tool(robot, SENSOR))  # fmt: skip
    assert set(est.sources) == {"wrench", "prior"}
    assert est.sources["prior"]["mass_kg"] > 0.5
    for quantity in ("mass_kg", "com_m"):
        total = np.add(est.sources["wrench"][quantity], est.sources["prior"][quantity])
        np.testing.assert_allclose(total, 1.0, atol=1e-9)
    assert abs(est.mass - PAYLOAD.mass) < 4 * np.sqrt(est.cov[0, 0])


def test_sources_that_disagree_make_the_verdict_unreliable(robot):
    """Joint torques as if the arm held 0.3 kg more than the sensor sees: the URDF's arm
    model is wrong by that much."""
    heavier = pin.Inertia(1.1, PAYLOAD.lever, PAYLOAD.inertia)
    log = wrench_log(robot, PAYLOAD, fourier_motion(robot), seed=6, tau_payload_ee=heavier)
    est = estimate_wrench_dynamic(robot, log, tool_params=nominal_tool(robot, SENSOR))
    assert est.wrench.agreement["disagree"]
    assert est.verdict == "unreliable"
    assert any("disagree" in r and "URDF's model of the arm" in r for r in est.reasons)


def test_nothing_held_is_not_a_payload(robot):
    log = wrench_log(robot, None, fourier_motion(robot), seed=7)
    est = estimate_wrench_dynamic(robot, log, tool_params=nominal_tool(robot, SENSOR))
    lo, hi = est.mass - 1.96 * np.sqrt(est.cov[0, 0]), est.mass + 1.96 * np.sqrt(est.cov[0, 0])
    assert lo < 0 < hi
    assert est.verdict == "nothing held" and est.motion.solver_status.startswith("not run")
    assert any("no payload seen" in r for r in est.reasons)


def test_a_motion_that_does_not_turn_the_sensor_is_refused_naming_what_to_move(robot):
    """Only the base turns: gravity keeps its direction in the sensor frame and the sensor
    spins about one axis; the encoders of the still joints read exactly."""
    log = wrench_log(robot, PAYLOAD, fourier_motion(robot, joints=[0], amplitude=1.0), q_std=0)
    with pytest.raises(UnobservableError) as exc:
        estimate_wrench_dynamic(robot, log, combine_joint_torques=False)
    message = str(exc.value)
    assert "Gravity turns by at most 0 deg" in message
    for joint in robot.joint_names[1:]:
        assert joint in message
    assert "I_xx" in message


def test_bad_input_says_what_is_wrong(robot):
    motion = fourier_motion(robot)
    log = wrench_log(robot, PAYLOAD, motion)
    bad = log.wrench.copy()
    bad[10, 2] = np.nan
    with pytest.raises(LogError, match="NaN"):
        WrenchLog(log.time, log.joint_names, log.position, bad, SENSOR)
    short = WrenchLog(log.time[:500], log.joint_names, log.position[:500], log.wrench[:500],
                      SENSOR)  # fmt: skip
    with pytest.raises(MotionLogError, match="at least 3.0 s"):
        estimate_wrench_dynamic(robot, short)
    elsewhere = WrenchLog(log.time, log.joint_names, log.position, log.wrench, "wrist_2_link")
    with pytest.raises(InvalidInputError, match="same link chain"):
        estimate_wrench_dynamic(robot, elsewhere)
    other_sensor = WrenchLog(log.time, log.joint_names, log.position, log.wrench, "tool0")
    with pytest.raises(InvalidInputError, match="same sensor"):
        estimate_wrench_dynamic(robot, log, empty_log=other_sensor)
    with pytest.raises(InvalidInputError, match="not both"):
        estimate_wrench_dynamic(robot, log, empty_log=log, tool_params=np.zeros(10))
    with pytest.raises(InvalidInputError, match="tool_params must be"):
        estimate_wrench_dynamic(robot, log, tool_params=np.zeros(4))


def test_result_json_carries_the_sensor_and_each_source(robot):
    est = estimate_wrench_dynamic(robot, wrench_log(robot, PAYLOAD, fourier_motion(robot)))
    out = json.loads(json.dumps(result_dict(est)))
    for key in "schema_version mass_kg com_m cov std interval95_mass_kg verdict reasons".split():
        assert key in out, key
    for key in "inertia_kgm2 inertia_std_kgm2 params_cov verdict".split():
        assert key in out["inertia"], key
    assert "condition_number" in out["motion"] and "validation" in out["motion"]
    w = out["wrench"]
    assert w["sensor_frame"] == SENSOR and "source" in w["tool"]
    assert len(w["sensor_bias"]) == 6 and len(w["sensor_bias_std"]) == 6
    assert set(out["sources"]) == {"wrench", "joint_torques"}
    assert len(out["motion"]["validation"]["rms_Nm"]) == 6 + robot.nq
    assert out["frame"] == robot.ee_frame and out["mode"] == "a motion's wrench and joint torques"


@pytest.mark.slow
def test_mujoco_wrench_against_the_truth_and_the_joint_torques_on_one_motion():
    """A 1 kg box on the simulated UR5 along one planned excitation (12 s): MuJoCo's
    force/torque sensor at ft_sensor (the realistic FT 300-S class: noise, an episode offset,
    drift) and its link-side joint torques, an empty run of the same motion for each path."""
    from comgrasp_pin.config import sensor_preset, wrench_preset
    from comgrasp_pin.planning.excitation import ExcitationSettings, plan_excitation
    from comgrasp_pin.robot_io.from_motion.dynamic import estimate_payload_dynamic
    from comgrasp_pin.simulation.arm_worlds import arm_robot
    from comgrasp_pin.simulation.payload_motion import MotionSimConfig, simulate_motion
    from comgrasp_pin.simulation.payloads import box

    robot, payload = arm_robot("ur5"), box()
    settings = ExcitationSettings(acceleration_limit=12.0, n_random=200, n_starts=1)
    m = plan_excitation(robot, 12.0, settings=settings, seed=0)
    motion = (m.t, m.q, m.qd, m.qdd)
    kw = dict(sensor=sensor_preset("realistic").torque, wrench=wrench_preset("ft300s"),
              config=MotionSimConfig(rest_s=1.5), offsets_seed=0)  # fmt: skip
    empty_j, empty_w = simulate_motion("ur5", None, *motion, seed=11, **kw)
    log_j, log_w = simulate_motion("ur5", payload, *motion, seed=12, **kw)
    joint = estimate_payload_dynamic(robot, log_j, empty_j)
    wrench = estimate_wrench_dynamic(robot, log_w, empty_log=empty_w, combine_joint_torques=False)
    both = estimate_wrench_dynamic(robot, log_w, empty_log=empty_w)
    truth = np.r_[payload.mass, payload.p_com_ee]
    true_moments, axes = np.linalg.eigh(payload.I_com_ee)
    for est in (joint, wrench, both):
        assert abs(est.mass / payload.mass - 1) < 0.01
        assert np.linalg.norm(est.com_ee - payload.p_com_ee) < 2e-3
        # each z follows Student's t of its variance's dof: through it to the normal's
        # quantile (the joint torques' mass: z 4.1 at 10 dof, score 3.1; the 1 ms step's
        # bias of about 1.5 g, docs/uncertainty.md)
        z = (np.r_[est.mass, est.com_ee] - truth) / np.sqrt(np.diag(est.cov))
        assert np.all(np.abs(normal_score(z, est.dof)) < 4), (z, est.dof)
        for moment, u in zip(true_moments, axes.T):
            std = np.sqrt(np.kron(u, u) @ est.inertia.inertia_cov @ np.kron(u, u))
            z = (u @ est.inertia.inertia_com_ee @ u - moment) / std
            assert abs(normal_score(z, est.inertia.dof)) < 4
            assert abs(u @ est.inertia.inertia_com_ee @ u / moment - 1) < 0.1
        assert est.verdict == "identified", est.reasons
    # the two paths see one payload: they agree within their stated uncertainties
    d = np.r_[wrench.mass, wrench.com_ee] - np.r_[joint.mass, joint.com_ee]
    assert np.all(np.abs(d) < 4 * np.sqrt(np.diag(wrench.cov) + np.diag(joint.cov))), d
    assert both.joint_torques.arm_model == "empty run"
    assert both.wrench.agreement["disagree"] is False
