"""com_along_axis: the CoM line met with the rod axis; paper eq. 8 as a special case."""

from types import SimpleNamespace

import numpy as np
import pytest
from _payload import payload_torques
from hypothesis import given, settings
from hypothesis import strategies as st

import comgrasp_pin as cg
from comgrasp_pin.errors import ComGraspError
from comgrasp_pin.geometry import check_transform, closest_point_on_line, invert_transform


def rot_x(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def rot_y(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def transform(R: np.ndarray, p) -> np.ndarray:
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = R, p
    return T


R_WORLD_EE_TOP_DOWN = np.diag([1.0, -1.0, -1.0])  # ee-z (approach) pointing down
R_EE_OBJ_LEVEL = np.diag([1.0, -1.0, -1.0])  # rod along ee-x, obj-z up


def one_pose_estimate(R_world_ee: np.ndarray, com_ee: np.ndarray) -> SimpleNamespace:
    """What a one-pose estimate holds: the CoM minus its component along gravity (ee)."""
    u = R_world_ee.T @ [0.0, 0.0, -1.0]
    return SimpleNamespace(com_ee=com_ee - (com_ee @ u) * u, unobservable_ee=u)


def paper_eq8(est, T_ee_obj: np.ndarray) -> float:
    """Paper eq. 8, written from the paper: M = T_obj_ee, z^O = 0, (dr_x, dr_y) in ee."""
    M = np.linalg.inv(T_ee_obj)
    r, (px, _, pz) = M[:3, :3], M[:3, 3]
    dx, dy = est.com_ee[0], est.com_ee[1]
    return (
        (r[0, 0] * r[2, 2] - r[0, 2] * r[2, 0]) / r[2, 2] * dx
        + (r[0, 1] * r[2, 2] - r[0, 2] * r[2, 1]) / r[2, 2] * dy
        + px
        - r[0, 2] / r[2, 2] * pz
    )


def rod(R_ee_obj: np.ndarray, origin_ee, x_com: float) -> tuple[np.ndarray, np.ndarray]:
    """(T_ee_obj, true CoM in ee) for a rod whose CoM is x_com along its axis."""
    T_ee_obj = transform(R_ee_obj, origin_ee)
    return T_ee_obj, (T_ee_obj @ [x_com, 0.0, 0.0, 1.0])[:3]


ORIGIN_EE, X_TRUE = np.array([0.01, -0.005, 0.02]), 0.07


def test_level_rod_top_down_equals_paper_eq8():
    T_ee_obj, com_ee = rod(R_EE_OBJ_LEVEL, ORIGIN_EE, X_TRUE)
    est = one_pose_estimate(R_WORLD_EE_TOP_DOWN, com_ee)
    assert cg.com_along_axis(est, T_ee_obj) == pytest.approx(X_TRUE, abs=1e-12)
    assert paper_eq8(est, T_ee_obj) == pytest.approx(X_TRUE, abs=1e-12)


@pytest.mark.parametrize("tilt_deg", [5.0, 20.0, 40.0])
def test_rod_tilted_in_the_jaws(tilt_deg):
    """Tilt about the jaw axis (ee-y), wrist pointing down: obj-y stays horizontal, so the
    plane z^O = 0 of eq. 8 contains the horizontal normal of the axis and both agree."""
    R_ee_obj = rot_y(np.radians(tilt_deg)) @ R_EE_OBJ_LEVEL
    T_ee_obj, com_ee = rod(R_ee_obj, ORIGIN_EE, X_TRUE)
    est = one_pose_estimate(R_WORLD_EE_TOP_DOWN, com_ee)
    assert cg.com_along_axis(est, T_ee_obj) == pytest.approx(X_TRUE, abs=1e-12)
    assert paper_eq8(est, T_ee_obj) == pytest.approx(X_TRUE, abs=1e-12)


@pytest.mark.parametrize("wrist_deg", [10.0, 25.0])
def test_tilted_rod_with_tilted_wrist_differs_from_eq8(wrist_deg):
    """Eq. 8 assumes the unobservable CoM direction is ee-z. With the wrist tilted at the
    measurement about the jaw axis (gravity not along ee-z) and the rod tilted 20 deg in the
    jaws, eq. 8 misplaces the CoM (3 mm at 10 deg, 16 mm at 25 deg); the line-axis
    intersection stays exact."""
    R_world_ee = R_WORLD_EE_TOP_DOWN @ rot_y(np.radians(wrist_deg))
    R_ee_obj = rot_y(np.radians(20.0)) @ R_EE_OBJ_LEVEL
    T_ee_obj, com_ee = rod(R_ee_obj, ORIGIN_EE, X_TRUE)
    est = one_pose_estimate(R_world_ee, com_ee)
    assert cg.com_along_axis(est, T_ee_obj) == pytest.approx(X_TRUE, abs=1e-12)
    paper_error = abs(paper_eq8(est, T_ee_obj) - X_TRUE)
    assert paper_error > 2e-3


def test_full_3d_estimate_projects_on_the_axis():
    R_ee_obj = rot_y(0.3) @ R_EE_OBJ_LEVEL
    T_ee_obj, com_ee = rod(R_ee_obj, ORIGIN_EE, X_TRUE)
    off_axis = com_ee + 0.01 * R_ee_obj[:, 2]  # a CoM 1 cm off the axis (thick rod)
    est = SimpleNamespace(com_ee=off_axis, unobservable_ee=None)
    assert cg.com_along_axis(est, T_ee_obj) == pytest.approx(X_TRUE, abs=1e-12)


def test_with_the_estimator(tmp_path):
    """UR5 at random poses, rod axis through the true CoM, torques from RNEA."""
    robot = cg.RobotModel.ur5()
    rng = np.random.default_rng(30)
    R_ee_obj = rot_y(0.25) @ rot_x(0.1) @ R_EE_OBJ_LEVEL
    T_ee_obj, com_ee = rod(R_ee_obj, ORIGIN_EE, X_TRUE)
    checked = 0
    while checked < 5:
        q = robot.random_configuration(rng)
        down_ee = robot.ee_pose(q)[:3, :3].T @ [0, 0, -1]
        if abs(down_ee @ R_ee_obj[:, 0]) > 0.95:
            continue  # rod nearly vertical at this pose
        tau_before, tau_after = payload_torques(robot, q, 0.4, com_ee)
        for method in ("lstsq", "ipopt"):
            est = cg.estimate_com(robot, q, tau_before, tau_after, method=method)
            assert cg.com_along_axis(est, T_ee_obj) == pytest.approx(X_TRUE, abs=1e-9)
        checked += 1


def test_rod_parallel_to_gravity_raises():
    est = one_pose_estimate(R_WORLD_EE_TOP_DOWN, np.array([0.01, 0.02, 0.0]))
    vertical = transform(rot_y(np.pi / 2) @ R_EE_OBJ_LEVEL, ORIGIN_EE)  # obj-x along ee-z
    with pytest.raises(cg.UnobservableError, match="from gravity"):
        cg.com_along_axis(est, vertical)
    with pytest.raises(ComGraspError, match="1.00 deg from gravity"):
        cg.com_along_axis(est, transform(rot_y(np.radians(89.0)) @ R_EE_OBJ_LEVEL, ORIGIN_EE))
    cg.com_along_axis(est, transform(rot_y(np.radians(85.0)) @ R_EE_OBJ_LEVEL, ORIGIN_EE))


@pytest.mark.parametrize(
    ("T", "message"),
    [
        (np.eye(3), r"\(4, 4\)"),
        (np.full((4, 4), np.nan), "NaN or inf"),
        (np.diag([2.0, 1.0, 1.0, 1.0]), "not a rotation"),
        (np.diag([1.0, 1.0, -1.0, 1.0]), "not a rotation"),
        (np.vstack([np.eye(4)[:3], [0, 0, 1, 1]]), "last row"),
    ],
)
def test_bad_transform(T, message):
    est = SimpleNamespace(com_ee=np.zeros(3), unobservable_ee=None)
    with pytest.raises(cg.InvalidInputError, match=message):
        cg.com_along_axis(est, T)


def test_invert_transform():
    T = transform(rot_y(0.4) @ rot_x(-1.1), [0.1, -0.2, 0.3])
    np.testing.assert_allclose(invert_transform(T) @ T, np.eye(4), atol=1e-14)
    assert check_transform(T).shape == (4, 4)


@settings(max_examples=300, deadline=None)
@given(seed=st.integers(0, 2**31), scale=st.floats(-9, 1), atol=st.floats(-9, -3))
def test_transform_check_accepts_what_numpy_allclose_accepts(seed, scale, atol):
    """The check's closeness is ``np.allclose``'s (the reference), on rotations disturbed
    by anything from far below to far above the tolerance."""
    rng = np.random.default_rng(seed)
    T = transform(rot_y(rng.uniform(-3, 3)) @ rot_x(rng.uniform(-3, 3)), rng.normal(size=3))
    T[:3, :3] += 10.0**scale * rng.normal(size=(3, 3))
    R, tol = T[:3, :3], 10.0**atol
    expected = (np.abs(R).max() <= 1 + tol and np.allclose(R.T @ R, np.eye(3), atol=tol)
                and np.linalg.det(R) >= 0)  # fmt: skip
    try:
        check_transform(T, atol=tol)
        accepted = True
    except cg.InvalidInputError:
        accepted = False
    assert accepted == expected


unit = (
    st.lists(st.floats(-1, 1), min_size=3, max_size=3)
    .map(np.array)
    .filter(lambda v: np.linalg.norm(v) > 0.1)
)
point = st.lists(st.floats(-1, 1), min_size=3, max_size=3).map(np.array)


@settings(max_examples=40, deadline=None)
@given(p1=point, d1=unit, p2=point, d2=unit)
def test_property_closest_point(p1, d1, p2, d2):
    d1, d2 = d1 / np.linalg.norm(d1), d2 / np.linalg.norm(d2)
    if np.linalg.norm(np.cross(d1, d2)) < 0.05:
        return
    t = closest_point_on_line(p1, d1, p2, d2)
    x = p1 + t * d1
    s = d2 @ (x - p2)  # the closest point of line 2 to x
    gap = x - (p2 + s * d2)
    assert abs(gap @ d1) < 1e-9 and abs(gap @ d2) < 1e-9


@settings(max_examples=50, deadline=None)
@given(st.lists(st.floats(-1, 1), min_size=4, max_size=4), st.floats(0.1, 10))
def test_a_ros_quaternion_turns_as_pinocchios(q, scale):
    """``transform_from_quaternion`` (x, y, z, w, ROS's order; normalised) against
    Pinocchio's Quaternion, which takes (w, x, y, z)."""
    import pinocchio as pin

    from comgrasp_pin.geometry import transform_from_quaternion

    if np.linalg.norm(q) < 0.1:
        return
    x, y, z, w = q
    T = transform_from_quaternion([1.0, -2.0, 0.5], [scale * v for v in q])
    expected = pin.Quaternion(w, x, y, z).normalized().toRotationMatrix()
    np.testing.assert_allclose(T[:3, :3], expected, atol=1e-12)
    np.testing.assert_array_equal(T[:3, 3], [1.0, -2.0, 0.5])
    with pytest.raises(ComGraspError, match="zero length"):
        transform_from_quaternion([0, 0, 0], [0, 0, 0, 0])
