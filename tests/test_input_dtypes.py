"""Arrays that are not real numbers are refused, never converted (issue 27, item 3).

NumPy would take a complex q with a warning and drop its imaginary part, a boolean q as
0 and 1, and strings of digits as numbers: each a silent wrong answer. The public entry
points refuse them with a ComGraspError that names the argument; real integers and floats
of any width are taken. The dtypes are drawn by hypothesis.
"""

from __future__ import annotations

import numpy as np
import pytest
from _payload import payload_torques
from hypothesis import given, settings
from hypothesis import strategies as st

import comgrasp_pin as cg
from comgrasp_pin.camera import PinholeCamera
from comgrasp_pin.errors import ComGraspError, InvalidDepthError, InvalidInputError
from comgrasp_pin.geometry import closest_point_on_line
from comgrasp_pin.perception import detect_rod_top_down, observe_held_rod

Q = np.array([0.0, -1.2, 1.5, -1.9, -1.57, 0.0])
REFUSED = [np.complex128, np.complex64, np.bool_, np.str_, np.object_]
TAKEN = [np.float64, np.float32, np.float16, np.int64, np.int32, np.int8, np.uint16]


def _as(a: np.ndarray, dtype) -> np.ndarray:
    if dtype is np.str_:
        return np.array([repr(float(x)) for x in a.ravel()]).reshape(a.shape)
    if dtype is np.object_:
        return np.array(list(a.ravel()), dtype=object).reshape(a.shape)
    return a.astype(dtype)


@pytest.fixture(scope="module")
def one_pose(ur5):
    tb, ta = payload_torques(ur5, Q, 0.5, np.array([0.05, 0.0, 0.1]))
    return ur5, tb, ta


@settings(max_examples=40, deadline=None)
@given(which=st.sampled_from(["q", "tau_before", "tau_after", "torque_std"]),
       dtype=st.sampled_from(REFUSED))  # fmt: skip
def test_estimate_com_refuses_arrays_that_are_not_real_numbers(one_pose, which, dtype):
    robot, tb, ta = one_pose
    args = {"q": Q, "tau_before": tb, "tau_after": ta, "torque_std": np.full(6, 0.01)}
    args[which] = _as(np.asarray(args[which]), dtype)
    with pytest.raises(InvalidInputError, match=which):
        cg.estimate_com(robot, **args)


@settings(max_examples=30, deadline=None)
@given(dtype=st.sampled_from(TAKEN))
def test_real_integers_and_floats_of_any_width_are_taken(one_pose, dtype):
    robot, tb, ta = one_pose
    q = np.round(Q).astype(dtype) if np.dtype(dtype).kind in "iu" else Q.astype(dtype)
    if np.dtype(dtype).kind == "u":
        q = np.abs(q)
    plain = robot.ee_pose(np.asarray(q, dtype=float))
    np.testing.assert_array_equal(robot.ee_pose(q), plain)


@pytest.mark.parametrize("dtype", REFUSED)
def test_robot_and_geometry_refuse_what_is_not_real(ur5, dtype):
    with pytest.raises(InvalidInputError, match="q"):
        ur5.ee_pose(_as(Q, dtype))
    x, z = np.array([1.0, 0, 0]), np.array([0, 0, 1.0])
    with pytest.raises(InvalidInputError, match="p_line"):
        closest_point_on_line(_as(np.zeros(3), dtype), z, np.ones(3), x)


def test_a_complex_q_gives_no_warning_and_no_estimate(one_pose, recwarn):
    robot, tb, ta = one_pose
    with pytest.raises(InvalidInputError, match="complex"):
        cg.estimate_com(robot, Q + 1e-3j, tb, ta, torque_std=0.01)
    assert not [w for w in recwarn if issubclass(w.category, np.exceptions.ComplexWarning)]


CAMERA = PinholeCamera.from_fovy(64, 48, 58.0)


@pytest.mark.parametrize("dtype", [np.uint16, np.int32])
def test_an_integer_depth_image_is_refused_and_the_message_names_depth_scale(dtype):
    depth_mm = np.full((48, 64), 500, dtype=dtype)  # a RealSense frame: 0.5 m in millimetres
    for look in (lambda d: observe_held_rod(None, d, CAMERA, np.eye(4)),
                 lambda d: detect_rod_top_down(None, d, CAMERA, np.eye(4))):  # fmt: skip
        with pytest.raises(InvalidDepthError, match="depth_scale"):
            look(depth_mm)


@pytest.mark.parametrize("dtype", [np.complex128, np.bool_, np.object_])
def test_a_depth_image_that_is_not_real_is_refused(dtype):
    with pytest.raises(ComGraspError, match="not a numeric array"):
        observe_held_rod(None, _as(np.full((48, 64), 0.5), dtype), CAMERA, np.eye(4))


@pytest.mark.parametrize("dtype", REFUSED)
def test_camera_transforms_and_planning_refuse_what_is_not_real(ur5, dtype):
    from comgrasp_pin.camera import transform_points
    from comgrasp_pin.geometry import check_transform
    from comgrasp_pin.planning.wrist_poses import best_next_pose

    points = np.array([[0.1, 0.2, 0.5], [0.0, 0.0, 1.0]])
    with pytest.raises(InvalidInputError, match="p_b"):
        transform_points(np.eye(4), _as(points, dtype))
    with pytest.raises(InvalidInputError, match="T_a_b"):
        transform_points(_as(np.eye(4), dtype), points)
    with pytest.raises(InvalidInputError, match="p_cam"):
        CAMERA.project(_as(points, dtype))
    with pytest.raises(InvalidInputError, match="uv"):
        CAMERA.backproject(_as(np.array([[3.0, 4.0]]), dtype), np.array([0.5]))
    with pytest.raises(InvalidInputError, match="T_world_cam"):
        check_transform(_as(np.eye(4), dtype), "T_world_cam")
    with pytest.raises(InvalidInputError, match="candidates"):
        best_next_pose(ur5, Q[None], _as(Q[None] + 0.1, dtype))


def test_float32_points_are_transformed_as_float64_ones():
    from comgrasp_pin.camera import transform_points

    points = np.random.default_rng(3).normal(size=(50, 3)).astype(np.float32)
    T = np.eye(4)
    T[:3, 3] = [0.1, -0.2, 0.3]
    expected = points.astype(float) + T[:3, 3]
    np.testing.assert_array_equal(transform_points(T, points), expected)


def _public_constructors():
    """name -> function of a converter of one array argument: the public values that take
    arrays (the estimator's prior, a robot log, a payload, a camera's intrinsics and depth)."""
    from comgrasp_pin.perception.frames.camera_input import metric_depth
    from comgrasp_pin.perception.frames.camera_model import camera_model
    from comgrasp_pin.robot_io import JointLog, Payload

    t, pos = np.linspace(0.0, 1.0, 5), np.zeros((5, 2))
    x, K = np.array([1.0, 0.0, 0.0]), CAMERA.K
    return {
        "point_ee": lambda b: cg.AxisPrior(point_ee=b(np.zeros(3)), direction_ee=x, std=0.01),
        "direction_ee": lambda b: cg.AxisPrior(point_ee=np.zeros(3), direction_ee=b(x), std=0.01),
        "JointLog.time": lambda b: JointLog(b(t), ("a", "b"), pos, pos),
        "JointLog.position": lambda b: JointLog(t, ("a", "b"), b(pos), pos),
        "JointLog.effort": lambda b: JointLog(t, ("a", "b"), pos, b(pos)),
        "JointLog.velocity": lambda b: JointLog(t, ("a", "b"), pos, pos, velocity=b(pos)),
        "Payload.com_flange": lambda b: Payload(1.0, b(np.zeros(3)), np.eye(3), "f", None, "point"),
        "Payload.inertia_flange": lambda b: Payload(
            1.0, np.zeros(3), b(np.eye(3)), "f", None, "point"
        ),  # fmt: skip
        "K": lambda b: camera_model(b(K), (48, 64)),
        "depth": lambda b: metric_depth(b(np.full((4, 4), 500.0)), 1e-3),
    }


@settings(max_examples=60, deadline=None)
@given(which=st.sampled_from(sorted(_public_constructors())), dtype=st.sampled_from(REFUSED))
def test_public_values_that_take_arrays_refuse_what_is_not_real(which, dtype):
    """A complex, boolean, string or object array is refused naming the argument (it was
    taken, a complex one with its imaginary part dropped)."""
    with pytest.raises(InvalidInputError, match=which.split(".")[-1]):
        _public_constructors()[which](lambda a: _as(a, dtype))


@pytest.mark.parametrize("dtype", REFUSED)
def test_planning_refuses_what_is_not_real(ur5, dtype):
    with pytest.raises(InvalidInputError, match="q"):
        cg.plan_wrist_poses(ur5, 3, _as(Q, dtype))
    with pytest.raises(InvalidInputError, match="not a numeric array"):  # (it says q)
        cg.plan_measurement_poses(ur5, 3, start=_as(Q, dtype), n_candidates=50)
