"""Perception against the simulator's ground truth (poses set kinematically, then rendered)."""

import mujoco
import numpy as np
import pytest

from comgrasp_pin.camera import PinholeCamera
from comgrasp_pin.errors import (
    AmbiguousObjectError,
    ComGraspError,
    InvalidDepthError,
    ObjectCutByBorderError,
    ObjectNotFoundError,
)
from comgrasp_pin.motion.ik import solve_ik, top_down_frame
from comgrasp_pin.perception import SlipMonitor, detect_rod_top_down
from comgrasp_pin.simulation import Simulation, build_model
from comgrasp_pin.simulation.cameras import CameraRig
from comgrasp_pin.simulation.eyes import look_from_side
from comgrasp_pin.simulation.objects import OBJECTS, add_object, pose_on_table
from comgrasp_pin.simulation.scene import random_table_pose
from comgrasp_pin.simulation.world import TOP_CAMERA
from comgrasp_pin.workcell import Q_PARK

OBJECT_NAMES = sorted(OBJECTS)


def _wrap_half_turn(angle):
    return (angle + np.pi / 2) % np.pi - np.pi / 2


@pytest.fixture(scope="module")
def top_errors():
    """Centre and yaw errors of 5 random poses of each of the six objects (30 poses)."""
    rng = np.random.default_rng(11)
    errors = []
    for name in OBJECT_NAMES:
        obj = OBJECTS[name]
        model = build_model(extras=[lambda spec, o=obj: add_object(spec, o, (0.55, 0.0, 0.0))])
        sim = Simulation(model)
        sim.reset_arm(Q_PARK)
        rig = CameraRig(model)
        qadr = model.joint("object_free").qposadr[0]
        for _ in range(5):
            x, y, yaw = random_table_pose(rng, obj.length)
            T = pose_on_table(x, y, yaw, obj)
            quat = np.zeros(4)
            mujoco.mju_mat2Quat(quat, T[:3, :3].ravel())
            sim.data.qpos[qadr : qadr + 7] = np.r_[T[:3, 3], quat]
            mujoco.mj_forward(model, sim.data)
            det = detect_rod_top_down(
                rig.rgb(sim.data, TOP_CAMERA),
                rig.depth(sim.data, TOP_CAMERA),
                rig.intrinsics(TOP_CAMERA),
                rig.T_world_cam(sim.data, TOP_CAMERA),
            )
            centre_err = np.hypot(det.grasp.x - x, det.grasp.y - y)
            yaw_err = abs(_wrap_half_turn(det.grasp.yaw - yaw))
            axis_z_err = abs(det.grasp.z - obj.rest_height)
            errors.append((name, centre_err, yaw_err, axis_z_err, abs(det.length - obj.length)))
        rig.close()
    return errors


def test_top_down_centre_within_3mm_and_yaw_within_1deg(top_errors):
    assert len(top_errors) >= 30
    worst_centre = max(e[1] for e in top_errors)
    worst_yaw = np.degrees(max(e[2] for e in top_errors))
    assert worst_centre < 3e-3, [e for e in top_errors if e[1] >= 3e-3]
    assert worst_yaw < 1.0, [e for e in top_errors if np.degrees(e[2]) >= 1.0]
    # The handle's axis height and the length come out too (not required, but used).
    assert max(e[3] for e in top_errors) < 4e-3
    assert max(e[4] for e in top_errors) < 8e-3


TILTS_DEG = (0.0, 10.0, -20.0, 35.0)
OFFSETS = (0.0, 0.03, -0.04)


def _held_rod_scene(ur5, name):
    """(sim, rig, place) with ``OBJECTS[name]`` held in the jaws at the measurement pose;
    ``place(tilt_deg, offset)`` sets the rod kinematically and returns its true T_ee_obj."""
    q = solve_ik(ur5, top_down_frame(0.55, 0.0, 0.45, 0.4), Q_PARK)
    obj = OBJECTS[name]
    model = build_model(extras=[lambda s, o=obj: add_object(s, o, np.eye(4), parent="eelink")])
    sim = Simulation(model)
    sim.reset_arm(q, finger_q=0.045 - obj.thickness / 2)
    body = model.body("object").id

    def place(tilt_deg, offset):
        # Rod frame in the ee frame: rotated by the tilt about ee-y, held `offset` from its
        # centre (the jaws at obj x = offset).
        a = np.radians(tilt_deg)
        R = np.array([[np.cos(a), 0, np.sin(a)], [0, 1, 0], [-np.sin(a), 0, np.cos(a)]])
        T_ee_obj = np.eye(4)
        T_ee_obj[:3, :3] = R
        T_ee_obj[:3, 3] = -R @ np.array([offset, 0.0, 0.0])
        quat = np.zeros(4)
        mujoco.mju_mat2Quat(quat, R.ravel())
        model.body_pos[body] = T_ee_obj[:3, 3]
        model.body_quat[body] = quat
        mujoco.mj_forward(model, sim.data)
        return T_ee_obj

    return sim, CameraRig(model), place


def _wrist_frame(name="obj2", tilt_deg=10.0):
    """(T_ee_obj, T_ee_cam, camera, depth): the wrist camera's render (m, float) of
    ``OBJECTS[name]`` held at ``tilt_deg`` at the measurement pose, and the truth."""
    from comgrasp_pin.robot import RobotModel
    from comgrasp_pin.simulation.eyes import side_camera_pose
    from comgrasp_pin.simulation.world import SIDE_CAMERA

    ur5 = RobotModel.ur5()
    sim, rig, place = _held_rod_scene(ur5, name)
    T_ee_obj = place(tilt_deg, 0.0)
    _, T_ee_cam = side_camera_pose(ur5, sim.q)
    camera, depth = rig.intrinsics(SIDE_CAMERA), rig.depth(sim.data, SIDE_CAMERA)
    rig.close()
    return T_ee_obj, T_ee_cam, camera, depth


def _side_view_errors(view, T_ee_obj, offset):
    """(tilt error (rad), axis error (m), grasp-position error (m)) against the truth."""
    R = T_ee_obj[:3, :3]
    # True tilt (the view's axis has positive ee-x: compared modulo a half turn).
    theta_true = np.arctan2(-R[2, 0], R[0, 0])
    # Distance of the true axis point nearest the TCP from the seen axis.
    p_true = T_ee_obj[:3, 3] + offset * R[:, 0]
    seen_o, seen_x = view.T_ee_obj[:3, 3], view.T_ee_obj[:3, 0]
    d = p_true - seen_o
    axis_err = np.linalg.norm(d - (d @ seen_x) * seen_x)
    sign = np.sign(seen_x @ R[:, 0])
    grasp_err = abs(view.grasp_offset - sign * offset)
    return abs(_wrap_half_turn(view.theta - theta_true)), axis_err, grasp_err


@pytest.fixture(scope="module")
def side_errors(ur5):
    """Tilt, axis and grasp-position errors of rods held in the jaws (rendered only)."""
    errors = []
    for name in ("obj1", "obj2", "obj4", "obj5", "obj6"):  # round handles (obj3 is a flat bar)
        obj = OBJECTS[name]
        sim, rig, place = _held_rod_scene(ur5, name)
        for tilt in TILTS_DEG:
            for offset in OFFSETS:
                T_ee_obj = place(tilt, offset)
                view = look_from_side(
                    rig, sim.data, ur5, sim.q, rod_length=obj.length, finger_q=sim.finger_q[0]
                )
                errors.append((name, tilt, offset, *_side_view_errors(view, T_ee_obj, offset)))
        rig.close()
    return errors


def test_side_view_tilt_axis_and_grasp_position(side_errors):
    assert len(side_errors) >= 48
    worst_theta = np.degrees(max(e[3] for e in side_errors))
    worst_axis = max(e[4] for e in side_errors)
    worst_grasp = max(e[5] for e in side_errors)
    assert worst_theta < 0.5, sorted(side_errors, key=lambda e: -e[3])[:3]
    assert worst_axis < 2e-3, sorted(side_errors, key=lambda e: -e[4])[:3]
    # Every view, also where an end leaves the image, hides behind the robot, or is a
    # round cap seen from behind (thick, long rods, steeply tilted).
    assert worst_grasp < 3e-3, sorted(side_errors, key=lambda e: -e[5])[:3]


@pytest.mark.parametrize("name", ["obj5", "obj6"])
def test_side_view_tilt_when_the_fingers_read_the_handle_thinner(ur5, name):
    """Under the grip the pads give, so the fingers read a thick handle's radius up to a
    millimetre small; the axis fitted with that radius misfits and the slice line alone is
    biased by 1-5 deg on these handles (measured). The tilt must hold all the same."""
    obj = OBJECTS[name]
    sim, rig, place = _held_rod_scene(ur5, name)
    errors = []
    for tilt in (10.0, 17.0, -25.0):
        for give in (0.0005, 0.001):
            T_ee_obj = place(tilt, 0.03)
            view = look_from_side(rig, sim.data, ur5, sim.q, rod_length=obj.length,
                                  finger_q=sim.finger_q[0] + give)  # fmt: skip
            errors.append(np.degrees(_side_view_errors(view, T_ee_obj, 0.03)[0]))
    rig.close()
    assert max(errors) < 0.3, errors


def test_side_view_neither_end_seen_uses_the_centre_hint(ur5):
    """An axe hanging at -34 deg: its head leaves the image and its handle's end reaches
    behind the arm. The grasp position then comes from where the rod's centre was when it
    was grasped (top view: here 2 mm off), within the bounds the ends seen set."""
    obj = OBJECTS["obj6"]
    sim, rig, place = _held_rod_scene(ur5, "obj6")
    offset = 0.033
    T_ee_obj = place(-34.3, offset)
    kwargs = dict(rod_length=obj.length, finger_q=sim.finger_q[0])
    try:
        with pytest.raises(ObjectCutByBorderError, match="neither end"):
            look_from_side(rig, sim.data, ur5, sim.q, **kwargs)
        view = look_from_side(rig, sim.data, ur5, sim.q, centre_hint=-offset + 0.002, **kwargs)
    finally:
        rig.close()
    theta_err, axis_err, grasp_err = _side_view_errors(view, T_ee_obj, offset)
    assert np.degrees(theta_err) < 0.5 and axis_err < 2e-3 and grasp_err < 3e-3


def test_side_view_of_a_rod_hanging_steeply(ur5):
    """Regression (accuracy trial obj6, seed trial_seed(0, 'obj6', 2)): the axe hung at
    65 deg in the jaws, 7 cm off its centre, when the side view measured it (and fell out
    later, at the rolled pose). The view must give that tilt and grasp position."""
    obj = OBJECTS["obj6"]
    sim, rig, place = _held_rod_scene(ur5, "obj6")
    offset = -0.0716
    try:
        T_ee_obj = place(-114.5, offset)
        view = look_from_side(rig, sim.data, ur5, sim.q, rod_length=obj.length,
                              centre_hint=-offset, finger_q=sim.finger_q[0])  # fmt: skip
    finally:
        rig.close()
    theta_err, axis_err, grasp_err = _side_view_errors(view, T_ee_obj, offset)
    assert np.degrees(theta_err) < 0.5 and axis_err < 2e-3 and grasp_err < 3e-3


@pytest.fixture(scope="module")
def empty_scene():
    sim = Simulation()
    sim.reset_arm(Q_PARK)
    rig = CameraRig(sim.model)
    yield sim, rig
    rig.close()


def _top_inputs(sim, rig):
    return (
        rig.rgb(sim.data, TOP_CAMERA),
        rig.depth(sim.data, TOP_CAMERA),
        rig.intrinsics(TOP_CAMERA),
        rig.T_world_cam(sim.data, TOP_CAMERA),
    )


def test_no_object_on_the_table(empty_scene):
    with pytest.raises(ObjectNotFoundError):
        detect_rod_top_down(*_top_inputs(*empty_scene))


def test_nothing_held_in_the_jaws(empty_scene, ur5):
    sim, rig = empty_scene
    with pytest.raises(ObjectNotFoundError, match="nothing is held"):
        look_from_side(rig, sim.data, ur5, sim.q)


def test_bad_depth_images(empty_scene):
    rgb, depth, camera, T = _top_inputs(*empty_scene)
    with pytest.raises(InvalidDepthError, match="shape"):
        detect_rod_top_down(rgb, depth[:-1], camera, T)
    with pytest.raises(InvalidDepthError, match="NaN"):
        detect_rod_top_down(rgb, np.where(depth > 0, np.nan, depth), camera, T)
    with pytest.raises(InvalidDepthError, match="no valid"):
        detect_rod_top_down(rgb, np.full_like(depth, np.inf), camera, T)


def test_object_cut_by_the_image_border():
    obj = OBJECTS["obj5"]
    model = build_model(extras=[lambda s: add_object(s, obj, (0.55, 0.0, 0.0))])
    sim = Simulation(model)
    sim.reset_arm(Q_PARK)
    rig = CameraRig(model)
    rgb, depth, camera, T = _top_inputs(sim, rig)
    rig.close()
    # A camera that sees only the left part of the same image: the rod runs out of it.
    u_cut = int(camera.project(np.linalg.inv(T)[:3, :3] @ np.array([0.55, 0, 0])
                               + np.linalg.inv(T)[:3, 3])[0][0])  # fmt: skip
    cropped = PinholeCamera(u_cut, camera.height, camera.fx, camera.fy, camera.cx, camera.cy)
    with pytest.raises(ObjectCutByBorderError):
        detect_rod_top_down(rgb[:, :u_cut], depth[:, :u_cut], cropped, T)


def test_slip_monitor():
    monitor = SlipMonitor()
    for k in range(10):
        monitor.add(0.1 * k, 0.0)
    settled = monitor.verdict()
    assert not settled.slipping and not settled.slip_seen
    for k in range(10, 15):
        monitor.add(0.1 * k, np.radians(2.0 * (k - 9)))  # 20 deg/s
    slipping = monitor.verdict()
    assert slipping.slipping and slipping.slip_seen and slipping.rate_deg_s > 10
    for k in range(15, 25):
        monitor.add(0.1 * k, np.radians(10.0))
    after = monitor.verdict()
    assert not after.slipping and after.slip_seen and abs(after.change_deg - 10.0) < 1e-9
    with pytest.raises(ComGraspError):
        monitor.add(0.0, 0.0)  # out of order
    with pytest.raises(ComGraspError):
        SlipMonitor().verdict()


def test_slip_monitor_ignores_one_bad_frame():
    monitor = SlipMonitor()
    for k, theta_deg in enumerate([-13.2, 0.0, 0.3, 0.1, 0.0, 0.0, 0.0]):  # seen in a trial
        monitor.add(0.2 * k, np.radians(theta_deg))
    verdict = monitor.verdict()
    assert not verdict.slip_seen and verdict.change_deg < 1.0
    assert abs(np.degrees(monitor.settled_tilt())) < 0.1
    monitor.add(1.4, np.radians(20.0))  # the rod starts to turn: one frame is not enough
    assert abs(np.degrees(monitor.settled_tilt())) < 0.1
    assert abs(np.degrees(monitor.largest_tilt())) < 0.4
    monitor.add(1.6, np.radians(30.0))
    assert np.degrees(monitor.settled_tilt()) == pytest.approx(20.0)
    assert np.degrees(monitor.largest_tilt()) == pytest.approx(20.0)  # median of 0, 20, 30
    assert monitor.verdict().slip_seen


def _detection_with_widths(profile):
    """A RodDetection whose 1 cm slices have the widths ``profile(position)`` (m)."""
    from comgrasp_pin.motion.ik import GraspPose
    from comgrasp_pin.perception import RodDetection

    pos = np.arange(-0.195, 0.2, 0.01)
    widths = np.c_[pos, [profile(p) for p in pos]]
    mask, rect, axis_px = np.zeros((4, 4), bool), ((0, 0), (1, 1), 0.0), np.zeros((2, 2))
    return RodDetection(
        GraspPose(0.5, 0.0, 0.01, 0.0), 0.40, widths, 0.0, 0.02, mask, rect, axis_px
    )


def test_graspable_points_keep_the_pads_off_wide_heads():
    from comgrasp_pin.perception.top_view.top_down import nearest_graspable, nearest_on_handle

    # A 2 cm handle with a 6 cm head (the jaws fit around it) from 0.12 m to the end.
    torch = _detection_with_widths(lambda p: 0.06 if p > 0.12 else 0.02)
    assert nearest_graspable(torch, 0.031) == 0.031  # not rounded to a 1 cm slice
    assert nearest_graspable(torch, 0.15) == pytest.approx(0.15)  # the head fits the jaws
    # On the handle: both pads (22 mm either side of the grasp) short of the head.
    s = nearest_on_handle(torch, 0.15)
    assert 0.12 - 0.022 - 0.01 <= s <= 0.12 - 0.022 + 1e-9
    assert nearest_on_handle(torch, -0.1) == -0.1
    # A 12 cm head across the rod: too wide for the jaws either way.
    mallet = _detection_with_widths(lambda p: 0.12 if p > 0.12 else 0.05)
    assert nearest_graspable(mallet, 0.16) <= 0.12 - 0.022 + 1e-9
    with pytest.raises(ObjectNotFoundError):
        nearest_graspable(_detection_with_widths(lambda p: 0.1), 0.0)


def test_depth_line_standard_error_matches_the_scatter_of_surfaces():
    """Points of one slice are one piece of surface: a handle whose surface wanders by 1 mm
    from slice to slice (point noise 0.05 mm). The stated standard error of the line's y at
    the TCP must match the spread of that y over many such handles (Monte Carlo)."""
    from comgrasp_pin.perception.side_view.side_depth import depth_line as _depth_line

    rng = np.random.default_rng(4)
    y0s, stds = [], []
    for _ in range(300):
        along = rng.uniform(-0.15, 0.15, 6000)
        piece = rng.normal(0.0, 0.001, 30)[np.clip(((along + 0.15) / 0.01).astype(int), 0, 29)]
        y = -0.02 + 0.01 * along + piece + rng.normal(0.0, 5e-5, along.size)
        y0, _, y0_std, _, _ = _depth_line(along, y)
        y0s.append(y0)
        stds.append(y0_std)
    spread = np.std(np.array(y0s) + 0.02)
    assert 0.7 < np.median(stds) / spread < 1.4, (np.median(stds), spread)


def test_a_head_joined_by_a_thin_neck_is_one_object():
    """A 1 cm stick's head joined to its handle by a 2 px neck: the 3 x 3 opening cuts the
    neck, and the two pieces (one blob before it) stay one object; two blobs with a gap of
    1 px stay two."""
    from comgrasp_pin.perception._points import largest_component
    from comgrasp_pin.perception.top_view.rod_shape import check_one_object

    mask = np.zeros((120, 200), bool)
    mask[56:64, 20:120] = True  # the handle, 8 px wide: 800 px
    mask[59:61, 120:126] = True  # the neck, 2 px wide
    mask[40:80, 126:150] = True  # the head, 40 x 24 px: 960 px
    blob = largest_component(mask, 100, "test image")
    assert blob[60, 140] and blob[60, 50]  # the head and the handle
    assert blob.sum() == 800 + 960  # the neck's pixels are the opening's, not the blob's
    check_one_object(mask, blob)  # one object: no AmbiguousObjectError

    apart = mask.copy()
    apart[:, 120:126] = False
    apart[:, 121:126] = mask[:, 126:127].repeat(5, axis=1)  # the head, 1 px from the handle
    blob = largest_component(apart, 100, "test image")
    assert blob[60, 140] and not blob[60, 50]
    with pytest.raises(AmbiguousObjectError):
        check_one_object(apart, blob)
