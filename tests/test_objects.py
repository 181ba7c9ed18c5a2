"""The six rod objects: specs, explicit inertial (pos_real), lying still, ground truth read-back."""

import mujoco
import numpy as np
import pytest

from comgrasp_pin.errors import ComGraspError
from comgrasp_pin.simulation import build_spec
from comgrasp_pin.simulation.objects import (
    OBJECTS,
    add_object,
    get_object,
    object_state,
    pose_on_table,
    tilt_angle,
)


def test_six_objects_within_the_issue_ranges():
    names = [f"obj{i}" for i in range(1, 7)]
    assert sorted(OBJECTS) == names
    thickness = [get_object(n).thickness for n in names]
    assert thickness[0] == pytest.approx(0.01) and 0.05 <= thickness[-1] <= 0.06
    assert np.all(np.diff(thickness) > 0)
    for n in names:
        o = get_object(n)
        assert 0.25 <= o.length <= 0.45 and 0.2 <= o.mass <= 1.5
        assert abs(o.com()[0]) > 0.02  # mass unevenly spread
        for p in o.parts:
            assert -o.length / 2 - 1e-12 <= p.x0 < p.x1 <= o.length / 2 + 1e-12
        assert np.all(np.linalg.eigvalsh(o.inertia_about_com()) > 0)
    with pytest.raises(ComGraspError, match="obj1"):
        get_object("hammer")


@pytest.mark.parametrize("name", ["obj1", "obj3", "obj6"])
def test_pos_real_and_length_set_per_trial_and_rod_lies_still(name):
    o = get_object(name).scaled(0.9 * get_object(name).length)
    pos_real = -0.2 * o.length
    spec = build_spec()
    add_object(spec, o, (0.55, -0.1, 0.8), pos_real=pos_real)
    m = spec.compile()
    d = mujoco.MjData(m)
    mujoco.mj_forward(m, d)
    b = m.body("object").id
    assert m.body_mass[b] == pytest.approx(o.mass)
    assert m.body_ipos[b][0] == pytest.approx(pos_real)
    s0 = object_state(m, d)
    assert s0.pos_real == pytest.approx(pos_real)
    np.testing.assert_allclose(s0.T_world_obj, pose_on_table(0.55, -0.1, 0.8, o), atol=1e-9)
    np.testing.assert_allclose(s0.p_world_com, s0.T_world_obj[:3, :3] @ s0.com_obj
                               + s0.T_world_obj[:3, 3], atol=1e-9)  # fmt: skip
    # the geoms span the set length along obj-x
    R, p = s0.T_world_obj[:3, :3], s0.T_world_obj[:3, 3]
    ends = []
    for g in range(m.ngeom):
        if m.geom_bodyid[g] == b:
            centre = R.T @ (d.geom_xpos[g] - p)
            ext = m.geom_size[g][0] + (m.geom_size[g][1] if m.geom_type[g] == 3 else 0.0)
            ends += [centre[0] - ext, centre[0] + ext]
    assert min(ends) == pytest.approx(-o.length / 2) and max(ends) == pytest.approx(o.length / 2)
    for _ in range(1500):
        mujoco.mj_step(m, d)
    s1 = object_state(m, d)
    assert np.linalg.norm(s1.T_world_obj[:3, 3] - s0.T_world_obj[:3, 3]) < 1e-3
    cos = (np.trace(s0.T_world_obj[:3, :3].T @ s1.T_world_obj[:3, :3]) - 1) / 2
    assert np.degrees(np.arccos(min(1.0, cos))) < 0.5


def test_tilt_angle_about_the_jaw_axis():
    T = np.eye(4)
    a = 0.3
    T[:3, :3] = [[np.cos(a), 0, np.sin(a)], [0, 1, 0], [-np.sin(a), 0, np.cos(a)]]
    assert tilt_angle(np.eye(4), T) == pytest.approx(a)
    assert tilt_angle(T, np.eye(4)) == pytest.approx(-a)
