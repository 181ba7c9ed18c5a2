"""The held rod's motion between two views, and the estimate that stacks poses with it.

References: the motion built by hand in the test (a turn about the jaw axis, a shift along
it, a turn out of the jaws' plane) and Pinocchio RNEA with the payload where it really sat
at each pose (tests/_payload.py)."""

import numpy as np
import pytest
from _payload import payload_torques

import comgrasp_pin as cg
from comgrasp_pin.config import RegraspConfig
from comgrasp_pin.estimation.regressor import pose_regressor
from comgrasp_pin.perception.side_view.side_view import SideView
from comgrasp_pin.planning.holding import holding_lever
from comgrasp_pin.planning.regrasp import needs_another_pose
from comgrasp_pin.planning.wrist_poses import best_next_pose
from comgrasp_pin.procedures.rod_motion import rod_motion


def _view(theta, offset, y0=0.0, slope=0.0, centre_along=0.05):
    """A side view of a rod tilted by theta about ee-y whose axis passes ``offset`` (m) from
    the TCP (its point nearest the TCP, the foot, is ``offset`` along the axis' normal)."""
    x = np.array([np.cos(theta), 0.0, -np.sin(theta)])
    foot = offset * np.array([np.sin(theta), 0.0, np.cos(theta)])
    T = np.eye(4)
    T[:3, :3] = np.column_stack([x, [0.0, 1.0, 0.0], np.cross(x, [0.0, 1.0, 0.0])])
    T[:3, 3] = foot + centre_along * x
    return SideView(T, theta, 0.3, -centre_along, None, None, None, None, 0.01, 0.02, 1e-4,
                    1e-3, y0, slope, 1e-5, 1e-4)  # fmt: skip


def test_rod_motion_carries_the_rod_where_the_second_view_saw_it():
    first = _view(np.radians(10.0), 0.004, y0=-0.004, slope=0.06)
    dtheta, dy, dslope = np.radians(1.5), 0.0008, 0.01
    second = _view(np.radians(10.0) + dtheta, 0.0035, y0=-0.004 + dy, slope=0.06 + dslope)
    M = rod_motion(first, second)
    # the rod's points in the first view, counted along the axis from its foot; the rod
    # turns about where the jaws hold it (that foot), shifts along the jaws and across its
    # axis onto the second view's line, and does not slide along itself: the foot lands on
    # the second line's point nearest it
    foot1 = first.T_ee_obj[:3, 3] - 0.05 * first.T_ee_obj[:3, 0]
    a2 = second.T_ee_obj[:3, 0] + np.array([0.0, dslope, 0.0])
    a2 /= np.linalg.norm(a2)
    foot2 = second.T_ee_obj[:3, 3] - 0.05 * second.T_ee_obj[:3, 0] + np.array([0.0, dy, 0.0])
    landed = foot2 + ((foot1 - foot2) @ a2) * a2
    for s in (0.0, 0.1, -0.07):
        p1 = np.r_[foot1 + s * first.T_ee_obj[:3, 0], 1.0]
        np.testing.assert_allclose((M @ p1)[:3], landed + s * a2, atol=1e-12)
    np.testing.assert_allclose(M[:3, :3] @ M[:3, :3].T, np.eye(3), atol=1e-12)
    # a view seen the other way round (x flipped) is the same rod
    flipped = _view(np.radians(10.0) + dtheta, 0.0035, y0=-0.004 + dy, slope=0.06)
    T = flipped.T_ee_obj.copy()
    T[:3, :2] *= -1.0
    from dataclasses import replace

    same = rod_motion(first, replace(flipped, T_ee_obj=T, surface_slope=-(0.06 + dslope)))
    np.testing.assert_allclose(same, M, atol=1e-12)


def test_stacking_poses_with_the_payloads_motion_finds_the_com():
    """The payload sat 1 mm further along ee-y and turned 1 deg at the second pose: with the
    motion given the estimate is exact; without it, it is off."""
    ur5 = cg.RobotModel.ur5()
    rng = np.random.default_rng(3)
    q0 = ur5.random_configuration(rng)
    Q = np.stack([q0, q0 + np.r_[0.0, 0.0, 0.0, 0.2, 0.35, -0.3]])
    com = np.array([0.012, 0.0, 0.08])
    c, s = np.cos(np.radians(1.0)), np.sin(np.radians(1.0))
    M = np.eye(4)
    M[:3, :3] = [[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]]
    M[:3, 3] = [0.0, 0.001, 0.0]
    tb0, ta0 = payload_torques(ur5, Q[0], 0.6, com)
    tb1, ta1 = payload_torques(ur5, Q[1], 0.6, (M @ np.r_[com, 1.0])[:3])
    tb, ta = np.stack([tb0, tb1]), np.stack([ta0, ta1])
    motion = np.stack([np.eye(4), M])
    for method in ("lstsq", "ipopt"):
        est = cg.estimate_com(ur5, Q, tb, ta, method=method, payload_motion_ee=motion)
        np.testing.assert_allclose(est.com_ee, com, atol=1e-9)
        assert est.mass == pytest.approx(0.6, rel=1e-9)
    ignored = cg.estimate_com(ur5, Q, tb, ta)
    assert np.linalg.norm(ignored.com_ee - com) > 5e-4
    with pytest.raises(cg.InvalidInputError, match="payload_motion_ee"):
        cg.estimate_com(ur5, Q, tb, ta, payload_motion_ee=np.eye(4))


def test_best_next_pose_is_the_d_optimal_one_by_brute_force():
    ur5 = cg.RobotModel.ur5()
    rng = np.random.default_rng(4)
    q0 = ur5.random_configuration(rng)
    existing = np.stack([q0, q0 + np.r_[0, 0, 0, 0.0, 0.3, 0.0]])
    candidates = np.stack([q0 + np.r_[0, 0, 0, rng.uniform(-0.6, 0.6, 3)] for _ in range(7)])
    info = sum(pose_regressor(ur5, q)[0].T @ pose_regressor(ur5, q)[0] for q in existing)
    dets = [np.linalg.det(info + pose_regressor(ur5, c)[0].T @ pose_regressor(ur5, c)[0])
            for c in candidates]  # fmt: skip
    assert best_next_pose(ur5, existing, candidates) == int(np.argmax(dets))


def test_one_more_pose_when_the_com_is_known_worse_than_the_jaws_tolerate():
    config = RegraspConfig()
    lever = holding_lever(0.5, 15.0, config.pad_friction)  # 2 F (mu a + mu_t) / (m g)
    tolerance = config.holding_margin * lever / 1.96
    assert not needs_another_pose(0.99 * tolerance, 0.5, 15.0, config)
    assert needs_another_pose(1.01 * tolerance, 0.5, 15.0, config)
    assert needs_another_pose(float("nan"), 0.5, 15.0, config)
    # a heavier rod, a shorter lever: the same std is too much
    assert needs_another_pose(0.99 * tolerance, 1.5, 15.0, config)


def test_a_rod_that_turns_far_about_the_jaws_does_not_slide_along_itself():
    """A rod held 12 mm below the TCP turns 60 deg about where the pads hold it: the rigid
    motion rod_motion builds from the two views takes that point to itself (the rotation's
    centre), and every point of the rod along the turned line (written by hand)."""
    theta1, theta2 = np.radians(15.0), np.radians(75.0)
    first = _view(theta1, 0.012)
    pivot = first.T_ee_obj[:3, 3] - 0.05 * first.T_ee_obj[:3, 0]  # the first view's foot
    # the turned rod's line passes through the pivot: its distance from the TCP is the
    # pivot's component along the line's normal (the normal _view uses)
    normal2 = np.array([np.sin(theta2), 0.0, np.cos(theta2)])
    second = _view(theta2, float(pivot @ normal2))
    M = rod_motion(first, second)
    np.testing.assert_allclose((M @ np.r_[pivot, 1.0])[:3], pivot, atol=1e-12)
    turn = theta2 - theta1  # about ee-y, the jaw axis: x -> x cos - z sin (tilt sign)
    a2 = np.array([np.cos(theta2), 0.0, -np.sin(theta2)])
    for s in (0.1, -0.07):
        p = pivot + s * first.T_ee_obj[:3, 0]
        np.testing.assert_allclose((M @ np.r_[p, 1.0])[:3], pivot + s * a2, atol=1e-12)
    assert abs(np.degrees(np.arccos((np.trace(M[:3, :3]) - 1) / 2)) - np.degrees(turn)) < 1e-9


def test_depth_change_std_pairs_the_slices_two_views_share():
    """Two views of one handle whose surface wanders by 1 mm from slice to slice (the same
    pieces in both) and a 0.05 mm reading noise per slice median, the rod shifted 0.4 mm
    along the jaws: the paired standard error of the shift must match the Monte Carlo
    spread of the lines' difference, far below the two lines' errors combined."""
    from dataclasses import replace

    from comgrasp_pin.perception.side_view.side_depth import depth_line as _depth_line
    from comgrasp_pin.procedures.rod_motion import depth_change_std

    rng = np.random.default_rng(5)
    along = np.arange(-0.145, 0.15, 0.01)
    shifts, paired, unpaired = [], [], []
    for _ in range(300):
        surface = rng.normal(0.0, 0.001, along.size)
        lines = []
        for dy in (0.0, 0.0004):
            y = -0.02 + dy + surface + rng.normal(0.0, 5e-5, along.size)
            y0, slope, y0_std, slope_std, slices = _depth_line(np.repeat(along, 5),
                                                               np.repeat(y, 5))  # fmt: skip
            lines.append(replace(_view(0.1, 0.0), surface_y=y0, surface_slope=slope,
                                 surface_y_std=y0_std, surface_slope_std=slope_std,
                                 depth_slices=slices))  # fmt: skip
        shifts.append(lines[1].surface_y - lines[0].surface_y)
        paired.append(depth_change_std(lines[0], lines[1])[0])
        unpaired.append(np.hypot(lines[0].surface_y_std, lines[1].surface_y_std))
    spread = np.std(shifts)
    assert abs(np.mean(shifts) - 0.0004) < 3 * spread / np.sqrt(len(shifts))
    assert 0.7 < np.median(paired) / spread < 1.4, (np.median(paired), spread)
    assert np.median(unpaired) > 5 * spread
