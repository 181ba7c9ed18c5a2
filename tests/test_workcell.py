"""``comgrasp_pin.workcell`` (plain XML reading of sim/scene.xml and the URDF) against the world
MuJoCo compiles from the same files.

Every expected value comes from the compiled ``mujoco.MjModel`` (world positions after
``mj_forward``, ``geom_size`` half sizes, joint ranges, keyframes) or, for the named poses, from
what scene.xml documents they mean (eelink 0.30 m above a given point, pointing down), checked
with Pinocchio's and MuJoCo's forward kinematics.
"""

import mujoco
import numpy as np
import pytest

from comgrasp_pin import workcell
from comgrasp_pin.simulation.world import ARM_JOINTS, EE_SITE, FINGER_JOINTS

BOX = mujoco.mjtGeom.mjGEOM_BOX
PLANE = mujoco.mjtGeom.mjGEOM_PLANE
DROP_WALLS = ("drop_wall_n", "drop_wall_s", "drop_wall_e", "drop_wall_w")


@pytest.fixture(scope="module")
def data(world_model):
    """The compiled world at qpos0: every joint at 0, so the fingers are fully open."""
    d = mujoco.MjData(world_model)
    mujoco.mj_forward(world_model, d)
    return d


def _extent(model, data, geom: str) -> np.ndarray:
    """(x0, x1, y0, y1, z0, z1) of an axis-aligned box geom in the compiled world."""
    gid = model.geom(geom).id
    assert model.geom_type[gid] == BOX, geom
    np.testing.assert_allclose(data.geom_xmat[gid].reshape(3, 3), np.eye(3), atol=1e-12)
    c, h = data.geom_xpos[gid], model.geom_size[gid]
    return np.array([c[0] - h[0], c[0] + h[0], c[1] - h[1], c[1] + h[1], c[2] - h[2], c[2] + h[2]])


def _body_geoms(model, body: str) -> list[str]:
    bid = model.body(body).id
    return [model.geom(g).name for g in range(model.ngeom) if model.geom_bodyid[g] == bid]


def _union_footprint(model, data, geoms) -> tuple[float, ...]:
    """(x_min, x_max, y_min, y_max, top z) of a set of box geoms."""
    e = np.array([_extent(model, data, g) for g in geoms])
    return (e[:, 0].min(), e[:, 1].max(), e[:, 2].min(), e[:, 3].max(), e[:, 5].max())


def _in_ee(model, data, geom: str | int) -> tuple[np.ndarray, np.ndarray]:
    """Centre and half sizes of a box geom (name or id) in the eelink site's frame (the geom
    must be aligned with it, so that its half sizes are along the ee axes)."""
    site = model.site(EE_SITE).id
    gid = geom if isinstance(geom, int) else model.geom(geom).id
    R = data.site_xmat[site].reshape(3, 3)
    R_rel = R.T @ data.geom_xmat[gid].reshape(3, 3)
    np.testing.assert_allclose(R_rel, np.eye(3), atol=1e-9, err_msg=geom)
    return R.T @ (data.geom_xpos[gid] - data.site_xpos[site]), model.geom_size[gid]


# --- the scene ---------------------------------------------------------------------------------


def test_table_top_face_is_table_z(world_model, data):
    assert workcell.TABLE_Z == pytest.approx(_extent(world_model, data, "table_top")[5], abs=1e-12)


def test_pick_area_is_the_table_tops_footprint(world_model, data):
    x0, x1, y0, y1, _, _ = _extent(world_model, data, "table_top")
    np.testing.assert_allclose(workcell.PICK_AREA, [x0, x1, y0, y1], atol=1e-12)


def test_drop_box_centre_lies_midway_between_opposite_walls(world_model, data):
    n, s, e, w = (_extent(world_model, data, g) for g in DROP_WALLS)
    centre = (0.5 * (e[0] + w[1]), 0.5 * (n[2] + s[3]))
    np.testing.assert_allclose(workcell.DROP_BOX_XY, centre, atol=1e-12)


def test_drop_box_inner_half_sizes_between_the_walls_inner_faces(world_model, data):
    n, s, e, w = (_extent(world_model, data, g) for g in DROP_WALLS)
    inner = (0.5 * (e[0] - w[1]), 0.5 * (n[2] - s[3]))  # east's west face, north's south face
    np.testing.assert_allclose(workcell.DROP_BOX_INNER_HALF, inner, atol=1e-12)


def test_drop_box_wall_top(world_model, data):
    tops = [_extent(world_model, data, g)[5] for g in DROP_WALLS]
    assert tops == pytest.approx([tops[0]] * 4, abs=1e-12)  # one wall height
    assert workcell.DROP_BOX_WALL_Z == pytest.approx(tops[0], abs=1e-12)


def test_obstacles_are_the_union_extents_of_table_drop_box_and_pedestal(world_model, data):
    expected = [
        _union_footprint(world_model, data, _body_geoms(world_model, "table")),
        _union_footprint(world_model, data, _body_geoms(world_model, "drop_box")),
        _union_footprint(world_model, data, ["pedestal"]),
    ]
    assert len(workcell.OBSTACLES) == 3
    for got, want in zip(workcell.OBSTACLES, expected, strict=True):
        np.testing.assert_allclose(got, want, atol=1e-12)


def test_floor_z_is_the_floor_planes_height(world_model, data):
    gid = world_model.geom("floor").id
    assert world_model.geom_type[gid] == PLANE
    np.testing.assert_allclose(data.geom_xmat[gid].reshape(3, 3)[:, 2], [0, 0, 1], atol=1e-12)
    assert workcell.FLOOR_Z == pytest.approx(data.geom_xpos[gid][2], abs=1e-12)


def test_put_down_spot_is_the_put_down_site(world_model, data):
    p = data.site_xpos[world_model.site("put_down").id]
    np.testing.assert_allclose(workcell.PUT_DOWN_XY, p[:2], atol=1e-12)


def test_put_down_spot_lies_on_the_table(world_model, data):
    x0, x1, y0, y1, _, z1 = _extent(world_model, data, "table_top")
    x, y = workcell.PUT_DOWN_XY
    assert x0 < x < x1 and y0 < y < y1
    assert data.site_xpos[world_model.site("put_down").id][2] == pytest.approx(z1, abs=1e-12)


# --- the named poses ---------------------------------------------------------------------------

# What scene.xml says each pose means: eelink 0.30 m above (x, y), pointing down.
POSES = {
    "home": (workcell.Q_HOME, (0.45, 0.0, 0.30)),
    "park": (workcell.Q_PARK, (0.12, -0.42, 0.30)),
}
POSE_TOL = 3e-3  # m: the keys' joint angles are written to 4 decimals


@pytest.mark.parametrize("name", sorted(POSES))
def test_pose_equals_the_compiled_keyframe_at_the_arm_joints(world_model, name):
    key = world_model.key(name).qpos
    q_key = [key[world_model.joint(j).qposadr[0]] for j in ARM_JOINTS]
    np.testing.assert_allclose(POSES[name][0], q_key, rtol=0, atol=1e-12)


@pytest.mark.parametrize("name", sorted(POSES))
def test_pose_puts_the_eelink_where_documented_pinocchio(ur5, name):
    q, p_expected = POSES[name]
    T = ur5.ee_pose(q)
    np.testing.assert_allclose(T[:3, 3], p_expected, atol=POSE_TOL)
    np.testing.assert_allclose(T[:3, 2], [0.0, 0.0, -1.0], atol=1e-3)  # ee z = world -z


@pytest.mark.parametrize("name", sorted(POSES))
def test_keyframe_puts_the_eelink_where_documented_mujoco(world_model, name):
    d = mujoco.MjData(world_model)
    mujoco.mj_resetDataKeyframe(world_model, d, world_model.key(name).id)
    mujoco.mj_forward(world_model, d)
    site = world_model.site(EE_SITE).id
    np.testing.assert_allclose(d.site_xpos[site], POSES[name][1], atol=POSE_TOL)
    np.testing.assert_allclose(d.site_xmat[site].reshape(3, 3)[:, 2], [0, 0, -1], atol=1e-3)


def test_home_points_the_side_camera_boom_away_from_the_base(ur5):
    """scene.xml: "boom away" — the boom runs along ee -y, away from the robot base."""
    T = ur5.ee_pose(workcell.Q_HOME)
    assert -T[:2, 1] @ T[:2, 3] > 0.0


def test_poses_are_read_only():
    for q in (workcell.Q_HOME, workcell.Q_PARK):
        assert q.shape == (len(ARM_JOINTS),)
        with pytest.raises(ValueError):
            q[0] = 0.0


# --- the gripper -------------------------------------------------------------------------------

PADS = [("pad_left", "pad_right"), ("pad_left_contact", "pad_right_contact")]


@pytest.mark.parametrize("pad", ["pad_left", "pad_left_contact", "pad_right", "pad_right_contact"])
def test_pad_half_sizes(world_model, pad):
    np.testing.assert_allclose(
        workcell.GRIPPER.pad_half, world_model.geom_size[world_model.geom(pad).id]
    )


def test_pad_geoms_sit_on_the_fingers(world_model):
    for side in ("left", "right"):
        for pad in (f"pad_{side}", f"pad_{side}_contact"):
            assert (
                world_model.geom_bodyid[world_model.geom(pad).id]
                == world_model.body(f"finger_{side}").id
            )


@pytest.mark.parametrize("joint", FINGER_JOINTS)
def test_finger_travel_is_the_finger_joints_upper_limit(world_model, joint):
    jid = world_model.joint(joint).id
    assert world_model.jnt_limited[jid]
    lower, upper = world_model.jnt_range[jid]
    assert lower == 0.0  # 0 is open
    assert workcell.GRIPPER.finger_travel == pytest.approx(upper, abs=1e-12)


def _pad_gap(model, data, left: str, right: str) -> float:
    """Distance between the two pads' inner faces along ee-y."""
    (pl, hl), (pr, hr) = _in_ee(model, data, left), _in_ee(model, data, right)
    assert pl[1] > 0.0 > pr[1]  # left pad at +ee-y, right at -ee-y
    return (pl[1] - hl[1]) - (pr[1] + hr[1])


@pytest.mark.parametrize(("left", "right"), PADS)
def test_open_gap_between_the_pad_faces(world_model, data, left, right):
    assert _pad_gap(world_model, data, left, right) == pytest.approx(
        2.0 * workcell.GRIPPER.open_half_gap, abs=1e-9
    )


@pytest.mark.parametrize(("left", "right"), PADS)
def test_pads_are_centred_on_the_eelink(world_model, data, left, right):
    """The TCP lies midway between the pads (URDF: "midway between the pads")."""
    (pl, hl), (pr, hr) = _in_ee(world_model, data, left), _in_ee(world_model, data, right)
    assert 0.5 * ((pl[1] - hl[1]) + (pr[1] + hr[1])) == pytest.approx(0.0, abs=1e-9)
    np.testing.assert_allclose([pl[0], pr[0]], 0.0, atol=1e-9)


def test_closed_fingers_leave_the_documented_1_mm_gap(world_model):
    """URDF: each finger at its upper limit closes the jaws to a 1 mm gap."""
    d = mujoco.MjData(world_model)
    for j in FINGER_JOINTS:
        d.qpos[world_model.joint(j).qposadr[0]] = workcell.GRIPPER.finger_travel
    mujoco.mj_forward(world_model, d)
    assert _pad_gap(world_model, d, "pad_left_contact", "pad_right_contact") == pytest.approx(
        0.001, abs=1e-9
    )


@pytest.mark.parametrize("pad", ["pad_left", "pad_left_contact", "pad_right", "pad_right_contact"])
def test_fingertips_lie_beyond_the_eelink(world_model, data, pad):
    centre, half = _in_ee(world_model, data, pad)
    assert centre[2] + half[2] == pytest.approx(workcell.GRIPPER.fingertip_below_ee, abs=1e-9)


def _colliding_geoms(model, body: str) -> list[int]:
    bid = model.body(body).id
    return [
        g
        for g in range(model.ngeom)
        if model.geom_bodyid[g] == bid and (model.geom_contype[g] or model.geom_conaffinity[g])
    ]


def test_finger_box_behind_the_pad(world_model):
    """The left finger's colliding box other than its pad: half sizes and centre in the
    finger's frame (whose origin is on the pad face)."""
    pad = world_model.geom("pad_left_contact").id
    (finger,) = [g for g in _colliding_geoms(world_model, "finger_left") if g != pad]
    np.testing.assert_allclose(workcell.GRIPPER.finger_half, world_model.geom_size[finger])
    np.testing.assert_allclose(
        workcell.GRIPPER.finger_centre, world_model.geom_pos[finger], atol=1e-12
    )
    np.testing.assert_allclose(world_model.geom_quat[finger], [1, 0, 0, 0], atol=1e-12)


def test_palm_size_and_extent_along_ee_z(world_model, data):
    (palm,) = _colliding_geoms(world_model, "gripper_base")
    centre, half = _in_ee(world_model, data, palm)
    np.testing.assert_allclose(workcell.GRIPPER.palm_half, half)
    np.testing.assert_allclose(
        workcell.GRIPPER.palm_z, [centre[2] - half[2], centre[2] + half[2]], atol=1e-9
    )


def test_tool_to_ee_is_the_flange_to_eelink_distance(world_model, data):
    site = world_model.site(EE_SITE).id
    R = data.site_xmat[site].reshape(3, 3)
    flange = R.T @ (data.xpos[world_model.body("tool0").id] - data.site_xpos[site])
    np.testing.assert_allclose(flange, [0.0, 0.0, -workcell.GRIPPER.tool_to_ee], atol=1e-9)


def test_gravity_is_the_compiled_worlds_and_the_arm_models(world_model):
    from comgrasp_pin.robot import RobotModel

    np.testing.assert_array_equal(workcell.GRAVITY_WORLD, world_model.opt.gravity)
    np.testing.assert_array_equal(RobotModel.ur5().model.gravity.linear, world_model.opt.gravity)
