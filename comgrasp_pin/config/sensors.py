"""The sensors' part of the config tree, and its presets.

``sensor_preset("ideal")`` is the world the experiments have always run in,
``sensor_preset("realistic")`` one as hard as hardware (every number below with its source;
see docs/design.md, "Realistic sensing").

Re-exported by ``comgrasp_pin.config``; frozen dataclasses, SI units.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

from comgrasp_pin.config.depth_line import DepthLineErrorConfig
from comgrasp_pin.config.wrench import WrenchSensorConfig, wrench_preset
from comgrasp_pin.errors import InvalidInputError

TORQUE_KINDS = ("link", "current")


@dataclass(frozen=True)
class TorqueSensorConfig:
    """Error model of each joint's torque reading (N m).

    Attributes:
        kind: "link" (a torque sensor on the link side of the gear: Franka, KUKA iiwa; it
            sees the load, not the drive's friction) or "current" (the drive's current times
            its torque constant, UR CB3 style: the friction of gear and motor is in it).
        noise_std: standard deviation of the white noise on every sample (N m); 0.05 is a
            joint-torque-sensor class arm.
        bias: constant offset added to every sample (N m), the same for all joints.
        drift_std: random-walk drift, standard deviation after one second (N m / sqrt(s)).
        offset_std: each joint's offset, drawn once per episode (seeded) from N(0, std)
            (N m): a sensor zeroed at some other time and temperature.
        coulomb: Coulomb friction of each joint's drive (N m), current-based only. Moving,
            the reading is the load plus coulomb * sign(velocity); at rest the friction
            holds whatever it held when the joint stopped, so the reading keeps the sign of
            the last motion (hysteresis of width 2 * coulomb).
        viscous: viscous friction of each drive (N m s / rad), current-based only.
        moving_speed: a joint counts as moving above this speed (rad/s): below it the
            friction term keeps its sign.
    """

    kind: str = "link"
    noise_std: float = 0.05
    bias: float = 0.0
    drift_std: float = 0.0
    offset_std: float = 0.0
    coulomb: tuple[float, ...] = ()
    viscous: tuple[float, ...] = ()
    moving_speed: float = 0.01

    def __post_init__(self) -> None:
        if self.kind not in TORQUE_KINDS:
            raise InvalidInputError(f"kind must be one of {TORQUE_KINDS}, not {self.kind!r}")
        values = (self.noise_std, self.drift_std, self.offset_std, self.moving_speed)
        if not all(v >= 0 for v in (*values, *self.coulomb, *self.viscous)):
            raise InvalidInputError(
                "noise_std, drift_std, offset_std, moving_speed, coulomb and viscous must be "
                f">= 0, got {values}, {self.coulomb}, {self.viscous}"
            )


@dataclass(frozen=True)
class DepthNoiseConfig:
    """Error model of one RGBD camera's depth image (active stereo, RealSense class).

    All zero: the render as it is (``enabled`` is False).

    Attributes:
        focal_px, baseline: focal length (px) and stereo baseline (m) of the emulated
            sensor (not of the render): they set the axial noise.
        subpixel: the stereo matcher's disparity error (px RMS). The axial noise is then
            depth^2 * subpixel / (focal_px * baseline) RMS (m), per pixel.
        noise_corr_px: the noise is smoothed over this many render pixels (Gaussian sigma)
            and rescaled to the same RMS: stereo matching windows make it patchy.
        edge_jump: a depth step of this much within 3 x 3 pixels is an edge (m) ...
        edge_band_px: ... and this many pixels either side of it are the edge band, where
        edge_hole_prob: this share of the pixels is lost (depth 0: the matcher fails on the
            mixed window) and
        flying_prob: this share of the rest lies between the near and far sides (flying
            pixels, uniformly in between).
        dropout_prob: this share of all other pixels is lost at random (depth 0 or, for
            half of them, inf: no return).
        quantum: depth is given in steps of this (m).
        scale_std: the depth's scale error, drawn once per episode from N(0, std) (relative).
        extrinsic_shift: the camera's calibrated pose is off by this (m), in a random
            direction drawn once per episode ...
        extrinsic_turn_deg: ... and turned by this (deg) about a random axis.
    """

    focal_px: float = 0.0
    baseline: float = 0.05
    subpixel: float = 0.08
    noise_corr_px: float = 0.0
    edge_jump: float = 0.01
    edge_band_px: int = 1
    edge_hole_prob: float = 0.0
    flying_prob: float = 0.0
    dropout_prob: float = 0.0
    quantum: float = 0.0
    scale_std: float = 0.0
    extrinsic_shift: float = 0.0
    extrinsic_turn_deg: float = 0.0

    def __post_init__(self) -> None:
        shares = (self.edge_hole_prob, self.flying_prob, self.dropout_prob)
        if not all(0.0 <= p <= 1.0 for p in shares):
            raise InvalidInputError(f"edge_hole_prob, flying_prob and dropout_prob must lie "
                                    f"in [0, 1], got {shares}")  # fmt: skip
        if min(self.focal_px, self.baseline, self.quantum, self.scale_std) < 0:
            raise InvalidInputError("focal_px, baseline, quantum and scale_std must be >= 0")

    @property
    def enabled(self) -> bool:
        """Whether any error is applied (False: the render is used as it is)."""
        return self != DepthNoiseConfig()

    def axial_std(self, depth: float) -> float:
        """RMS axial noise (m) at ``depth`` (m); 0 without an emulated sensor."""
        if self.focal_px <= 0 or self.baseline <= 0:
            return 0.0
        return depth * depth * self.subpixel / (self.focal_px * self.baseline)


@dataclass(frozen=True)
class SensorConfig:
    """The robot's sensors, and what its description gets wrong.

    Attributes:
        preset: the preset this was built from ("ideal", "realistic", ...; ``sensor_preset``)
            or "custom"; recorded with the run.
        torque: the joint-torque sensor's error model.
        top_depth, side_depth: error models of the top-down and the wrist camera's depth.
        side_depth_line: what the wrist camera's depth line's change between two views is
            known to beyond its slices' scatter (``DepthLineErrorConfig``, the same for
            every preset: its camera term is ``side_depth``'s depth resolution).
        gripper_mass_error: the simulated gripper is this much heavier than the robot's model
            says (relative): the model's gravity torques are then off, a measured tau_before
            is not.
        gripper_com_error: and its CoM this far off the model's (m, along (1, 1, 1) / sqrt 3
            of the gripper's frame).
        watch_dt: period of the side camera while the rod is lifted and held (s).
        watch_stride: the slip watch measures every stride-th pixel of each row and column
            (it needs the tilt only).
        side_frames: frames of the wrist camera averaged in time for a side view while the
            arm holds still (``perception.frames.depth_frames.average_depth_frames``, per pixel the
            mean of the valid values near their median, as a RealSense's temporal filter
            does; each simulated frame has its own noise, holes and flying pixels, the
            calibration error is the episode's). Used only for a camera with errors (a clean
            render is the same every frame); the slip watch takes single frames. 1: no
            averaging. Measured on the 152 side views of 10 + 10 realistic obj3 and obj1
            grasps (seed 0): the side view's refusals were systematic (a flat bar is no
            cylinder; a stick hanging out of the image; jaws closed on nothing), not noise,
            and averaging 8 frames lowers the image's noise and with it the cylinder misfit
            allowed, so that obj1's refused views rose from 20 to 36 of 58 (obj3: 2 to 4 of
            94, its worst tilt 1.0 to 0.5 deg); at 25 ms a frame (render and noise) it would
            also cost 0.2 s a view. Hence 1.
        side_frames_tolerance: a frame's value this far from the pixel's median over the
            frames is left out of its mean (m): 5 mm, the side view's flying-pixel threshold
            (8 noise stds of the D435 at the held rod, 0.15-0.6 mm).
        wrench: the wrist force/torque sensor's error model (``config.wrench``).
    """

    preset: str = "ideal"
    torque: TorqueSensorConfig = field(default_factory=TorqueSensorConfig)
    top_depth: DepthNoiseConfig = field(default_factory=DepthNoiseConfig)
    side_depth: DepthNoiseConfig = field(default_factory=DepthNoiseConfig)
    side_depth_line: DepthLineErrorConfig = field(default_factory=DepthLineErrorConfig)
    gripper_mass_error: float = 0.0
    gripper_com_error: float = 0.0
    watch_dt: float = 0.2
    watch_stride: int = 3
    side_frames: int = 1
    side_frames_tolerance: float = 0.005
    wrench: WrenchSensorConfig = field(default_factory=WrenchSensorConfig)

    def __post_init__(self) -> None:
        frames = self.side_frames
        if isinstance(frames, bool) or not isinstance(frames, int) or frames < 1:
            raise InvalidInputError(f"side_frames must be an integer >= 1, got {frames!r}")
        if not self.side_frames_tolerance > 0:
            raise InvalidInputError(
                f"side_frames_tolerance must be > 0 (m), got {self.side_frames_tolerance!r}"
            )


# Intel RealSense D415 (top-down camera over the table, 1.25 m: the narrow-FOV model is the
# one for that range): 1280 px over 65 deg HFOV -> f = 640 / tan(32.5 deg) = 1005 px, baseline
# 55 mm; subpixel 0.08 (Intel, "Tuning depth cameras for best performance"): 1.5 mm RMS at
# 1 m, 2.3 mm at the table. D435 (wrist camera, 0.1-0.4 m): 848 px over 90 deg -> f = 424 px,
# baseline 50 mm: 0.9 mm at 0.5 m, 0.15-0.6 mm at the held rod. Both: 1 mm depth unit
# (RealSense's default), holes and flying pixels at depth edges, 1 % of pixels lost at random
# (dark and shiny spots), scale error 0.2 % (Intel's "< 2 % at 2 m" is the worst case; a
# calibrated unit does better), extrinsics off by 1 mm and 0.2 deg (a good hand-eye
# calibration's residual).
_REALSENSE = DepthNoiseConfig(
    subpixel=0.08,
    noise_corr_px=1.0,
    edge_jump=0.01,
    edge_band_px=1,
    edge_hole_prob=0.5,
    flying_prob=0.3,
    dropout_prob=0.01,
    quantum=0.001,
    scale_std=0.002,
    extrinsic_shift=0.001,
    extrinsic_turn_deg=0.2,
)
_D415 = replace(_REALSENSE, focal_px=1005.0, baseline=0.055)
_D435 = replace(_REALSENSE, focal_px=424.0, baseline=0.050)

# Link-side torque sensing (Franka / iiwa class): 0.05 N m white noise per sample (this
# project's default), offsets of 0.2 N m per joint between episodes (re-zeroing), drift
# 0.005 N m / sqrt(s) (temperature); friction does not reach a link-side sensor.
_LINK_TORQUE = TorqueSensorConfig(kind="link", noise_std=0.05, drift_std=0.005, offset_std=0.2)
# Current-based torque (UR CB3 style): friction is in the reading. Coulomb 3 N m on the big
# joints and 1 N m on the wrists, viscous 0.5-1 N m s / rad: the order of magnitude of a UR5's
# identified joint friction (Clochiatti et al., "Electro-mechanical modeling and
# identification of the UR5 e-series robot", Robotica 2024, fit Coulomb + viscous per joint to
# the controller's currents; our values are rounded assumptions, not theirs) and of UR's own
# +-5 N m tool-torque accuracy (DESIGN.md section 8). Noise 0.1 N m, offsets as above.
_CURRENT_TORQUE = TorqueSensorConfig(
    kind="current",
    noise_std=0.1,
    drift_std=0.005,
    offset_std=0.2,
    coulomb=(3.0, 3.0, 2.0, 1.0, 1.0, 1.0),
    viscous=(1.0, 1.0, 0.8, 0.5, 0.5, 0.5),
)


def _calibration_only(depth: DepthNoiseConfig) -> DepthNoiseConfig:
    return DepthNoiseConfig(scale_std=depth.scale_std, extrinsic_shift=depth.extrinsic_shift,
                            extrinsic_turn_deg=depth.extrinsic_turn_deg)  # fmt: skip


def _image_only(depth: DepthNoiseConfig) -> DepthNoiseConfig:
    return replace(depth, scale_std=0.0, extrinsic_shift=0.0, extrinsic_turn_deg=0.0)


_IDEAL_TORQUE = TorqueSensorConfig()
SOURCES = {
    "top_depth": lambda c: replace(c, top_depth=_image_only(_D415)),
    "wrist_depth": lambda c: replace(c, side_depth=_image_only(_D435)),
    "calibration": lambda c: replace(c, top_depth=_calibration_only(_D415),
                                     side_depth=_calibration_only(_D435)),
    "torque_offsets": lambda c: replace(c, torque=replace(_IDEAL_TORQUE, offset_std=0.2)),
    "torque_drift": lambda c: replace(c, torque=replace(_IDEAL_TORQUE, drift_std=0.005)),
    "friction": lambda c: replace(c, torque=replace(_CURRENT_TORQUE, noise_std=0.05,
                                                    offset_std=0.0, drift_std=0.0)),
    "gripper_model": lambda c: replace(c, gripper_mass_error=0.03, gripper_com_error=0.002),
}  # fmt: skip
"""Each error source of the realistic presets on its own, added to the ideal sensors by
``sensor_preset("ideal+NAME")``: the cameras' image errors (noise, holes, flying pixels,
dropouts, quantisation) apart from their calibration (pose and depth scale); the link-side
torque sensor's offsets and its drift; the current-based reading's friction (its white
noise kept at the ideal 0.05 N m); the gripper's model error."""

SENSOR_PRESETS = ("ideal", "realistic", "realistic_current", *(f"ideal+{s}" for s in SOURCES))


def sensor_preset(name: str) -> SensorConfig:
    """The sensors of a named preset.

    ``"ideal"``: today's defaults exactly (renders as they are, 0.05 N m white torque noise,
    the wrist sensor's white noise alone, the robot's model of its gripper exact).
    ``"realistic"``: RealSense-class depth (D415 above the table, D435 on the wrist),
    link-side torque sensors with offsets and drift, a Robotiq FT 300-S class wrist sensor
    with its offset and drift (``config.wrench``), and a gripper 3 % heavier than modelled
    with its CoM 2 mm off. ``"realistic_current"``: the same with a UR CB3-style
    current-based torque reading (friction, hysteresis).
    ``"ideal+SOURCE"``: the ideal sensors with one of the realistic presets' error sources
    (``SOURCES``), for a sensitivity study.
    """
    if name == "ideal":
        return SensorConfig()
    if name.startswith("ideal+") and name.removeprefix("ideal+") in SOURCES:
        return replace(SOURCES[name.removeprefix("ideal+")](SensorConfig()), preset=name)
    if name in ("realistic", "realistic_current"):
        torque = _LINK_TORQUE if name == "realistic" else _CURRENT_TORQUE
        return SensorConfig(name, torque, _D415, _D435, gripper_mass_error=0.03,
                            gripper_com_error=0.002, wrench=wrench_preset("ft300s"))  # fmt: skip
    raise InvalidInputError(f"unknown sensor preset {name!r}; presets are {SENSOR_PRESETS}")
