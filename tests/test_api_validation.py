"""Every public parameter checked; every error a ComGraspError (issue 15)."""

import ast
import builtins
import inspect
from pathlib import Path

import numpy as np
import pytest
from _payload import payload_torques

import comgrasp_pin as cg
from comgrasp_pin import errors
from comgrasp_pin._paths import urdf_path
from comgrasp_pin.camera import PinholeCamera, transform_points
from comgrasp_pin.errors import ComGraspError, InvalidInputError, UnobservableError
from comgrasp_pin.geometry import closest_point_on_line, invert_transform
from comgrasp_pin.perception import SlipMonitor, observe_held_rod

Q = np.array([0.0, -1.2, 1.5, -1.9, -1.57, 0.0])
PACKAGE = Path(cg.__file__).parent


@pytest.fixture(scope="module")
def one_pose(ur5):
    tb, ta = payload_torques(ur5, Q, 0.5, np.array([0.05, 0.0, 0.1]))
    return ur5, tb, ta


# --- estimation ---------------------------------------------------------------------------


@pytest.mark.parametrize("rcond", ["1e-6", None, 0, 0.0, 1.0, -1e-6, float("nan"), True])
def test_rcond_must_be_a_number_in_0_1(one_pose, rcond):
    robot, tb, ta = one_pose
    with pytest.raises(InvalidInputError, match="rcond must be"):
        cg.estimate_com(robot, Q, tb, ta, rcond=rcond)


def test_estimates_need_a_robot_model(one_pose):
    _, tb, ta = one_pose
    with pytest.raises(InvalidInputError, match="robot must be a RobotModel"):
        cg.estimate_com("ur5", Q[None], tb[None], ta[None])


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [({"margin": float("nan")}, "margin .* must be finite"),
     ({"margin": -0.1}, "margin .* must be >= 0"),
     ({"margin": 1e308}, "margin .* <= 6.28"),
     ({"max_offset": float("inf")}, "max_offset .* must be finite"),
     ({"max_offset": 0.0}, "max_offset .* must be > 0"),
     ({"max_offset": 9e307}, "max_offset .* <= 6.28"),
     ({"n_grid": 1}, "n_grid must be an integer >= 2"),
     ({"n_grid": 2.5}, "n_grid must be an integer"),
     ({"n_grid": 10**6}, "n_grid must be an integer >= 2 and <= 21"),
     ({"k": True}, "k must be an integer"),
     ({"k": 0}, "k must be an integer >= 1")],
)  # fmt: skip
def test_plan_wrist_poses_checks_its_numbers(ur5, kwargs, message):
    with pytest.raises(InvalidInputError, match=message):
        cg.plan_wrist_poses(ur5, start=Q, **{"k": 3, **kwargs})


def test_plan_wrist_poses_gives_finite_joints_within_limits(ur5):
    poses = cg.plan_wrist_poses(ur5, 4, Q, margin=0.05).q
    assert np.all(np.isfinite(poses))
    assert np.all(poses >= ur5.q_lower - 1e-12) and np.all(poses <= ur5.q_upper + 1e-12)


def _rod_along(direction_ee: np.ndarray) -> np.ndarray:
    x = direction_ee / np.linalg.norm(direction_ee)
    y = np.cross([1.0, 0.0, 0.0], x)
    y /= np.linalg.norm(y)
    T = np.eye(4)
    T[:3, :3] = np.c_[x, y, np.cross(x, y)]
    return T


@pytest.mark.parametrize("min_angle", [0, 0.0, -0.1, float("nan"), 2.0, "0.05"])
def test_com_along_axis_needs_a_min_angle_in_0_pi_2(one_pose, min_angle):
    robot, tb, ta = one_pose
    est = cg.estimate_com(robot, Q, tb, ta)
    vertical = _rod_along(est.unobservable_ee)
    with pytest.raises(InvalidInputError, match="min_angle"):
        cg.com_along_axis(est, vertical, min_angle=min_angle)
    with pytest.raises(UnobservableError, match="from gravity"):
        cg.com_along_axis(est, vertical)  # the default: a vertical rod fixes no point


def test_com_along_axis_refuses_what_is_not_an_estimate():
    with pytest.raises(InvalidInputError, match="est must be a ComEstimate"):
        cg.com_along_axis(np.zeros(3), np.eye(4))


# --- the robot model ----------------------------------------------------------------------


def test_from_urdf_on_a_folder_or_a_non_urdf_file(tmp_path):
    with pytest.raises(InvalidInputError, match="is a folder, not a file"):
        cg.RobotModel.from_urdf(tmp_path, "eelink")
    (tmp_path / "robot.urdf").write_text("not xml")
    with pytest.raises(InvalidInputError, match="cannot read .* as a URDF"):
        cg.RobotModel.from_urdf(tmp_path / "robot.urdf", "eelink")
    with pytest.raises(InvalidInputError, match="not found"):
        cg.RobotModel.from_urdf(tmp_path / "missing.urdf", "eelink")
    with pytest.raises(InvalidInputError, match="urdf_path must be a path"):
        cg.RobotModel.from_urdf(None, "eelink")
    with pytest.raises(InvalidInputError, match="package_dirs must be a list of folders"):
        cg.RobotModel.from_urdf(urdf_path("ur5_gripper.urdf"), "eelink", package_dirs="/x")


@pytest.mark.parametrize("frame", [None, 3, "", "no_such_frame"])
def test_from_urdf_with_no_ee_frame_lists_the_frames(frame):
    with pytest.raises(InvalidInputError, match=r"ee_frame .* is not a frame.*'eelink'"):
        cg.RobotModel.from_urdf(urdf_path("ur5_gripper.urdf"), frame)


@pytest.mark.parametrize("frame", ["world", "base_link"])
def test_an_ee_frame_that_no_joint_moves_is_refused(frame):
    with pytest.raises(InvalidInputError, match="no joint moves the frame"):
        cg.RobotModel.from_urdf(urdf_path("ur5_gripper.urdf"), frame)


def test_robot_methods_check_q_and_frames(ur5):
    for q in ("abc", [0.0] * 5, [np.nan] * 6):
        with pytest.raises(InvalidInputError):
            ur5.ee_pose(q)
    with pytest.raises(InvalidInputError, match="is not a frame"):
        ur5.frame_pose(Q, None)


# --- perception ---------------------------------------------------------------------------

CAMERA = PinholeCamera(64, 48, 50.0, 50.0, 32.0, 24.0)
DEPTH = np.full((48, 64), np.inf)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [({"rod_length": float("nan")}, "rod_length .* must be finite"),
     ({"rod_length": -0.3}, "rod_length .* must be > 0"),
     ({"handle_radius": 0.0}, "handle_radius .* must be > 0"),
     ({"centre_hint": float("inf")}, "centre_hint .* must be finite"),
     ({"table_z": "low"}, "table_z .* must be a real number"),
     ({"T_ee_cam": np.eye(3)}, r"T_ee_cam must be a \(4, 4\)"),
     ({"T_world_ee": np.eye(3)}, r"T_world_ee must be a \(4, 4\)"),
     ({"T_ee_cam": np.full((4, 4), np.nan)}, "T_ee_cam contains NaN")],
)  # fmt: skip
def test_observe_held_rod_checks_its_arguments(kwargs, message):
    args = {"T_ee_cam": np.eye(4), **kwargs}
    T = args.pop("T_ee_cam")
    with pytest.raises(InvalidInputError, match=message):
        observe_held_rod(None, DEPTH, CAMERA, T, **args)


def test_observe_held_rod_checks_the_camera_and_depth():
    with pytest.raises(ComGraspError, match="camera intrinsics not understood"):
        observe_held_rod(None, DEPTH, "camera", np.eye(4))
    with pytest.raises(ComGraspError, match="not a numeric array"):
        observe_held_rod(None, "depth", CAMERA, np.eye(4))


@pytest.mark.parametrize("t", [float("nan"), float("inf"), "0.1", None])
def test_slip_monitor_refuses_a_time_that_is_not_a_finite_number(t):
    with pytest.raises(InvalidInputError, match="time t"):
        SlipMonitor().add(t, 0.0)


def _verdict(thetas_deg, dt=0.2):
    monitor = SlipMonitor()
    for k, theta in enumerate(thetas_deg):
        monitor.add(k * dt, np.radians(theta))
    return monitor.verdict()


def test_slip_monitor_sees_a_steady_turn():
    verdict = _verdict([0.0, 28.6, 57.3])  # 57.3 deg in 0.4 s
    assert verdict.slip_seen and verdict.change_deg > 50.0
    assert _verdict([0.0, 0.4, 0.8, 1.2, 1.6]).slip_seen  # 1.6 deg, slowly


@pytest.mark.parametrize(
    "thetas", [[0.0, 57.3, 0.0], [57.3, 0.0, 0.0], [0.0, 0.0, 57.3], [0.0, 0.0, 30.0, 0.0, 0.0],
               [0.0, 0.0, 0.0, 0.0, 0.0, 30.0]],
)  # fmt: skip
def test_slip_monitor_still_ignores_one_bad_frame(thetas):
    verdict = _verdict(thetas)
    assert not verdict.slip_seen and verdict.change_deg < 1e-9


# --- geometry helpers ---------------------------------------------------------------------


def test_geometry_helpers_check_their_inputs():
    with pytest.raises(InvalidInputError, match=r"\(4, 4\)"):
        invert_transform(np.eye(3))
    with pytest.raises(InvalidInputError, match="not a rotation"):
        invert_transform(np.diag([2.0, 1.0, 1.0, 1.0]))
    with pytest.raises(InvalidInputError, match=r"shape \(N, 3\)"):
        transform_points(np.eye(4), np.zeros((5, 2)))
    with pytest.raises(InvalidInputError, match="d_line must be a unit vector"):
        closest_point_on_line(np.zeros(3), np.array([2.0, 0, 0]), np.ones(3), np.eye(3)[2])
    with pytest.raises(UnobservableError, match="parallel"):
        closest_point_on_line(np.zeros(3), np.eye(3)[0], np.ones(3), -np.eye(3)[0])
    assert closest_point_on_line(np.zeros(3), np.eye(3)[0], np.array([0.3, 1, 0]),
                                 np.eye(3)[2]) == pytest.approx(0.3)  # fmt: skip


# --- simulation ---------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [({"pos_real": float("nan")}, "pos_real must be finite"),
     ({"pos_real": 1.0}, "pos_real must be >= -0.2 and <= 0.2"),
     ({"seed": -1}, "seed must be an integer >= 0"),
     ({"seed": 1.5}, "seed must be an integer"),
     ({"obj": "obj9"}, "unknown object"),
     ({"config": {"noise": 0.1}}, "config must be an EpisodeConfig"),
     ({"method": "magic"}, "method must be one of")],
)  # fmt: skip
def test_run_episode_refuses_bad_arguments_before_simulating(kwargs, message):
    from comgrasp_pin.simulation.episode import run_episode

    args = {"obj": "obj1", "seed": 0, **kwargs}
    with pytest.raises(InvalidInputError, match=message):
        run_episode(args.pop("obj"), args.pop("seed"), **args)


# --- every error a ComGraspError ----------------------------------------------------------


def test_every_error_class_is_a_comgrasp_error():
    """(Which ones are ValueErrors, and which harness ones are not: tests/test_errors.py.)"""
    classes = [c for _, c in inspect.getmembers(errors, inspect.isclass)
               if issubclass(c, Exception)]  # fmt: skip
    assert len(classes) >= 15
    assert all(issubclass(c, ComGraspError) for c in classes)


def test_the_package_raises_only_its_own_errors():
    """No ``raise ValueError(...)``-style statement with a built-in exception in the package
    (a re-raise of the caught exception or of a package error is fine)."""
    builtin = set(dir(builtins)) - {"AssertionError"}  # internal invariants (STYLE.md 6)
    caught_at_once = {"experiments/run_files.py OSError"}  # a short write, handled below it
    offenders = []
    for path in PACKAGE.rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Raise) and node.exc is not None:
                target = node.exc.func if isinstance(node.exc, ast.Call) else node.exc
                name = target.id if isinstance(target, ast.Name) else None
                where = f"{path.relative_to(PACKAGE)} {name}"
                if name in builtin and name.endswith("Error") and where not in caught_at_once:
                    offenders.append(f"{where} (line {node.lineno})")
    assert offenders == []


def test_stats_and_runner_errors_are_comgrasp_errors(tmp_path):
    from comgrasp_pin.experiments.runner import run_trials
    from comgrasp_pin.experiments.stats import t_quantile

    with pytest.raises(ComGraspError, match="t_quantile needs"):
        t_quantile(1.5, 3)
    tasks = [{"object": "obj1", "trial": 0, "method": "m"}]
    run_trials(dict, tasks, tmp_path / "a.csv", ["object"])
    with pytest.raises(ComGraspError, match="already holds results"):
        run_trials(dict, tasks, tmp_path / "a.csv", ["object"])
