"""The rod objects (the paper's six and the extras): specs, explicit inertial (pos_real),
lying still, ground truth read-back."""

import json

import mujoco
import numpy as np
import pytest

from comgrasp_pin._paths import sim_path
from comgrasp_pin.config import EpisodeConfig
from comgrasp_pin.errors import ComGraspError
from comgrasp_pin.simulation import build_spec
from comgrasp_pin.simulation.objects import (
    EXTRA_OBJECTS,
    OBJECTS,
    PAPER_OBJECTS,
    add_object,
    get_object,
    object_state,
    pose_on_table,
    tilt_angle,
)
from comgrasp_pin.workcell import GRIPPER


def test_six_paper_objects_within_the_issue_ranges():
    names = [f"obj{i}" for i in range(1, 7)]
    assert PAPER_OBJECTS == tuple(names)
    thickness = [get_object(n).thickness for n in names]
    assert thickness[0] == pytest.approx(0.01) and 0.05 <= thickness[-1] <= 0.06
    assert np.all(np.diff(thickness) > 0)
    for n in names:
        o = get_object(n)
        assert o.paper
        assert 0.25 <= o.length <= 0.45 and 0.2 <= o.mass <= 1.5
        assert abs(o.com()[0]) > 0.02  # mass unevenly spread
        for p in o.parts:
            assert -o.length / 2 - 1e-12 <= p.x0 < p.x1 <= o.length / 2 + 1e-12
        assert np.all(np.linalg.eigvalsh(o.inertia_about_com()) > 0)
    with pytest.raises(ComGraspError, match="obj1"):
        get_object("hammer")


# (length m, mass kg, handle width m, parts) of the paper's six as they were first made
PAPER_AS_MADE = {
    "obj1": (0.4, 0.51, 0.01, 2), "obj2": (0.32, 0.62, 0.02, 3), "obj3": (0.3, 0.6, 0.03, 3),
    "obj4": (0.3, 0.62, 0.04, 3), "obj5": (0.38, 1.05, 0.05, 2), "obj6": (0.45, 1.4, 0.056, 2),
}  # fmt: skip


def test_the_paper_objects_are_unchanged():
    for name, (length, mass, width, n_parts) in PAPER_AS_MADE.items():
        o = get_object(name)
        assert (o.length, o.thickness, len(o.parts)) == pytest.approx((length, width, n_parts))
        assert o.mass == pytest.approx(mass, abs=1e-12)


def test_extra_objects_are_listed_apart_and_everything_is_offered():
    assert EXTRA_OBJECTS == ("obj7", "obj8")
    assert list(OBJECTS) == [f"obj{i}" for i in range(1, 9)]
    assert not any(get_object(n).paper for n in EXTRA_OBJECTS)
    from comgrasp_pin.cli.args import OBJECTS as CLI_OBJECTS
    from comgrasp_pin.experiments.reproduce import ALL_OBJECTS

    assert CLI_OBJECTS == ALL_OBJECTS == PAPER_OBJECTS + EXTRA_OBJECTS


def _com_by_hand(name: str) -> np.ndarray:
    """The CoM from the file's raw parts: every part's bottom on the handle's bottom plane."""
    raw = json.loads(sim_path("objects.json").read_text())["objects"][name]["parts"]
    h = raw[0]["half_z_m"]
    m = np.array([p["mass_kg"] for p in raw])
    centres = np.array([[(p["x0_m"] + p["x1_m"]) / 2, 0.0, p["half_z_m"] - h] for p in raw])
    return m @ centres / m.sum()


def test_the_hammers_com_lies_well_off_its_axis():
    o = get_object("obj7")
    com = _com_by_hand("obj7")
    assert np.hypot(com[1], com[2]) >= 0.015  # the paper's assumption fails
    np.testing.assert_allclose(o.com(), com, atol=1e-12)
    assert 0.02 <= o.thickness <= 0.03 and 0.25 <= o.length <= 0.45
    # the simulator carries it: the body's CoM in MuJoCo
    spec = build_spec()
    add_object(spec, o, (0.55, 0.0, 0.3))
    m = spec.compile()
    assert m.body_ipos[m.body("object").id][2] == pytest.approx(com[2])


def test_the_thick_rod_fits_the_jaws_and_its_weight_the_grip():
    o = get_object("obj8")
    assert 0.06 <= o.thickness <= 0.07
    assert o.thickness < 2 * GRIPPER.open_half_gap - 0.015  # room to close on it
    config = EpisodeConfig()
    mu, force = config.world.pad_friction[0], config.motion.grip_force
    assert o.mass * 9.81 < 2 * mu * force  # the two pads carry its weight
    assert abs(_com_by_hand("obj8")[0]) > 0.05  # weighted at one end


@pytest.mark.parametrize("name", ["obj1", "obj3", "obj6", "obj7", "obj8"])
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
