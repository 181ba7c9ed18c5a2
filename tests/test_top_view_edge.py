"""A rod laid back at the pick area's edge: the top view measures it whole where it lies
on the table's plane, also over the edge, and refuses it where it leaves the image or
dips over the edge. Real renders (ideal and the realistic preset's depth), errors against
the simulator's truth; the geometry (where the ends lie) is derived here from the pose."""

import mujoco
import numpy as np
import pytest
from _corruption import corruptions, table_scene, top_errors, top_inputs

from comgrasp_pin.config import RegraspConfig
from comgrasp_pin.errors import ObjectCutByBorderError
from comgrasp_pin.perception import detect_rod_top_down
from comgrasp_pin.perception.top_view.grasp_points import nearest_graspable, with_known_length
from comgrasp_pin.simulation.objects import OBJECTS
from comgrasp_pin.workcell import PICK_AREA, TABLE_Z

X_MIN, X_MAX, Y_MIN, Y_MAX = PICK_AREA


def _scene_at(name, x, y, yaw):
    """(clean depth, camera, T_world_cam, rgb) of ``name`` lying at (x, y, yaw)."""
    sim, rig, _ = table_scene([(name, x, y, yaw)])
    try:
        return top_inputs(sim, rig)
    finally:
        rig.close()


# (object, x, y, yaw, how far its axis' end reaches beyond the pick area (m))
OVER = [
    ("obj2", 0.55, Y_MAX + 0.04 - OBJECTS["obj2"].length / 2, np.pi / 2, 0.04),  # 4 cm over +y
    ("obj1", X_MAX + 0.06 - OBJECTS["obj1"].length / 2, 0.05, 0.0, 0.06),  # 6 cm over +x
    ("obj4", 0.55, Y_MIN + 0.005 + OBJECTS["obj4"].length / 2, np.pi / 2, 0.0),  # 5 mm short
    ("obj6", X_MIN + 0.04 + OBJECTS["obj6"].length / 2, -0.1, 0.0, 0.0),  # blade 1-2 cm in
]


@pytest.mark.parametrize("name, x, y, yaw, overhang", OVER)
@pytest.mark.parametrize("sensors", ["ideal", "realistic"])
def test_a_rod_at_or_over_the_edge_is_measured_whole(name, x, y, yaw, overhang, sensors):
    depth, camera, T, rgb = _scene_at(name, x, y, yaw)
    T_cal = np.eye(4)
    if sensors == "realistic":
        corrupt, T_cal = corruptions("top", 7)["realistic"]
        depth = corrupt(depth)
    det = detect_rod_top_down(rgb, depth, camera, T @ T_cal)
    centre_err, yaw_err_deg = top_errors(det, (x, y, yaw), T, T_cal)
    bound = 3e-3 if sensors == "ideal" else 4.5e-3  # tests/test_perception_robust.py's
    assert centre_err < bound and yaw_err_deg < 1.0, (centre_err, yaw_err_deg)
    assert abs(det.length - OBJECTS[name].length) < 8e-3
    # The axis' ends lie at (x, y) +- length / 2 along yaw; the overhang is their farthest
    # reach beyond the table (1 mm of calibration error shifts it, plus a pixel of outline).
    assert det.overhang == pytest.approx(overhang, abs=3e-3 if sensors == "ideal" else 6e-3)


def test_a_rod_leaving_the_image_is_refused_with_the_part_seen():
    """The top camera sees y up to 1.25 m tan(20 deg) = 0.455 m at the table: a rod that
    reaches 0.49 m lies partly outside its view; the detection is refused, the part seen
    comes with the error."""
    depth, camera, T, rgb = _scene_at("obj2", 0.55, 0.49 - OBJECTS["obj2"].length / 2, np.pi / 2)
    with pytest.raises(ObjectCutByBorderError, match="runs out of the top-down image") as caught:
        detect_rod_top_down(rgb, depth, camera, T)
    assert caught.value.seen.length < OBJECTS["obj2"].length - 0.02


@pytest.mark.parametrize("sensors", ["ideal", "realistic"])
def test_a_rod_dipping_over_the_edge_is_refused(sensors):
    """A hammer resting on the table's +y edge, its far part tilted 35 deg down over it: its
    part below the table's plane cannot be measured from above."""
    obj = OBJECTS["obj2"]
    sim, rig, _ = table_scene([("obj2", 0.55, 0.0, np.pi / 2)])
    pitch = np.radians(35.0)
    axis = np.array([0.0, np.cos(pitch), -np.sin(pitch)])  # obj x, towards +y and down
    inside = 0.06  # the axis crosses the edge this far (m) from the centre, at rest height
    centre = np.array([0.55, Y_MAX, TABLE_Z + obj.rest_height]) - inside * axis
    R = np.column_stack([axis, [-1.0, 0.0, 0.0], np.cross(axis, [-1.0, 0.0, 0.0])])
    quat = np.zeros(4)
    mujoco.mju_mat2Quat(quat, R.ravel())
    adr = sim.model.joint("rod0_free").qposadr[0]
    sim.data.qpos[adr : adr + 7] = np.r_[centre, quat]
    mujoco.mj_forward(sim.model, sim.data)
    depth, camera, T, rgb = top_inputs(sim, rig)
    rig.close()
    T_cal = np.eye(4)
    if sensors == "realistic":
        corrupt, T_cal = corruptions("top", 7)["realistic"]
        depth = corrupt(depth)
    with pytest.raises(ObjectCutByBorderError, match="hangs down over the edge"):
        detect_rod_top_down(rgb, depth, camera, T @ T_cal)


@pytest.mark.parametrize("sensors", ["ideal", "realistic"])
@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_a_rod_running_out_of_the_image_is_completed_with_its_known_length(sensors, sign):
    """obj1 (0.40 m) along y reaching 6 cm past the image's edge at y = +-0.455 m (the top
    camera's half view at the table, 1.25 m tan 20 deg): the part seen comes with the
    error; completed with the length known from a whole view, its centre is the truth's."""
    obj = OBJECTS["obj1"]
    y = sign * (0.455 + 0.06 - obj.length / 2)
    depth, camera, T, rgb = _scene_at("obj1", 0.6, y, np.pi / 2)
    T_cal = np.eye(4)
    if sensors == "realistic":
        corrupt, T_cal = corruptions("top", 7)["realistic"]
        depth = corrupt(depth)
    with pytest.raises(ObjectCutByBorderError, match="runs out of the top-down image") as caught:
        detect_rod_top_down(rgb, depth, camera, T @ T_cal)
    seen = caught.value.seen
    assert seen is not None and seen.cut_end != 0
    # the cut end points out of the image: along +yaw when cut_end is +1
    towards = seen.cut_end * np.array([np.cos(seen.grasp.yaw), np.sin(seen.grasp.yaw)])
    assert np.sign(towards[1]) == sign
    assert 0.25 < seen.length < obj.length - 0.04
    whole = with_known_length(seen, obj.length, RegraspConfig().min_seen_share)
    centre_err, yaw_err_deg = top_errors(whole, (0.6, y, np.pi / 2), T, T_cal)
    bound = 3e-3 if sensors == "ideal" else 6e-3
    assert centre_err < bound and yaw_err_deg < 1.0, (centre_err, yaw_err_deg)
    assert whole.length == obj.length and whole.cut_end == seen.cut_end
    # a grasp goes only where the pads lie on slices seen
    far = 0.5 * obj.length * seen.cut_end - 0.03 * seen.cut_end
    reach = nearest_graspable(whole, far)
    seen_end = whole.widths[:, 0].max() if seen.cut_end > 0 else whole.widths[:, 0].min()
    assert abs(reach) + 0.022 <= abs(seen_end) + 0.01 + 1e-9
    with pytest.raises(ObjectCutByBorderError, match="too little"):
        with_known_length(seen, 2.0 * obj.length, 0.6)
