"""Rendering the world's RGBD cameras, headless (``MUJOCO_GL=egl``).

This is the one place where MuJoCo's camera frame (x right, y up, looking along -z) is
converted to the optical frame used by all perception code (x right, y down, z forward).
"""

from __future__ import annotations

import hashlib
from contextlib import contextmanager

import mujoco
import numpy as np

from comgrasp_pin.camera import PinholeCamera
from comgrasp_pin.errors import ComGraspError
from comgrasp_pin.simulation.depth_noise import DepthNoise

# R_mujococam_optical: flip y and z.
_R_MJ_OPTICAL = np.diag([1.0, -1.0, -1.0])


# Renderers not in use, by image size, multisampling and the model's rendering assets.
# Building one costs 0.2-0.3 s (uploading the robot's meshes to OpenGL), as much as a whole
# accuracy trial's physics; the worlds of an experiment differ only in their rod (built from
# primitives, not assets), so a process re-points a finished world's renderer at the next one.
# A renderer keeps what its OpenGL context was made with (meshes, textures, height fields,
# skins, the shadow map and the primitives' resolution): the key is a digest of their content,
# not only their counts (two hexagonal rods of one vertex count but other lengths would be
# drawn with the first one's mesh).
_IDLE_RENDERERS: dict[tuple, list[mujoco.Renderer]] = {}

# The MjModel arrays and visual settings that mujoco.Renderer uploads when it is made.
_ASSET_ARRAYS = (
    "mesh_vert", "mesh_normal", "mesh_face", "mesh_facenormal", "mesh_texcoord",
    "mesh_facetexcoord", "mesh_graph", "tex_type", "tex_height", "tex_width", "tex_nchannel",
    "tex_colorspace", "tex_data", "hfield_size", "hfield_nrow", "hfield_ncol", "hfield_data",
    "skin_face", "skin_texcoord", "flex_elem", "flex_texcoord",
)  # fmt: skip

# Depth is drawn without multisampling: the depth a multisampled buffer resolves to is the
# same to the bit (Mesa llvmpipe; tests/test_cameras.py), and reading it back is about half
# a render's time (14 -> 7 ms a 640 x 480 frame). Colour keeps the model's antialiasing.
DEPTH_SAMPLES = 0


def assets_digest(model: mujoco.MjModel) -> str:
    """A digest of what a renderer made for ``model`` keeps: its rendering assets' content
    and the visual settings read when the OpenGL context is made (about 1 ms for the
    robot's world)."""
    digest = hashlib.blake2b(digest_size=16)
    for name in _ASSET_ARRAYS:
        array = getattr(model, name, None)
        if array is not None:
            digest.update(name.encode())
            digest.update(np.ascontiguousarray(array).tobytes())
    q, g = model.vis.quality, model.vis.global_
    digest.update(np.array([q.shadowsize, q.numslices, q.numstacks, q.numquads, g.offwidth,
                            g.offheight]).tobytes())  # fmt: skip
    return digest.hexdigest()


def _assets_key(
    model: mujoco.MjModel,
    width: int,
    height: int,
    samples: int | None = None,
    digest: str | None = None,
) -> tuple:
    """The pool's key: image size, samples per pixel and ``assets_digest`` (given, or
    computed)."""
    samples = int(model.vis.quality.offsamples) if samples is None else samples
    return (width, height, samples, digest or assets_digest(model))


def _take_renderer(
    model: mujoco.MjModel,
    width: int,
    height: int,
    samples: int | None = None,
    digest: str | None = None,
) -> mujoco.Renderer:
    """A renderer for ``model`` drawing with ``samples`` per pixel (None: the model's): an
    idle one made for the same assets (``digest``: ``assets_digest(model)``, computed when
    None), re-pointed at it (its OpenGL context stays, and its scene, whose buffers depend
    on the model only through its flexes and skins: making one of 10000 geoms takes 30 ms),
    or a new one."""
    idle = _IDLE_RENDERERS.get(_assets_key(model, width, height, samples, digest))
    if idle:
        renderer = idle.pop()
        renderer._model = model  # the attributes mujoco.Renderer renders the model from
        if model.nflex or model.nskin:  # the only parts of a scene made for its model
            renderer._scene = mujoco.MjvScene(model, maxgeom=renderer._scene.maxgeom)
        return renderer
    model_samples = int(model.vis.quality.offsamples)
    if samples is not None:  # read when the OpenGL context is made, not when drawing
        model.vis.quality.offsamples = samples
    try:
        renderer = mujoco.Renderer(model, height, width)
    finally:
        model.vis.quality.offsamples = model_samples
    renderer.samples = model_samples if samples is None else samples
    return renderer


class CameraRig:
    """Renders RGB, metric depth and ground-truth segmentation of the model's cameras.

    Up to two offscreen renderers per rig, made when first needed: depth without
    multisampling, colour and segmentation with the model's; handed back by ``close`` for
    the next rig of a model with the same assets (``assets_digest``; tests/test_cameras.py
    checks that the images are the same).

    Attributes:
        noise: the depth errors of each camera, by name (``DepthNoise``; none: the renders
            as they are). ``depth`` applies them; ``calibration_error`` gives the pose error.
        shadows: cast the lights' shadows in colour images (off: a software renderer draws
            a frame about four times faster, as a video needs). Depth never draws them: it
            does not depend on them, to the bit, and a software renderer's shadow pass
            (the sun's 4096² map) is most of a depth frame's time (tests/test_cameras.py).
    """

    def __init__(
        self,
        model: mujoco.MjModel,
        width: int = 640,
        height: int = 480,
        noise: dict[str, DepthNoise] | None = None,
        shadows: bool = True,
    ):
        self.model = model
        self.width = width
        self.height = height
        self.noise = dict(noise or {})
        self.shadows = shadows
        self._renderers: dict[bool, mujoco.Renderer] = {}  # by depth (True) or not
        self._closed = False
        self._digest: str | None = None  # assets_digest(model), when first needed

    def _assets_digest(self) -> str:
        if self._digest is None:
            self._digest = assets_digest(self.model)
        return self._digest

    def close(self) -> None:
        """Hand the renderers back for reuse; the rig must not render afterwards."""
        for renderer in self._renderers.values():
            key = _assets_key(self.model, self.width, self.height, renderer.samples,
                              self._assets_digest())  # fmt: skip
            _IDLE_RENDERERS.setdefault(key, []).append(renderer)
        self._renderers.clear()
        self._closed = True

    def _renderer(self, depth: bool) -> mujoco.Renderer:
        """The rig's renderer for depth (no multisampling) or for colour and segmentation."""
        if self._closed:
            raise ComGraspError("the camera rig was closed: it renders no more")
        if depth not in self._renderers:
            samples = DEPTH_SAMPLES if depth else None
            self._renderers[depth] = _take_renderer(self.model, self.width, self.height, samples,
                                                    self._assets_digest())  # fmt: skip
        return self._renderers[depth]

    def intrinsics(self, camera: str) -> PinholeCamera:
        """Pinhole intrinsics of ``camera`` at the rig's image size."""
        fovy = float(self.model.camera(camera).fovy[0])
        return PinholeCamera.from_fovy(self.width, self.height, fovy)

    def T_world_cam(self, data: mujoco.MjData, camera: str) -> np.ndarray:
        """(4, 4) pose of the camera's optical frame in the world."""
        cam = self.model.camera(camera).id
        T = np.eye(4)
        T[:3, :3] = data.cam_xmat[cam].reshape(3, 3) @ _R_MJ_OPTICAL
        T[:3, 3] = data.cam_xpos[cam]
        return T

    def _render(
        self, data: mujoco.MjData, camera: str, depth=False, segmentation=False, stride: int = 1
    ):
        r = self._renderer(depth)
        r.disable_depth_rendering()
        r.disable_segmentation_rendering()
        if depth:
            r.enable_depth_rendering()
        if segmentation:
            r.enable_segmentation_rendering()
        shadows = self.shadows and not depth  # depth does not show them
        if stride == 1:
            r.update_scene(data, camera)
            image = self._draw(r, shadows)
        else:  # the scene's camera keeps the frustum update_scene gives it
            with sampling_every(self.model, camera, self.intrinsics(camera), stride) as sampled:
                r.update_scene(data, camera)
            with _viewport(r, sampled.width, sampled.height):
                image = self._draw(r, shadows)
        r.disable_depth_rendering()
        r.disable_segmentation_rendering()
        return image

    def _draw(self, r: mujoco.Renderer, shadows: bool) -> np.ndarray:
        r.scene.flags[mujoco.mjtRndFlag.mjRND_SHADOW] = shadows  # renderers are shared
        return r.render()  # a new array each call

    def rgb(self, data: mujoco.MjData, camera: str) -> np.ndarray:
        """(H, W, 3) uint8 RGB image."""
        return self._render(data, camera)

    def depth(self, data: mujoco.MjData, camera: str, stride: int = 1) -> np.ndarray:
        """(H, W) float z-depth along the optical axis (m); ``inf`` where nothing is seen,
        and, with the camera's ``noise``, 0 or inf where the sensor lost the pixel.
        ``stride`` > 1: every stride-th pixel of each row and column of that image, and only
        they are rendered (``sampling_every``) and given the camera's errors
        (``DepthNoise.apply``)."""
        rendered = self._render(data, camera, depth=True, stride=stride)  # float32
        noise = self.noise.get(camera)
        depth = rendered.astype(float)
        depth[depth >= self.model.vis.map.zfar * self.model.stat.extent * 0.999] = np.inf
        return depth if noise is None else noise.apply(depth, stride)

    def calibration_error(self, camera: str) -> np.ndarray:
        """(4, 4) T_cam_calibrated: the camera frame the robot's calibration gives, in the
        true one (identity without ``noise``)."""
        noise = self.noise.get(camera)
        return np.eye(4) if noise is None else noise.T_cam_calibrated.copy()

    def segmentation(self, data: mujoco.MjData, camera: str) -> np.ndarray:
        """(H, W) int geom id per pixel, -1 for background (ground truth: tests only)."""
        seg = self._render(data, camera, segmentation=True)
        ids = seg[:, :, 0].astype(int)
        ids[seg[:, :, 1] != int(mujoco.mjtObj.mjOBJ_GEOM)] = -1
        return ids


@contextmanager
def sampling_every(model: mujoco.MjModel, camera: str, image: PinholeCamera, stride: int):
    """``camera`` set up, inside the block, to image every ``stride``-th pixel of each row
    and column of ``image`` (its intrinsics at the full size), each at that pixel's centre;
    the block gets the sampled pixels' camera (``image.subsampled(stride)``).

    MuJoCo's intrinsic camera (``cam_sensorsize``, ``cam_intrinsic``: focal lengths and the
    principal point's offset from the sensor's centre, here in the full image's pixels): the
    sensor spans the sampled pixels' own pixels, ``stride`` full pixels each, its first one
    centred on the full image's first. A render of ``-(-width // stride)`` by ``-(-height //
    stride)`` pixels then holds ``full[::stride, ::stride]``, up to the float rounding of
    another projection (tests/test_cameras.py measures it). The model's camera is restored
    on leaving.
    """
    cam = model.camera(camera).id
    kept = (model.cam_sensorsize[cam].copy(), model.cam_intrinsic[cam].copy(),
            model.cam_resolution[cam].copy())  # fmt: skip
    sampled = image.subsampled(stride)
    # The sampled sensor's left (top) edge lies half a sampled pixel before the first centre.
    left, top = 0.5 - stride / 2, 0.5 - stride / 2
    shift_x = left + stride * sampled.width / 2 - image.width / 2
    shift_y = top + stride * sampled.height / 2 - image.height / 2
    try:
        model.cam_sensorsize[cam] = [stride * sampled.width, stride * sampled.height]
        model.cam_intrinsic[cam] = [image.fx, image.fy, shift_x, shift_y]
        model.cam_resolution[cam] = [sampled.width, sampled.height]
        yield sampled
    finally:
        model.cam_sensorsize[cam], model.cam_intrinsic[cam], model.cam_resolution[cam] = kept


@contextmanager
def _viewport(renderer: mujoco.Renderer, width: int, height: int):
    """``renderer`` drawing and reading, inside the block, the ``width`` by ``height``
    corner of its framebuffer (a smaller image than it was made for; the attributes
    ``mujoco.Renderer.render`` sizes its viewport and its array from). A renderer of its
    own would hold another framebuffer, about 150 MB on a software OpenGL."""
    kept = renderer._width, renderer._height, renderer._rect
    try:
        renderer._width, renderer._height = width, height
        renderer._rect = mujoco.MjrRect(0, 0, width, height)
        yield
    finally:
        renderer._width, renderer._height, renderer._rect = kept
