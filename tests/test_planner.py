import numpy as np
import pytest

from comgrasp_pin.config import RegraspConfig
from comgrasp_pin.errors import ComGraspError
from comgrasp_pin.geometry import GraspPose
from comgrasp_pin.motion.ik import top_down_frame
from comgrasp_pin.planning.regrasp import com_grasp, decide, rod_axis_world

CONFIG = RegraspConfig()


def test_decisions():
    assert decide(np.radians(6.0), False, 0.05, 0.0, CONFIG).regrasp
    assert decide(0.0, True, 0.0, 0.0, CONFIG).regrasp
    assert decide(0.0, False, 0.05, 0.0, CONFIG).regrasp  # far CoM, no slip yet
    keep = decide(np.radians(0.5), False, 0.004, 0.0, CONFIG)
    assert not keep.regrasp and "holds" in keep.reason
    with pytest.raises(ComGraspError):
        decide(np.nan, False, 0.0, 0.0, CONFIG)


def test_com_grasp_resolves_the_rod_direction():
    rod = GraspPose(0.5, 0.1, 0.01, np.radians(30.0))
    d = np.array([np.cos(np.radians(30)), np.sin(np.radians(30)), 0.0])
    for sign in (1.0, -1.0):
        g = com_grasp(rod, sign * d, 0.08)
        np.testing.assert_allclose([g.x, g.y], [0.5 + sign * 0.08 * d[0], 0.1 + sign * 0.08 * d[1]])
        assert g.z == rod.z


def test_rod_axis_world_from_a_held_tilted_rod():
    T_world_ee = top_down_frame(0.5, 0.0, 0.3, np.radians(90.0))  # ee-x along world +y
    tilt = np.radians(20.0)
    T_ee_obj = np.eye(4)
    T_ee_obj[:3, :3] = [
        [np.cos(tilt), 0, np.sin(tilt)],
        [0, 1, 0],
        [-np.sin(tilt), 0, np.cos(tilt)],
    ]
    np.testing.assert_allclose(rod_axis_world(T_world_ee, T_ee_obj), [0.0, 1.0, 0.0], atol=1e-12)
    vertical = np.eye(4)
    vertical[:3, :3] = [[0, 0, 1], [0, 1, 0], [-1, 0, 0]]
    with pytest.raises(ComGraspError):
        rod_axis_world(T_world_ee, vertical)
