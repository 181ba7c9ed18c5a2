"""The world's cameras see what they should, in the conventions perception relies on."""

import cv2
import numpy as np
import pytest

from comgrasp_pin.camera import PinholeCamera, transform_points
from comgrasp_pin.errors import ComGraspError
from comgrasp_pin.simulation import Simulation
from comgrasp_pin.simulation.cameras import CameraRig

Q_DOWN = np.array([0.0, -1.9, 1.9, -1.57, -1.57, 0.0])


@pytest.fixture(scope="module")
def scene():
    sim = Simulation()
    sim.reset_arm(Q_DOWN, finger_q=0.02)
    rig = CameraRig(sim.model)
    yield sim, rig
    rig.close()


def test_top_down_camera_sees_the_table_and_its_height(scene):
    sim, rig = scene
    rgb = rig.rgb(sim.data, "top_down")
    depth = rig.depth(sim.data, "top_down")
    seg = rig.segmentation(sim.data, "top_down")
    K = rig.intrinsics("top_down")
    T_world_cam = rig.T_world_cam(sim.data, "top_down")
    # The camera looks straight down from 2.0 m above the floor (floor at z = -0.75).
    np.testing.assert_allclose(T_world_cam[:3, 2], [0, 0, -1], atol=1e-12)
    assert abs(T_world_cam[2, 3] - (-0.75 + 2.0)) < 1e-12
    # Where the table should be (projected by hand), the renderer shows the table top.
    table = sim.model.geom("table_top").id
    corners_world = np.array([[0.35, -0.3, 0.0], [0.75, 0.3, 0.0], [0.55, 0.0, 0.0]])
    T_cam_world = np.linalg.inv(T_world_cam)
    uv = K.project(transform_points(T_cam_world, corners_world)).round().astype(int)
    for u, v in uv:
        assert seg[v, u] == table
    on_table = seg == table
    assert on_table.mean() > 0.3
    # The table looks like the table (its warm wood colour: red > green > blue), not the floor.
    mean_table = rgb[on_table].mean(axis=0)
    mean_floor = rgb[seg == sim.model.geom("floor").id].mean(axis=0)
    assert mean_table[0] > mean_table[1] > mean_table[2]
    assert np.linalg.norm(mean_table - mean_floor) > 30
    # Depth, back-projected with the intrinsics and extrinsics, puts the table top at z = 0.
    points = transform_points(T_world_cam, K.depth_to_points(depth)[on_table])
    assert np.abs(points[:, 2]).max() < 2e-3
    assert abs(np.median(points[:, 2])) < 5e-4


def test_side_camera_pose_matches_robot_description_and_sees_pads(scene, ur5):
    sim, rig = scene
    T_world_cam = rig.T_world_cam(sim.data, "side_camera")
    np.testing.assert_allclose(T_world_cam, ur5.frame_pose(sim.q, "side_camera"), atol=1e-9)
    # Optical axis along the jaw-closing axis (ee y), horizontal with the gripper pointing down.
    T_world_ee = ur5.ee_pose(sim.q)
    np.testing.assert_allclose(T_world_cam[:3, 2], T_world_ee[:3, 1], atol=1e-9)
    assert abs(T_world_cam[2, 2]) < 1e-3
    seg = rig.segmentation(sim.data, "side_camera")
    visible = {
        name: int((seg == sim.model.geom(name).id).sum()) for name in ("pad_left", "pad_right")
    }
    assert max(visible.values()) > 100, visible
    # A point 0.45 m long rod held at the TCP would be in view end to end.
    K = rig.intrinsics("side_camera")
    T_cam_ee = np.linalg.inv(T_world_cam) @ T_world_ee
    ends = transform_points(T_cam_ee, np.array([[-0.225, 0, 0], [0.225, 0, 0]]))
    uv = K.project(ends)
    assert np.all(
        (uv[:, 0] > 0) & (uv[:, 0] < K.width - 1) & (uv[:, 1] > 0) & (uv[:, 1] < K.height - 1)
    )


def test_pinhole_round_trip():
    K = PinholeCamera.from_fovy(640, 480, 45.0)
    rng = np.random.default_rng(4)
    p = np.c_[rng.uniform(-0.3, 0.3, (50, 2)), rng.uniform(0.2, 2.0, 50)]
    np.testing.assert_allclose(K.backproject(K.project(p), p[:, 2]), p, atol=1e-12)
    # The optical axis hits the centre of the image.
    np.testing.assert_allclose(K.project(np.array([[0, 0, 1.0]])), [[319.5, 239.5]])
    with pytest.raises(ComGraspError):
        K.project(np.array([[0, 0, -1.0]]))


def test_a_reused_renderer_draws_the_new_world_exactly():
    """CameraRig hands a closed rig's renderer to the next world with the same assets: its
    images must be those of a renderer made for that world."""
    import mujoco

    from comgrasp_pin.simulation import build_model, cameras
    from comgrasp_pin.simulation.objects import OBJECTS, add_object
    from comgrasp_pin.simulation.world import SIDE_CAMERA, TOP_CAMERA

    def world(name, pose):
        model = build_model(extras=[lambda spec: add_object(spec, OBJECTS[name], pose)])
        data = mujoco.MjData(model)
        mujoco.mj_forward(model, data)
        return model, data

    model_a, data_a = world("obj1", (0.5, 0.1, 0.3))
    model_b, data_b = world("obj6", (0.6, -0.1, -0.7))
    first = CameraRig(model_a, 160, 120)
    first.rgb(data_a, TOP_CAMERA)
    first.depth(data_a, TOP_CAMERA)
    colour, depth = first._renderer(False), first._renderer(True)
    first.close()
    reused = CameraRig(model_b, 160, 120)
    fresh = CameraRig(model_b, 160, 120)  # the pool is empty now: new renderers
    assert reused._renderer(False) is colour and fresh._renderer(False) is not colour
    assert reused._renderer(True) is depth and fresh._renderer(True) is not depth
    try:
        for camera in (TOP_CAMERA, SIDE_CAMERA):
            for image in ("rgb", "depth", "segmentation"):
                np.testing.assert_array_equal(
                    getattr(reused, image)(data_b, camera), getattr(fresh, image)(data_b, camera)
                )
        # World b's rod (the axe, not world a's stick) is in the top view.
        rod = [model_b.geom(f"object_{i}").id for i in range(len(OBJECTS["obj6"].parts))]
        assert np.isin(reused.segmentation(data_b, TOP_CAMERA), rod).sum() > 100
    finally:
        fresh.close()
        reused.close()
    assert len(cameras._IDLE_RENDERERS[cameras._assets_key(model_b, 160, 120)]) >= 2
    key = cameras._assets_key(model_b, 160, 120, cameras.DEPTH_SAMPLES)
    assert len(cameras._IDLE_RENDERERS[key]) >= 2


def test_depth_without_multisampling_is_the_multisampled_depth_to_the_bit():
    """Depth is drawn by a renderer without multisampling (half the read-back time): its
    images must be what the model's multisampled renderer resolves, rod edges included, and
    the model's own setting must be left as it was."""
    import mujoco

    from comgrasp_pin.simulation import build_model, cameras
    from comgrasp_pin.simulation.objects import OBJECTS, add_object
    from comgrasp_pin.simulation.world import SIDE_CAMERA, TOP_CAMERA

    model = build_model(extras=[lambda spec: add_object(spec, OBJECTS["obj6"], (0.5, 0.0, 0.3))])
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    samples = int(model.vis.quality.offsamples)
    assert samples > 0 and cameras.DEPTH_SAMPLES == 0
    rig = CameraRig(model)
    multisampled = CameraRig(model)
    multisampled._renderers[True] = multisampled._renderer(False)  # depth drawn by it too
    try:
        for camera in (TOP_CAMERA, SIDE_CAMERA):
            depth, expected = rig.depth(data, camera), multisampled.depth(data, camera)
            assert np.isfinite(depth).sum() > 1000
            np.testing.assert_array_equal(depth, expected)
        assert rig._renderer(True).samples == 0 and rig._renderer(False).samples == samples
        assert model.vis.quality.offsamples == samples
    finally:
        multisampled._renderers.pop(True)
        multisampled.close()
        rig.close()


def test_depth_is_drawn_without_the_shadow_pass_and_is_the_same_to_the_bit():
    """A depth frame skips the shadows' pass (most of its time in a software renderer):
    its images must be what a plain MuJoCo renderer with shadows on gives, while the colour
    image does show the shadows."""
    import mujoco

    from comgrasp_pin.simulation import build_model
    from comgrasp_pin.simulation.objects import OBJECTS, add_object
    from comgrasp_pin.simulation.world import SIDE_CAMERA, TOP_CAMERA

    model = build_model(extras=[lambda spec: add_object(spec, OBJECTS["obj6"], (0.5, 0.0, 0.3))])
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    rig, plain = CameraRig(model), mujoco.Renderer(model, 480, 640)
    try:
        for camera in (TOP_CAMERA, SIDE_CAMERA):
            plain.update_scene(data, camera)
            plain.scene.flags[mujoco.mjtRndFlag.mjRND_SHADOW] = True
            plain.enable_depth_rendering()
            expected = plain.render().astype(float)
            plain.disable_depth_rendering()
            expected[expected >= model.vis.map.zfar * model.stat.extent * 0.999] = np.inf
            np.testing.assert_array_equal(rig.depth(data, camera), expected)
        rig.shadows = True
        shaded = rig.rgb(data, TOP_CAMERA)
        rig.shadows = False
        assert np.abs(shaded.astype(int) - rig.rgb(data, TOP_CAMERA)).sum() > 1000
    finally:
        plain.close()
        rig.close()


@pytest.mark.parametrize("stride", [2, 3, 4])
def test_a_render_of_every_stride_th_pixel_is_those_pixels_of_the_full_render(stride):
    """A slip watch's frame is rendered at every stride-th pixel's centre alone (MuJoCo's
    intrinsic camera, ``sampling_every``): the full render's pixels there, up to the
    rounding of another projection matrix (within 1e-5 of the depth; 99.9 % within 3e-6),
    except where a pixel's centre lies on an edge within the rasteriser's sub-pixel
    precision (1/256 of a render pixel): there it may show the other side, as its
    neighbours in the full render do (at most 1 pixel in 1000; 2-3 a frame here). The
    model's camera is left as it was."""
    import mujoco

    from comgrasp_pin.simulation import build_model
    from comgrasp_pin.simulation.objects import OBJECTS, add_object
    from comgrasp_pin.simulation.world import SIDE_CAMERA, TOP_CAMERA

    model = build_model(extras=[lambda spec: add_object(spec, OBJECTS["obj6"], (0.5, 0.0, 0.3))])
    data = mujoco.MjData(model)
    data.qpos[:6] = Q_DOWN
    mujoco.mj_forward(model, data)
    before = [a.copy() for a in (model.cam_sensorsize, model.cam_intrinsic, model.cam_fovy)]
    rig = CameraRig(model)
    try:
        for camera in (TOP_CAMERA, SIDE_CAMERA):
            full = rig.depth(data, camera)
            sampled, expected = rig.depth(data, camera, stride), full[::stride, ::stride]
            assert sampled.shape == expected.shape
            assert np.isfinite(expected).sum() > 1000
            with np.errstate(invalid="ignore"):  # inf - inf
                close = np.abs(sampled - expected) <= 1e-5 * expected
            close |= sampled == expected
            # The others show what the full render shows within a pixel of their centre.
            far = np.where(np.isfinite(full), full, 1e3).astype(np.float32)
            kernel = np.ones((3, 3), np.uint8)
            lo, hi = (cv2.erode(far, kernel)[::stride, ::stride],
                      cv2.dilate(far, kernel)[::stride, ::stride])  # fmt: skip
            shown = np.where(np.isfinite(sampled), sampled, 1e3)
            assert np.all(close | ((shown >= lo - 1e-5) & (shown <= hi + 1e-5)))
            assert np.count_nonzero(~close) <= 1e-3 * close.size
        for a, b in zip(before, (model.cam_sensorsize, model.cam_intrinsic, model.cam_fovy)):
            np.testing.assert_array_equal(a, b)
    finally:
        rig.close()


def _prism_world(length: float, checker: tuple):
    """A world of one hexagonal prism (a mesh of 12 vertices, ``length`` m along x) on a
    textured floor (a 2 x 2 checker of colours ``checker``), seen from above by ``top``."""
    import mujoco

    spec = mujoco.MjSpec()
    spec.add_texture(name="floor_tex", type=mujoco.mjtTexture.mjTEXTURE_2D,
                     builtin=mujoco.mjtBuiltin.mjBUILTIN_CHECKER, width=64, height=64,
                     rgb1=list(checker[0]), rgb2=list(checker[1]))  # fmt: skip
    floor = spec.add_material(name="floor_mat", texrepeat=[2.0, 2.0])
    floor.textures[mujoco.mjtTextureRole.mjTEXROLE_RGB] = "floor_tex"
    spec.worldbody.add_geom(type=mujoco.mjtGeom.mjGEOM_PLANE, size=[1, 1, 0.1],
                            material="floor_mat")  # fmt: skip
    angles = np.arange(6) * np.pi / 3
    vertices = [[s * length / 2, 0.02 * np.cos(a), 0.02 + 0.02 * np.sin(a)]
                for s in (-1, 1) for a in angles]  # fmt: skip
    spec.add_mesh(name="prism", uservert=np.ravel(vertices).tolist())
    spec.worldbody.add_geom(type=mujoco.mjtGeom.mjGEOM_MESH, meshname="prism",
                            rgba=[0.8, 0.1, 0.1, 1])  # fmt: skip
    spec.worldbody.add_light(pos=[0, 0, 2], dir=[0, 0, -1], diffuse=[0.8, 0.8, 0.8])
    spec.worldbody.add_camera(name="top", pos=[0, 0, 0.6], fovy=60.0)
    model = spec.compile()
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    return model, data


def test_a_renderer_is_not_reused_for_other_meshes_or_textures_of_the_same_size():
    """Two worlds with as many mesh vertices, faces and texels, but another prism length and
    another floor colour: the second world's rig must draw its own prism and floor (before,
    the renderer made for the first was reused, and drew the first one's)."""
    model_a, data_a = _prism_world(0.2, ((0.9, 0.9, 0.9), (0.1, 0.1, 0.1)))
    model_b, data_b = _prism_world(0.4, ((0.1, 0.3, 0.9), (0.9, 0.8, 0.1)))
    assert (model_a.nmeshvert, model_a.ntexdata) == (model_b.nmeshvert, model_b.ntexdata)
    first = CameraRig(model_a, 160, 120)
    first.rgb(data_a, "top")
    first.depth(data_a, "top")
    first.close()
    second = CameraRig(model_b, 160, 120)
    try:
        depth, rgb = second.depth(data_b, "top"), second.rgb(data_b, "top")
    finally:
        second.close()
    # The truth from the model: the prism's top (3.7 cm high) spans its length along x.
    top = 0.6 - 0.02 * (1.0 + np.sin(np.pi / 3))  # the camera's height less the prism's
    on_prism = depth[60] < 0.59  # the image row through the prism's axis; the floor at 0.6
    seen_length = on_prism.sum() * top / second.intrinsics("top").fx
    assert abs(seen_length - 0.4) < 0.02, seen_length
    floor = rgb[5, 5].astype(int)  # a corner: the floor's checker, lit from above
    colours = np.array([[0.1, 0.3, 0.9], [0.9, 0.8, 0.1]])
    hue = floor / max(floor.max(), 1)
    assert min(np.abs(hue - c / c.max()).max() for c in colours) < 0.2, floor
