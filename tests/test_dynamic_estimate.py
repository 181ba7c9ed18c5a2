"""The payload's inertia from a motion (robot_io.from_motion.dynamic, estimation.inertial_fit).

Independent reference: the efforts are Pinocchio's RNEA of the arm with the payload appended
as a body (not the payload regressor under test), plus friction, an offset and white noise;
the log-Cholesky map is checked against the pseudo-inertia's definition.
"""

import json
from dataclasses import replace

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from comgrasp_pin.cli import main
from comgrasp_pin.errors import MotionLogError, UnobservableError
from comgrasp_pin.estimation.inertial_fit import fit_inertial, pi_of_theta, theta_of_pi
from comgrasp_pin.robot import RobotModel
from comgrasp_pin.robot_io import JointLog, write_csv
from comgrasp_pin.robot_io.from_motion.dynamic import estimate_payload_dynamic

PAYLOAD = pin.Inertia(0.8, np.array([0.02, -0.01, 0.08]), np.diag([4e-3, 5e-3, 1e-3]))
RATE = 250.0


@pytest.fixture(scope="module")
def robot():
    return RobotModel.ur5()


def fourier_motion(robot, duration=16.0, seed=0, amplitude=0.5):
    """A smooth motion at rest at both ends: each joint a sum of four harmonics, windowed."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, duration, 1 / RATE)
    w = 2 * np.pi / (duration / 2)
    q = np.tile([0.0, -1.6, 1.6, -1.57, -1.57, 0.0], (len(t), 1))
    window = np.sin(np.pi * t / duration) ** 2
    for j in range(robot.nq):
        for h in range(1, 5):
            a, b = rng.normal(0, amplitude / h / 2, 2)
            q[:, j] += window * (a * np.sin(h * w * t) + b * (np.cos(h * w * t) - 1))
    qd = np.gradient(q, t, axis=0)
    return t, q, qd, np.gradient(qd, t, axis=0)


def arm_efforts(robot, inertia, motion, rng, noise=0.05, offset=0.2, coulomb_speed=0.01):
    """RNEA of the arm with ``inertia`` appended at the ee frame, viscous friction and
    Coulomb friction 0.3 tanh(qd / coulomb_speed) (the model's shape is 0.02), an offset and
    white noise."""
    t, q, qd, qdd = motion
    model = pin.Model(robot.model)
    if inertia is not None:
        frame = model.frames[robot.ee_frame_id]
        model.appendBodyToJoint(frame.parentJoint, inertia, frame.placement)
    data = model.createData()
    tau = np.array([pin.rnea(model, data, a, b, c) for a, b, c in zip(q, qd, qdd)])
    tau += 0.3 * np.tanh(qd / coulomb_speed) + 0.5 * qd + offset
    return tau + noise * rng.standard_normal(tau.shape)


def rnea_log(robot, inertia, motion, noise=0.05, seed=0, offset=0.2):
    """The arm's efforts along ``motion`` with ``inertia`` appended at the ee frame."""
    t, q = motion[0], motion[1]
    rng = np.random.default_rng(seed)
    tau = arm_efforts(robot, inertia, motion, rng, noise, offset)
    q_read = q + 1e-5 * rng.standard_normal(q.shape)
    return JointLog(t, tuple(robot.joint_names), q_read, tau, "synthetic")


@settings(max_examples=50, deadline=None)
@given(st.lists(st.floats(-2, 2), min_size=10, max_size=10))
def test_every_theta_is_a_consistent_body_and_maps_back(theta):
    theta = np.array(theta)
    pi = pi_of_theta(theta)
    m, h = pi[0], pi[1:4]
    inertia = np.array([[pi[4], pi[5], pi[7]], [pi[5], pi[6], pi[8]], [pi[7], pi[8], pi[9]]])
    sigma = 0.5 * np.trace(inertia) * np.eye(3) - inertia  # the second moment of mass
    J = np.block([[sigma, h[:, None]], [h[None, :], np.array([[m]])]])
    assert np.linalg.eigvalsh(J).min() > 0
    # a consistent body: triangle inequalities of the principal moments about the CoM
    c = h / m
    I_c = inertia - m * (c @ c * np.eye(3) - np.outer(c, c))
    e = np.linalg.eigvalsh(I_c)
    assert e[0] + e[1] >= e[2] * (1 - 1e-9) - 1e-12
    np.testing.assert_allclose(theta_of_pi(pi), theta, atol=1e-6)


def test_the_fit_stays_consistent_where_least_squares_does_not():
    """A point mass with noisy rows: the plain solution's pseudo-inertia is indefinite."""
    rng = np.random.default_rng(1)
    A = rng.standard_normal((60, 10))
    truth = pin.Inertia(1.0, np.array([0.0, 0.0, 0.1]), np.zeros((3, 3))).toDynamicParameters()
    b = A @ truth + 0.05 * rng.standard_normal(60)
    fit = fit_inertial(A, np.zeros((60, 0)), b, np.full(60, 20.0))
    from comgrasp_pin.estimation.inertial_fit import pseudo_inertia

    assert np.linalg.eigvalsh(pseudo_inertia(fit.unconstrained_pi)).min() < 0
    assert np.linalg.eigvalsh(pseudo_inertia(fit.pi)).min() > -1e-12
    assert abs(fit.pi[0] - 1.0) < 0.05


@pytest.mark.parametrize("empty_run", [True, False])
def test_payload_from_a_motion_within_its_stated_uncertainty(robot, empty_run):
    motion = fourier_motion(robot)
    log = rnea_log(robot, PAYLOAD, motion, seed=1)
    empty = rnea_log(robot, None, motion, seed=2, offset=0.25) if empty_run else None
    est = estimate_payload_dynamic(robot, log, empty)
    truth = PAYLOAD.toDynamicParameters()
    z = (est.inertia.params - truth) / np.sqrt(np.diag(est.inertia.params_cov))
    assert np.all(np.abs(z) < 4.5), z
    # a random motion (condition number ~2000); the friction and offsets found with the
    # payload take some of its information: the tolerances are the stated std's, above
    tolerance = 1 if empty_run else 3
    assert abs(est.mass - 0.8) < tolerance * 0.01 * 0.8
    assert np.linalg.norm(est.com_ee - PAYLOAD.lever) < tolerance * 2e-3
    assert est.joint_torques.arm_model == ("empty run" if empty_run else "URDF model + friction")
    if not empty_run:  # friction found where the model lacks it: 0.5 N m s/rad viscous and
        # 0.3 N m Coulomb, whose shape (tanh(qd / 0.01)) differs from the model's (0.02)
        np.testing.assert_allclose(est.joint_torques.friction[:, 0], 0.5, atol=0.25)
        np.testing.assert_allclose(est.joint_torques.friction[:, 1], 0.3, atol=0.1)


MC_PAYLOAD = pin.Inertia(0.8, np.array([0.02, -0.01, 0.08]), np.diag([4e-3, 5e-3, 3e-3]))
"""PAYLOAD with its spread inside the consistent set (PAYLOAD's own is flat along y: the
consistent fit's errors there are cut at the boundary and its error bars read wide)."""
MC_DRAWS = 40
RMS_Z_BAND = (0.7, 1.45)
"""The pooled rms normal score of the ten parameters over MC_DRAWS noise draws: each z taken
through Student's t of its variance's degrees of freedom to the normal's quantile, so that a
calibrated interval gives 1 whatever the degrees of freedom (a t variable's own rms is
sqrt(nu / (nu - 2)), 1.29 at nu = 5). Its sampling spread over 40 draws is about 0.06. A
variance 3 times too large or too small gives about 0.55 or 1.7, and fails."""
GROUP_BAND = (0.6, 1.6)
"""Each group alone (the mass; the CoM; the inertia about the CoM): fewer values, wider band."""


def dynamic_z(robot, draws=MC_DRAWS, seed=100, duration=8.0, empty_run=True):
    """(draws, 20) normal scores of the ten parameters (params_cov), of (mass, CoM) (cov) and
    of the six entries of the inertia about the CoM (inertia_cov), each draw with its own
    noise on the loaded and the empty run (or no empty run: the URDF model and friction),
    against the appended body's truth. A short (8 s) motion: each draw costs about 0.1 s."""
    motion = fourier_motion(robot, duration=duration)
    truth = MC_PAYLOAD.toDynamicParameters()
    upper = [0, 1, 2, 4, 5, 8]  # the inertia's six entries in the flattened (3, 3)
    z = []
    for i in range(draws):
        log = rnea_log(robot, MC_PAYLOAD, motion, seed=seed + 2 * i)
        empty = rnea_log(robot, None, motion, seed=seed + 2 * i + 1, offset=0.25)
        est = estimate_payload_dynamic(robot, log, empty if empty_run else None)
        z_params = (est.inertia.params - truth) / np.sqrt(np.diag(est.inertia.params_cov))
        z_com = np.r_[est.mass - MC_PAYLOAD.mass, est.com_ee - MC_PAYLOAD.lever]
        z_com /= np.sqrt(np.diag(est.cov))
        z_inertia = (est.inertia.inertia_com_ee - MC_PAYLOAD.inertia).ravel()
        z_inertia = (z_inertia / np.sqrt(np.diag(est.inertia.inertia_cov)))[upper]
        dof = np.r_[est.inertia.params_dof, est.dof, np.full(6, est.inertia.dof)]
        z.append(normal_score(np.r_[z_params, z_com, z_inertia], dof))
    return np.array(z)


def normal_score(z: np.ndarray, dof: np.ndarray) -> np.ndarray:
    """z (Student's t with ``dof``) mapped to the normal's quantile of the same probability."""
    from scipy.stats import norm, t

    p = t.cdf(z, np.where(np.isfinite(dof), dof, 1e12))
    return norm.ppf(np.clip(p, 1e-15, 1 - 1e-15))


def rms_z_groups(z: np.ndarray) -> dict:
    """rms z of the ten parameters pooled, and of each derived group."""
    groups = {"params": z[:, :10], "mass": z[:, 10], "com": z[:, 11:14], "inertia_com": z[:, 14:]}
    return {name: float(np.sqrt(np.mean(v**2))) for name, v in groups.items()}


def check_rms_z(rms: dict) -> None:
    lo, hi = RMS_Z_BAND
    assert lo < rms["params"] < hi, rms
    lo, hi = GROUP_BAND
    assert all(lo < v < hi for v in rms.values()), rms


def test_the_motion_error_bars_are_neither_too_wide_nor_too_narrow(robot):
    """Two-sided Monte Carlo (issue 33, item 7): the rms normal score over repeated noise
    draws lies in a band, so a covariance three times too wide or too narrow in variance fails
    (the |z| < 4.5 above passes a covariance 100 times too wide)."""
    check_rms_z(rms_z_groups(dynamic_z(robot)))


def test_the_urdf_model_path_error_bars_are_neither_too_wide_nor_too_narrow(robot):
    """The same check without an empty run: the arm's torques from the URDF model, offsets
    and friction fitted with the payload, the friction's shape not the model's (a model
    error the same in every draw). Too wide (rms z of the inertia 0.47) while a delete-a-block
    jackknife widened the white noise's covariance (issue 33); right with the block sandwich
    (CR2) and its degrees of freedom (issue 42)."""
    check_rms_z(rms_z_groups(dynamic_z(robot, draws=24, duration=16.0, empty_run=False)))


def test_logged_velocities_are_used(robot):
    motion = fourier_motion(robot, seed=3)
    log = rnea_log(robot, PAYLOAD, motion, seed=4)
    noisy = motion[2] + 0.01 * np.random.default_rng(0).standard_normal(motion[2].shape)
    est = estimate_payload_dynamic(robot, replace(log, velocity=noisy))
    assert est.motion.velocity_from == "log"
    assert abs(est.mass - 0.8) < 0.01 * 0.8


def _still(robot):
    t = np.arange(0, 10, 1 / RATE)
    return t, np.tile([0.0, -1.6, 1.6, -1.57, -1.57, 0.0], (len(t), 1))


def test_bad_motion_logs_say_what_is_wrong(robot):
    motion = fourier_motion(robot)
    good = rnea_log(robot, PAYLOAD, motion)
    t, q = _still(robot)
    cases = {
        "barely moves": JointLog(t, good.joint_names, q, np.zeros_like(q)),
        "lasts": JointLog(
            good.time[:500], good.joint_names, good.position[:500], good.effort[:500]
        ),  # fmt: skip
        "gap": JointLog(
            np.delete(good.time, range(1000, 1200)),
            good.joint_names,
            np.delete(good.position, range(1000, 1200), axis=0),
            np.delete(good.effort, range(1000, 1200), axis=0),
        ),  # fmt: skip
    }
    jerky = good.position.copy()
    jerky[::2, 4] += 0.05  # a 125 Hz square wave on a wrist joint
    cases["jerkily"] = replace(good, position=jerky)
    at_limit = good.position.copy()
    at_limit[:, 0] = np.clip(at_limit[:, 0] + 2 * np.pi, None, robot.q_upper[0])
    cases["limit"] = replace(good, position=at_limit)
    for words, log in cases.items():
        with pytest.raises(MotionLogError, match=words):
            estimate_payload_dynamic(robot, log)


def test_cli_writes_the_inertia_and_exports_carry_it(robot, tmp_path, capsys):
    from comgrasp_pin._paths import urdf_path

    # 20 s: with an empty run the still ends and EDGE_S inside them are not used
    # (motion_samples' crop), and 16 s of this motion then leave the inertia not determined
    motion = fourier_motion(robot, duration=20.0, seed=5)
    loaded = write_csv(rnea_log(robot, PAYLOAD, motion, seed=6), tmp_path / "loaded.csv")
    empty = write_csv(rnea_log(robot, None, motion, seed=7), tmp_path / "empty.csv")
    out, franka = tmp_path / "RESULT.json", tmp_path / "load.json"
    args = ["estimate", "--dynamic", "--urdf", str(urdf_path("ur5_gripper.urdf")),
            "--ee-frame", "eelink", "--csv", str(loaded), "--empty-csv", str(empty),
            "--out", str(out), "--export-franka", str(franka)]  # fmt: skip
    assert main(args) == 0
    result = json.loads(out.read_text())
    I = np.array(result["inertia"]["inertia_kgm2"])
    assert I.shape == (3, 3) and np.allclose(I, I.T)
    assert np.array(result["inertia"]["params_cov"]).shape == (10, 10)
    assert (
        result["motion"]["condition_number"] > 1
        and result["joint_torques"]["arm_model"] == "empty run"
    )
    load = json.loads(franka.read_text())
    np.testing.assert_allclose(np.reshape(load["load_inertia"], (3, 3), order="F"), I, atol=1e-12)
    assert "identified" in load["comment"]
    assert "principal moments" in capsys.readouterr().out
    # a still log: exit 2 with the reason, nothing written
    t, q = _still(robot)
    still = write_csv(JointLog(t, tuple(robot.joint_names), q, np.zeros_like(q)),
                      tmp_path / "still.csv")  # fmt: skip
    out2 = tmp_path / "R2.json"
    assert main(args[:6] + ["--csv", str(still), "--out", str(out2)]) == 2
    assert "barely moves" in capsys.readouterr().err
    assert not out2.exists()


def test_a_line_of_mass_converges_at_the_spread_bound():
    """A rod of no thickness: its mass has no spread about its axis, the optimum lies on the
    consistency boundary (d at minus infinity); the fit converges within LOG_SPREAD_MIN,
    recovers the rod, and its covariance stays finite."""
    from comgrasp_pin.estimation.inertial_fit import LOG_SPREAD_MIN

    rng = np.random.default_rng(3)
    rod = pin.Inertia(0.6, np.array([0.06, 0.0, 0.0]), np.diag([0.0, 4.5e-3, 4.5e-3]))
    A = rng.standard_normal((400, 10)) * np.array([10, 1, 1, 1, 30, 30, 30, 30, 30, 30])
    b = A @ rod.toDynamicParameters()  # exact: the optimum has no spread at all
    fit = fit_inertial(A, np.zeros((400, 0)), b, np.full(400, 1e4))
    assert fit.return_status in ("Solve_Succeeded", "Solved_To_Acceptable_Level")
    assert fit.theta[1:4].min() >= LOG_SPREAD_MIN - 1e-9
    np.testing.assert_allclose(fit.pi, rod.toDynamicParameters(), atol=2e-4)
    assert np.all(np.isfinite(fit.cov))
    # the second moment along the rod's axis, (I_yy + I_zz - I_xx) / 2, sits at its bound
    # (zero): the Hessian in theta is flat along its log-spread, yet the data determine it;
    # its variance is the data's (the weighted least squares'), not the zero a pseudo-inverse
    # of the flat Hessian gave
    u = np.zeros(10)
    u[[4, 6, 9]] = [-0.5, 0.5, 0.5]
    Aw = A * 1e4
    assert u @ fit.cov @ u == pytest.approx(u @ np.linalg.inv(Aw.T @ Aw) @ u, rel=1e-6)


def _one_joint_motion(robot, joint: int):
    """The Fourier motion with every joint but ``joint`` held still, positions exact."""
    t, q, qd, qdd = fourier_motion(robot, duration=8.0)
    still = np.arange(robot.nq) != joint
    q[:, still] = q[0, still]
    qd[:, still] = qdd[:, still] = 0.0
    return t, q, qd, qdd


@pytest.mark.parametrize("joint", [0, 5])
@pytest.mark.parametrize("empty_run", [True, False])
def test_a_parameter_no_motion_moves_is_refused_not_given_zero_variance(robot, joint, empty_run):
    """One joint moving cannot tell every parameter (the base joint: the inertia about a
    vertical axis only; the last wrist joint: the mass from the offsets). The estimate is
    refused, naming what it cannot determine; a pseudo-inverse gave those directions zero
    variance and the last wrist joint's motion a confident 0.78 +- 0.003 kg "identified"
    payload of 0.8 kg."""
    motion = _one_joint_motion(robot, joint)
    log = replace(rnea_log(robot, PAYLOAD, motion, seed=1), position=motion[1])
    empty = replace(rnea_log(robot, None, motion, seed=2), position=motion[1])
    with pytest.raises(UnobservableError, match="does not determine (m|I_)"):
        estimate_payload_dynamic(robot, log, empty if empty_run else None)


def test_a_flat_information_direction_is_refused_by_name():
    """The inertial fit's covariance inverts pi's Hessian; a flat direction (two parameters
    the rows see only together) is refused with their names, not given zero variance."""
    from comgrasp_pin.estimation.inertial_fit import covariance

    A = np.random.default_rng(0).standard_normal((60, 10))
    A[:, 5] = 2 * A[:, 4]  # I_xy seen only with I_xx
    with pytest.raises(UnobservableError, match=r"I_xx \+ I_xy"):
        covariance(A.T @ A)
    A[:, 5] += 1e-3 * np.random.default_rng(1).standard_normal(60)  # barely seen: huge
    assert np.sqrt(covariance(A.T @ A)[5, 5]) > 100 * np.sqrt(covariance(A.T @ A)[0, 0])
