"""estimate_com: exact inversion of RNEA-with-payload torques, uncertainty, CRB, bad input."""

import dataclasses

import numpy as np
import pytest
from _payload import panda, payload_torques, ur10
from hypothesis import given, settings
from hypothesis import strategies as st

import comgrasp_pin as cg
from comgrasp_pin.estimation import ipopt as _lsq_ipopt

ROBOTS = {"ur5": cg.RobotModel.ur5, "panda": panda, "ur10": ur10}
MASS, COM_EE = 0.7, np.array([0.04, -0.03, 0.15])


@pytest.fixture(scope="module")
def ur5() -> cg.RobotModel:
    return cg.RobotModel.ur5()


@pytest.fixture(scope="module", params=list(ROBOTS))
def robot(request) -> cg.RobotModel:
    return ROBOTS[request.param]()


def perpendicular(c: np.ndarray, u: np.ndarray) -> np.ndarray:
    return c - (c @ u) * u


def wrist_poses(robot: cg.RobotModel, q: np.ndarray, k: int, rng) -> np.ndarray:
    offsets = np.zeros((k, robot.nq))
    offsets[1:, -3:] = rng.uniform(-0.8, 0.8, size=(k - 1, 3))
    return q + offsets


@pytest.mark.parametrize("method", ["lstsq", "ipopt"])
def test_exact_inversion_one_pose(robot, method):
    rng = np.random.default_rng(10)
    for _ in range(4):
        q = robot.random_configuration(rng)
        tau_before, tau_after = payload_torques(robot, q, MASS, COM_EE)
        est = cg.estimate_com(robot, q, tau_before, tau_after, method=method)
        u = est.unobservable_ee
        np.testing.assert_allclose(robot.ee_pose(q)[:3, :3] @ u, [0, 0, -1], atol=1e-12)
        assert abs(est.mass - MASS) <= 1e-9 * MASS
        np.testing.assert_allclose(est.com_ee, perpendicular(COM_EE, u), atol=1e-9)
        assert abs(est.com_ee @ u) < 1e-12
        assert est.residual_rms < 1e-10 and est.n_poses == 1
        assert est.weight == pytest.approx(MASS * 9.81, rel=1e-9)


@pytest.mark.parametrize("method", ["lstsq", "ipopt"])
def test_exact_inversion_several_poses(robot, method):
    rng = np.random.default_rng(11)
    Q = wrist_poses(robot, robot.random_configuration(rng), 4, rng)
    tau_before, tau_after = payload_torques(robot, Q, MASS, COM_EE)
    est = cg.estimate_com(robot, Q, tau_before, tau_after, method=method)
    assert est.unobservable_ee is None and est.n_poses == 4
    assert abs(est.mass - MASS) <= 1e-9 * MASS
    np.testing.assert_allclose(est.com_ee, COM_EE, atol=1e-9)
    assert est.residuals.shape == (4, robot.nq)
    np.testing.assert_allclose(
        est.com_world(2), (robot.ee_pose(Q[2]) @ np.r_[COM_EE, 1])[:3], atol=1e-9
    )


def test_ipopt_solver_is_built_once_and_reports(ur5):
    rng = np.random.default_rng(12)
    Q = wrist_poses(ur5, ur5.random_configuration(rng), 3, rng)
    tau_before, tau_after = payload_torques(ur5, Q, MASS, COM_EE)
    noisy = tau_after + rng.normal(scale=0.01, size=Q.shape)
    before = _lsq_ipopt.build.cache_info()
    first = cg.estimate_com(ur5, Q, tau_before, noisy, method="ipopt")
    second = cg.estimate_com(ur5, Q, tau_before, noisy, method="ipopt")
    after = _lsq_ipopt.build.cache_info()
    assert after.misses - before.misses <= 1 and after.hits - before.hits >= 1
    # warm-started at the closed form, IPOPT confirms it (or cannot step: at the optimum)
    assert first.solver_status in ("Solve_Succeeded", "Search_Direction_Becomes_Too_Small")
    assert first.iterations <= 2
    assert second.com_ee.tolist() == first.com_ee.tolist()
    closed = cg.estimate_com(ur5, Q, tau_before, noisy, method="lstsq")
    assert closed.solver_status == "closed_form" and closed.iterations == 0
    np.testing.assert_allclose(first.com_ee, closed.com_ee, atol=1e-10)
    assert first.mass == pytest.approx(closed.mass, rel=1e-10)


def test_ipopt_failure_raises_solver_error(ur5, monkeypatch):
    """IPOPT stopped after no iteration (a real failure, not a stub): SolverError with its
    status; the prior's problem starts away from its optimum."""
    monkeypatch.setitem(_lsq_ipopt.IPOPT_OPTIONS, "ipopt.max_iter", 0)
    _lsq_ipopt.build.cache_clear()
    q = ur5.random_configuration(np.random.default_rng(13))
    tau_before, tau_after = payload_torques(ur5, q, MASS, COM_EE)
    prior = cg.AxisPrior(COM_EE + [0.0, 0.0, 0.02], [1.0, 0.0, 0.0], 0.005)
    try:
        with pytest.raises(cg.SolverError, match="Maximum_Iterations_Exceeded") as info:
            cg.estimate_com(ur5, q, tau_before, tau_after, method="ipopt", torque_std=0.01,
                            com_prior=prior)  # fmt: skip
        assert info.value.return_status == "Maximum_Iterations_Exceeded"
    finally:
        _lsq_ipopt.build.cache_clear()


def test_same_wrist_orientation_leaves_gravity_direction_unobservable(ur5):
    """Poses that differ only by the base joint keep gravity fixed in the ee frame."""
    q = ur5.random_configuration(np.random.default_rng(14))
    Q = np.array([q + [d, 0, 0, 0, 0, 0] for d in (0.0, 0.4, -0.7)])
    tau_before, tau_after = payload_torques(ur5, Q, MASS, COM_EE)
    for method in ("lstsq", "ipopt"):
        est = cg.estimate_com(ur5, Q, tau_before, tau_after, method=method, torque_std=0.01)
        u = est.unobservable_ee
        np.testing.assert_allclose(u, -ur5.ee_pose(q)[2, :3], atol=1e-9)
        np.testing.assert_allclose(est.com_ee, perpendicular(COM_EE, u), atol=1e-9)
        assert est.singular_values[3] < 1e-9 * est.singular_values[0]
        assert abs(u @ est.cov[1:, 1:] @ u) < 1e-15


def test_result_is_frozen_and_read_only(ur5):
    q = ur5.random_configuration(np.random.default_rng(15))
    est = cg.estimate_com(ur5, q, *payload_torques(ur5, q, MASS, COM_EE))
    with pytest.raises(dataclasses.FrozenInstanceError):
        est.mass = 1.0
    with pytest.raises(ValueError, match="read-only"):
        est.com_ee[0] = 1.0
    # without torque_std the noise comes from the residuals (6 readings, 3 unknowns); these
    # are exact, so it is the floor (1e-6 N m on a difference of two readings)
    assert est.torque_std == pytest.approx(1e-6 / np.sqrt(2)) and est.cov is not None
    point, direction = est.com_line_ee()
    np.testing.assert_allclose(point + (COM_EE @ direction) * direction, COM_EE, atol=1e-9)
    assert est.singular_values.shape == (4,) and est.singular_values[3] == 0.0
    assert est.condition_number == pytest.approx(est.singular_values[0] / est.singular_values[2])


# --- uncertainty --------------------------------------------------------------------------


def fisher_information(robot, Q, mass, com_ee, sigma, basis=None):
    """Fisher information of psi = (m, com_ee) (or (m, basis^T com_ee)) for dtau ~
    N(mu(psi), 2 sigma^2 I), mu from RNEA with a payload, by central differences."""
    basis = np.eye(3) if basis is None else basis
    psi0 = np.r_[mass, basis.T @ com_ee]
    rest = com_ee - basis @ (basis.T @ com_ee)

    def mu(psi):
        tau_before, tau_after = payload_torques(robot, Q, psi[0], basis @ psi[1:] + rest)
        return (tau_after - tau_before).ravel()

    h = 1e-6
    D = np.column_stack(
        [(mu(psi0 + h * e) - mu(psi0 - h * e)) / (2 * h) for e in np.eye(len(psi0))]
    )
    weights = np.tile(
        1.0 / (2.0 * np.broadcast_to(sigma, Q.shape[-1:]) ** 2), len(D) // Q.shape[-1]
    )
    return D.T @ (weights[:, None] * D)


def test_cov_is_the_cramer_rao_bound_several_poses(ur5):
    rng = np.random.default_rng(16)
    Q = cg.plan_wrist_poses(ur5, 4, ur5.random_configuration(rng)).q
    tau_before, tau_after = payload_torques(ur5, Q, MASS, COM_EE)
    for sigma in (0.05, np.array([0.02, 0.05, 0.05, 0.03, 0.08, 0.1])):
        crb = np.linalg.inv(fisher_information(ur5, Q, MASS, COM_EE, sigma))
        for method in ("lstsq", "ipopt"):
            est = cg.estimate_com(ur5, Q, tau_before, tau_after, method=method, torque_std=sigma)
            np.testing.assert_allclose(est.cov, crb, rtol=1e-6, atol=1e-14)


def test_cov_is_the_cramer_rao_bound_one_pose(ur5):
    q = ur5.random_configuration(np.random.default_rng(17))
    tau_before, tau_after = payload_torques(ur5, q, MASS, COM_EE)
    est = cg.estimate_com(ur5, q, tau_before, tau_after, torque_std=0.05)
    E = np.linalg.svd(est.unobservable_ee[None])[2][1:].T  # the observable CoM directions
    crb = np.linalg.inv(fisher_information(ur5, q[None], MASS, COM_EE, 0.05, basis=E))
    P = np.zeros((3, 4))
    P[0, 0], P[1:, 1:] = 1.0, E.T
    np.testing.assert_allclose(P @ est.cov @ P.T, crb, rtol=1e-6, atol=1e-14)


@pytest.mark.parametrize("poses", [1, 4])
def test_cov_matches_empirical_spread(ur5, poses):
    """sigma = 0.05 N m on every reading, 500 draws: RMS error per component within 15 %."""
    rng = np.random.default_rng(18)
    q = ur5.random_configuration(rng)
    Q = cg.plan_wrist_poses(ur5, poses, q).q if poses > 1 else q
    mass, com_ee = 2.0, COM_EE
    tau_before, tau_after = payload_torques(ur5, Q, mass, com_ee)
    sigma = 0.05
    est0 = cg.estimate_com(ur5, Q, tau_before, tau_after, torque_std=sigma)
    truth = np.r_[mass, com_ee if poses > 1 else perpendicular(com_ee, est0.unobservable_ee)]
    errors = []
    for _ in range(500):
        noisy_before = tau_before + rng.normal(scale=sigma, size=np.shape(Q))
        noisy_after = tau_after + rng.normal(scale=sigma, size=np.shape(Q))
        est = cg.estimate_com(ur5, Q, noisy_before, noisy_after, torque_std=sigma)
        errors.append(np.r_[est.mass, est.com_ee] - truth)
    rms = np.sqrt(np.mean(np.square(errors), axis=0))
    predicted = est0.std
    np.testing.assert_allclose(rms / predicted, 1.0, atol=0.15)


# --- property-based ---------------------------------------------------------------------


@settings(max_examples=30, deadline=None)
@given(
    seed=st.integers(0, 2**32 - 1),
    mass=st.floats(0.05, 5.0),
    com=st.lists(st.floats(-0.25, 0.25), min_size=3, max_size=3),
    method=st.sampled_from(["lstsq", "ipopt"]),
)
def test_property_exact_inversion(ur5, seed, mass, com, method):
    rng = np.random.default_rng(seed)
    com_ee = np.array(com)
    q = ur5.random_configuration(rng)
    tau_before, tau_after = payload_torques(ur5, q, mass, com_ee)
    est = cg.estimate_com(ur5, q, tau_before, tau_after, method=method)
    tol = 1e-13 * est.condition_number**2 + 1e-11
    assert abs(est.mass - mass) <= tol * mass
    np.testing.assert_allclose(est.com_ee, perpendicular(com_ee, est.unobservable_ee), atol=tol)
    Q = wrist_poses(ur5, q, 3, rng)
    tb3, ta3 = payload_torques(ur5, Q, mass, com_ee)
    full = cg.estimate_com(ur5, Q, tb3, ta3, method=method)
    assert full.unobservable_ee is None
    tol3 = 1e-13 * full.condition_number**2 + 1e-11
    assert abs(full.mass - mass) <= tol3 * mass
    np.testing.assert_allclose(full.com_ee, com_ee, atol=tol3)


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), factor=st.floats(0.2, 5.0))
def test_property_linearity_and_invariance(ur5, seed, factor):
    """Scaling dtau scales the mass and keeps the CoM (and scales the CoM's covariance)."""
    rng = np.random.default_rng(seed)
    q = ur5.random_configuration(rng)
    tau_before, tau_after = payload_torques(ur5, q, MASS, COM_EE)
    dtau = tau_after - tau_before
    base = cg.estimate_com(ur5, q, tau_before, tau_after)
    scaled = cg.estimate_com(ur5, q, tau_before, tau_before + factor * dtau)
    assert scaled.mass == pytest.approx(factor * base.mass, rel=1e-9)
    np.testing.assert_allclose(scaled.com_ee, base.com_ee, atol=1e-10)
    with_std = cg.estimate_com(ur5, q, tau_before, tau_after, torque_std=1e-4)
    scaled_std = cg.estimate_com(ur5, q, tau_before, tau_before + factor * dtau, torque_std=1e-4)
    # sigma(m) does not scale; sigma(c) = sigma(m c) / m scales as 1 / factor
    assert scaled_std.std[0] == pytest.approx(with_std.std[0], rel=1e-9)
    np.testing.assert_allclose(scaled_std.std[1:] * factor, with_std.std[1:], rtol=1e-6)


# --- bad input ---------------------------------------------------------------------------


@pytest.fixture(scope="module")
def good(ur5):
    q = ur5.random_configuration(np.random.default_rng(20))
    return (q, *payload_torques(ur5, q, MASS, COM_EE))


def test_bad_shapes(ur5, good):
    q, tb, ta = good
    cases = [
        ((q[:5], tb, ta), "q must have shape"),
        ((q, tb[:5], ta), "tau_before has shape"),
        ((q, tb, np.r_[ta, 0.0]), "tau_after has shape"),
        ((np.tile(q, (2, 1)), np.tile(tb, (3, 1)), np.tile(ta, (2, 1))), "tau_before has shape"),
        ((q[None, None], tb[None, None], ta[None, None]), "q must have shape"),
        ((np.empty((0, 6)), np.empty((0, 6)), np.empty((0, 6))), "k >= 1"),
        ((["a"] * 6, tb, ta), "not a numeric array"),
    ]
    for args, message in cases:
        for method in ("lstsq", "ipopt"):
            with pytest.raises(cg.InvalidInputError, match=message):
                cg.estimate_com(ur5, *args, method=method)


@pytest.mark.parametrize("which", [0, 1, 2])
@pytest.mark.parametrize("value", [np.nan, np.inf, -np.inf])
def test_non_finite_input(ur5, good, which, value):
    args = [a.copy() for a in good]
    args[which][3] = value
    name = ["q", "tau_before", "tau_after"][which]
    for method in ("lstsq", "ipopt"):
        with pytest.raises(cg.InvalidInputError, match=f"{name} contains NaN or inf"):
            cg.estimate_com(ur5, *args, method=method)


def test_bad_options(ur5, good):
    with pytest.raises(cg.InvalidInputError, match="unknown method 'gd'"):
        cg.estimate_com(ur5, *good, method="gd")
    for std in (-0.1, 0.0, np.nan, np.array([0.1, 0.1])):
        with pytest.raises(cg.InvalidInputError, match="torque_std"):
            cg.estimate_com(ur5, *good, torque_std=std)
    with pytest.raises(cg.InvalidInputError, match="rcond"):
        cg.estimate_com(ur5, *good, rcond=0.0)


def test_empty_gripper(ur5, good):
    q, tb, ta = good
    for method in ("lstsq", "ipopt"):
        with pytest.raises(cg.EmptyGripperError, match="not measurably above zero"):
            cg.estimate_com(ur5, q, tb, tb, method=method)
        with pytest.raises(cg.EmptyGripperError, match="swapped"):
            cg.estimate_com(ur5, q, ta, tb, method=method)  # negative mass
    tiny_before, tiny_after = payload_torques(ur5, q, 0.005, COM_EE)  # 5 g under 0.05 N m noise
    with pytest.raises(cg.EmptyGripperError, match="3 standard deviations"):
        cg.estimate_com(ur5, q, tiny_before, tiny_after, torque_std=0.05)
    assert cg.estimate_com(ur5, q, tiny_before, tiny_after).mass == pytest.approx(0.005)


SCARA_URDF = """<robot name="scara">
  <link name="base"/>
  <link name="l1"><inertial><mass value="1"/><origin xyz="0.2 0 0"/>
    <inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="l2"><inertial><mass value="1"/><origin xyz="0.2 0 0"/>
    <inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="tool"/>
  <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/>
    <axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="10" velocity="1"/></joint>
  <joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/><origin xyz="0.4 0 0"/>
    <axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="10" velocity="1"/></joint>
  <joint name="j3" type="revolute"><parent link="l2"/><child link="tool"/>
    <origin xyz="0.4 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="10" velocity="1"/></joint>
</robot>"""


def test_mass_unobservable(tmp_path):
    """A SCARA's vertical joints bear none of the weight: no pose set shows the mass."""
    path = tmp_path / "scara.urdf"
    path.write_text(SCARA_URDF)
    scara = cg.RobotModel.from_urdf(path, "tool")
    q = np.array([0.3, -0.5, 0.2])
    tau_before, tau_after = payload_torques(scara, q, MASS, COM_EE)
    for method in ("lstsq", "ipopt"):
        with pytest.raises(cg.UnobservableError, match="mass unobservable"):
            cg.estimate_com(scara, q, tau_before, tau_after, method=method)
        Q = np.array([q, q + 0.3])
        with pytest.raises(cg.UnobservableError, match="mass unobservable"):
            cg.estimate_com(scara, Q, *payload_torques(scara, Q, MASS, COM_EE), method=method)
