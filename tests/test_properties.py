"""Property-based checks of the public API (issue 15): any finite input gives a result or a
ComGraspError, never another exception, and never a NaN or an infinity in a result."""

import numpy as np
import pytest
from _payload import payload_torques
from hypothesis import HealthCheck, assume, event, given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

import comgrasp_pin as cg
from comgrasp_pin.camera import transform_points
from comgrasp_pin.errors import ComGraspError
from comgrasp_pin.geometry import check_transform, closest_point_on_line, invert_transform
from comgrasp_pin.perception import SlipMonitor

SETTINGS = settings(max_examples=100, deadline=None,
                    suppress_health_check=[HealthCheck.function_scoped_fixture])  # fmt: skip
ROBOT = cg.RobotModel.ur5()
N = ROBOT.nq

any_float = st.floats(allow_nan=False, allow_infinity=False)
moderate = st.floats(-1e3, 1e3, allow_nan=False)
angles = st.floats(-2 * np.pi, 2 * np.pi, allow_nan=False)


def _finite(*values) -> bool:
    return all(v is None or np.all(np.isfinite(np.asarray(v, dtype=float))) for v in values)


def _assert_finite_estimate(est) -> None:
    assert _finite(est.com_ee, est.mass, est.weight, est.unobservable_ee, est.cov,
                   est.residual_rms, est.residuals, est.condition_number)  # fmt: skip


@st.composite
def torque_data(draw, k_max=3):
    """(q, tau_before, tau_after): a real payload's torques (perhaps noisy) or any numbers."""
    k = draw(st.integers(1, k_max))
    q = draw(arrays(float, (k, N), elements=angles))
    if draw(st.integers(0, 3)) > 0:  # mostly a real payload: estimates, not only errors
        mass = draw(st.floats(0.0, 20.0))
        com = draw(arrays(float, (3,), elements=st.floats(-1.0, 1.0)))
        tb, ta = payload_torques(ROBOT, q, mass, com)
        ta = ta + draw(arrays(float, (k, N), elements=st.floats(-0.1, 0.1)))
    else:
        elements = draw(st.sampled_from([moderate, any_float]))
        tb = draw(arrays(float, (k, N), elements=elements))
        ta = draw(arrays(float, (k, N), elements=elements))
    if k == 1 and draw(st.booleans()):
        q, tb, ta = q[0], tb[0], ta[0]
    return q, tb, ta


torque_stds = st.one_of(
    st.none(),
    st.floats(1e-4, 10.0),
    arrays(float, (N,), elements=st.floats(1e-4, 10.0)),
    st.floats(1e-4, 10.0),
    any_float,
)


@st.composite
def axis_priors(draw):
    point = draw(arrays(float, (3,), elements=st.floats(-1.0, 1.0)))
    direction = draw(arrays(float, (3,), elements=st.floats(-1.0, 1.0)))
    std = draw(st.floats(1e-4, 1.0))
    try:
        return cg.AxisPrior(point, direction, std)
    except ComGraspError:
        assume(False)


def _estimate_or_error(call):
    """call() or None for a ComGraspError; any other exception fails the test."""
    try:
        result = call()
    except ComGraspError as exc:
        event(type(exc).__name__)  # --hypothesis-show-statistics: how often each outcome
        return None
    event("a result")
    return result


@SETTINGS
@given(data=torque_data(), torque_std=torque_stds)
def test_lstsq_gives_a_finite_estimate_or_a_comgrasp_error(data, torque_std):
    est = _estimate_or_error(lambda: cg.estimate_com(ROBOT, *data, "lstsq", torque_std))
    if est is not None:
        _assert_finite_estimate(est)
        assert est.mass > 0


@SETTINGS
@given(data=torque_data(k_max=2), torque_std=torque_stds, prior=st.none() | axis_priors(),
       loss=st.sampled_from(["l2", "huber"]))  # fmt: skip
def test_ipopt_gives_a_finite_estimate_or_a_comgrasp_error(data, torque_std, prior, loss):
    def call():
        return cg.estimate_com(ROBOT, *data, "ipopt", torque_std, loss=loss, com_prior=prior)

    est = _estimate_or_error(call)
    if est is not None:
        _assert_finite_estimate(est)
        assert est.mass > 0


@SETTINGS
@given(data=torque_data(), torque_std=torque_stds, rcond=st.floats(1e-12, 0.5))
def test_any_rcond_gives_a_finite_estimate_or_a_comgrasp_error(data, torque_std, rcond):
    est = _estimate_or_error(lambda: cg.estimate_com(ROBOT, *data, "lstsq", torque_std, rcond))
    if est is not None:
        _assert_finite_estimate(est)
        assert est.mass > 0


@st.composite
def rigid_transforms(draw, scale=1.0):
    quat = draw(arrays(float, (4,), elements=st.floats(-1.0, 1.0))) + [1e-3, 0.0, 0.0, 0.0]
    w, x, y, z = quat / np.linalg.norm(quat)
    T = np.eye(4)
    T[:3, :3] = [
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ]
    T[:3, 3] = draw(arrays(float, (3,), elements=st.floats(-scale, scale)))
    return T


@SETTINGS
@given(data=torque_data(k_max=2), T=rigid_transforms(),
       min_angle=st.floats(1e-9, np.pi / 2) | any_float)  # fmt: skip
def test_com_along_axis_is_finite_or_a_comgrasp_error(data, T, min_angle):
    est = _estimate_or_error(lambda: cg.estimate_com(ROBOT, *data))
    assume(est is not None)
    x = _estimate_or_error(lambda: cg.com_along_axis(est, T, min_angle))
    assert x is None or np.isfinite(x)


@SETTINGS
@given(point=arrays(float, (3,), elements=moderate | any_float) | st.just([0.0, 1.0]),
       direction=arrays(float, (3,), elements=st.floats(-1, 1) | any_float),
       std=st.floats(1e-6, 10.0) | any_float | st.text(max_size=3),
       com=arrays(float, (3,), elements=moderate))  # fmt: skip
def test_axis_prior_is_valid_or_a_comgrasp_error(point, direction, std, com):
    prior = _estimate_or_error(lambda: cg.AxisPrior(point, direction, std))
    if prior is not None:
        assert np.linalg.norm(prior.direction_ee) == pytest.approx(1.0)
        assert prior.std > 0 and _finite(prior.point_ee, prior.across(), prior.distance(com))


@settings(max_examples=30, deadline=None)
@given(q=arrays(float, (N,), elements=angles), k=st.integers(1, 4) | st.integers(-1, 0),
       max_offset=st.floats(0.01, 3.0) | any_float, n_grid=st.integers(2, 4) | st.integers(0, 1),
       margin=st.floats(0, 0.5) | any_float)  # fmt: skip
def test_plan_wrist_poses_is_finite_within_limits_or_a_comgrasp_error(q, k, max_offset, n_grid,
                                                                       margin):  # fmt: skip
    plan = _estimate_or_error(
        lambda: cg.plan_wrist_poses(
            ROBOT, k, q, max_offset=max_offset, n_grid=n_grid, margin=margin
        )
    )
    poses = None if plan is None else plan.q
    if poses is not None:
        assert poses.shape == (k, N) and _finite(poses)
        assert np.array_equal(poses[0], q) and np.array_equal(poses[:, :3], np.tile(q[:3], (k, 1)))


@SETTINGS
@given(samples=st.lists(st.tuples(st.floats(1e-3, 10.0), any_float | angles), max_size=30))
def test_the_slip_monitor_gives_finite_verdicts(samples):
    monitor, t = SlipMonitor(), 0.0
    for dt, theta in samples:
        t += dt
        added = _estimate_or_error(lambda: monitor.add(t, theta) or True)  # noqa: B023
        assert added or abs(theta) > 2 * np.pi or t > 1e6
    if not monitor.times:
        return
    verdict = _estimate_or_error(monitor.verdict)
    if verdict is not None:
        assert _finite(verdict.rate_deg_s, verdict.change_deg, verdict.theta)
        assert _finite(monitor.largest_tilt(), monitor.settled_tilt())


@SETTINGS
@given(T=rigid_transforms(scale=1e3), points=arrays(float, (5, 3), elements=moderate))
def test_transforms_invert_and_map_points(T, points):
    T_inv = invert_transform(check_transform(T))
    assert np.allclose(T_inv @ T, np.eye(4), atol=1e-9)
    back = transform_points(T_inv, transform_points(T, points))
    assert np.allclose(back, points, atol=1e-6)


@SETTINGS
@given(M=arrays(float, st.sampled_from([(4, 4), (3, 3), (4,)]), elements=any_float)
       | rigid_transforms(), noise=st.floats(0.0, 1e-3))  # fmt: skip
def test_check_transform_accepts_rigid_transforms_only(M, noise):
    if M.shape == (4, 4):
        M = M + noise * np.sign(M)
    T = _estimate_or_error(lambda: check_transform(M))
    if T is not None:
        assert np.allclose(T[:3, :3].T @ T[:3, :3], np.eye(3), atol=1e-5)


@SETTINGS
@given(p1=arrays(float, (3,), elements=moderate), d1=arrays(float, (3,), elements=moderate),
       p2=arrays(float, (3,), elements=moderate), d2=arrays(float, (3,), elements=moderate),
       unit=st.booleans())  # fmt: skip
def test_closest_point_on_line_is_finite_or_a_comgrasp_error(p1, d1, p2, d2, unit):
    if unit:
        assume(np.linalg.norm(d1) > 1e-6 and np.linalg.norm(d2) > 1e-6)
        d1, d2 = d1 / np.linalg.norm(d1), d2 / np.linalg.norm(d2)
    t = _estimate_or_error(lambda: closest_point_on_line(p1, d1, p2, d2))
    assert t is None or np.isfinite(t)


@SETTINGS
@given(q=arrays(float, (N,), elements=angles | any_float) | arrays(float, (N - 1,)))
def test_robot_kinematics_are_finite_or_a_comgrasp_error(q):
    for method in (ROBOT.joint_axes, ROBOT.joint_origins, ROBOT.lever_arms, ROBOT.ee_pose,
                   ROBOT.gravity_torques):  # fmt: skip
        out = _estimate_or_error(lambda: method(q))  # noqa: B023
        assert out is None or _finite(out)
