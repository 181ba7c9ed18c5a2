"""The trial grasp's pure parts: its plan, the extra pose's choice, and the row's flags."""

from __future__ import annotations

from dataclasses import replace
from types import SimpleNamespace

import numpy as np
import pytest

from comgrasp_pin.geometry import GraspPose
from comgrasp_pin.procedures.cell import TorqueMeasurement
from comgrasp_pin.procedures.com_location import ComLocation
from comgrasp_pin.procedures.measurement import HeldReadings
from comgrasp_pin.procedures.trial_grasp import trial_measurement
from comgrasp_pin.procedures.trial_plan import extra_pose, plan_trial, rolled
from comgrasp_pin.workcell import Q_HOME

ROD = SimpleNamespace(grasp=GraspPose(0.45, 0.10, 0.02, 0.3), length=0.4)


@pytest.fixture(scope="module")
def plan(ur5):
    return plan_trial(ur5, Q_HOME, ROD, 0.02, approach=0.1, lift_height=0.3, roll_deg=30.0)


def test_the_plan_rolls_its_second_pose_about_ee_x(ur5, plan):
    assert len(plan.poses) == 2
    T0, T1 = ur5.ee_pose(plan.poses[0]), ur5.ee_pose(plan.poses[1])
    np.testing.assert_allclose(T0, plan.T_world_ee_meas, atol=1e-4)
    np.testing.assert_allclose(T1, rolled(plan.T_world_ee_meas, 30.0), atol=1e-4)


def test_extra_pose_is_none_when_no_roll_is_within_reach(ur5, plan):
    measured = np.array(plan.poses)
    assert extra_pose(ur5, plan, measured, (20.0, 45.0)) is not None
    T_far = plan.T_world_ee_meas.copy()
    T_far[2, 3] = 5.0  # 5 m up: out of any arm's reach
    unreachable = replace(plan, T_world_ee_meas=T_far)
    assert extra_pose(ur5, unreachable, measured, (20.0, 45.0)) is None


def _held(ur5, poses: list) -> HeldReadings:
    after = [TorqueMeasurement(ur5.gravity_torques(q), np.full(6, 1e-3), q, 100, 1.0)
             for q in poses]  # fmt: skip
    view = SimpleNamespace(theta=0.0, T_ee_obj=np.eye(4))
    tau_before = [ur5.gravity_torques(q) for q in poses]
    return HeldReadings(after, tau_before, [None] * len(poses), [view] * len(poses),
                        False, False, False)  # fmt: skip


def _loc() -> ComLocation:
    estimate = SimpleNamespace(mass=0.5)
    return ComLocation(estimate, estimate, 0.01, 0.01, "2 poses", 0.002, {})


def test_extra_pose_flag_says_a_pose_was_measured_not_asked_for(ur5, plan):
    """Every IK candidate failing leaves the readings as they were: the row must not count
    an extra pose then (it once said ``extra_pose=1`` whenever one was asked for)."""
    as_planned = trial_measurement(ur5, plan, _held(ur5, plan.poses), _loc())
    assert not as_planned.extra_pose
    one_more = [*plan.poses, plan.poses[0] + 0.05]
    assert trial_measurement(ur5, plan, _held(ur5, one_more), _loc()).extra_pose
