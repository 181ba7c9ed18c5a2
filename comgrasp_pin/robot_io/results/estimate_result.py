"""One payload estimate, whatever it came from: ``PayloadEstimate`` and its optional parts.

Every estimate mode (the joint torques or a wrist sensor's wrench, at rest or along a motion,
or both sources at once) returns a ``PayloadEstimate``: the mass and CoM (ee frame) with
their covariance, the verdict with its reasons (``trust``), each source's share of the
information, and a part for what only some modes have:

- ``at_rest``: the still windows or poses, the static fit (``AtRest``);
- ``motion``: the motion's samples, its fit, held-out validation and halves (``Motion``);
- ``inertia``: the inertia a motion identified, with its own verdict (``Inertia``);
- ``joint_torques``: what the joint torques' side found (``JointTorques``);
- ``wrench``: what the wrist sensor's side found (``Wrench``).

A part is None where the mode does not have it. Frames: the CoM and the inertia are in the ee
frame ``frame`` (the sensor's own numbers in its frame); SI units throughout.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from comgrasp_pin.estimation import ComEstimate
from comgrasp_pin.estimation.dynamic_uncertainty import Validation
from comgrasp_pin.estimation.side_friction import SideFriction
from comgrasp_pin.estimation.trust import t95
from comgrasp_pin.estimation.wrench import StaticWrenchFit

JOINT_TORQUES, WRENCH, PRIOR = "joint_torques", "wrench", "prior"
"""The sources' names, as ``PayloadEstimate.sources`` keys them."""
TOOL_EMPTY_RUN, TOOL_GIVEN = "empty run (the tool's parameters fitted)", "given"
TOOL_NOMINAL = "URDF links beyond the sensor (nominal)"
"""Where the tool's own wrench came from (``Wrench.tool``), along a motion or at rest."""


def sole_source(name: str, motion: bool = False) -> dict:
    """``PayloadEstimate.sources`` where ``name`` gave all the information."""
    shares = {"mass_kg": 1.0, "com_m": [1.0, 1.0, 1.0]}
    if motion:
        shares["principal_moments_kgm2"] = [1.0, 1.0, 1.0]
    return {name: shares}


@dataclass(frozen=True)
class AtRest:
    """What an estimate from readings at rest used and found.

    Attributes:
        q: (k, n) the poses (rad): the after windows' (pairs) or each window's mean.
        windows: the still windows (s from the log's start): {"before": [[t0, t1, n]...],
            "after": [...]} for pairs, {"still": [[t0, t1], ...]} for one log at rest.
        method: "lstsq" or "ipopt"; solver_status: the solver's word.
        condition_number: of the stacked regressor (None where not computed).
        fit: the estimator's own result where it is a ``ComEstimate`` (residuals, singular
            values), else None.
    """

    q: np.ndarray
    windows: dict
    method: str = "lstsq"
    solver_status: str = "closed_form"
    condition_number: float | None = None
    fit: ComEstimate | None = None

    @property
    def n_poses(self) -> int:
        """The number of poses (orientations)."""
        return len(self.q)


@dataclass(frozen=True)
class Motion:
    """What an estimate from a motion used and found.

    Attributes:
        n_samples, duration_s: samples fitted and the motion's length (s).
        cutoff_hz: the zero-phase filter's cutoff; velocity_from: "log" or "positions".
        solver_status: IPOPT's, or "not run: ..." where no payload was seen.
        condition_number: of the regressor along the motion (rows in noise units, columns
            scaled by a 1 kg payload 0.1 m out).
        t: (k,) the fitted samples' times (s from the log's start).
        validation: each fifth of the motion predicted from the rest (every row).
        halves_mass: (m1, m2) kg, each half of the motion alone.
        second_log: the payload predicting a second log of the same payload, or None.
        pipeline_bias: (10,) what the filters and derivatives add to the payload's
            parameters on this motion (``payload_system.pipeline_bias``; carried in the
            covariance, not subtracted), or None where not measured (a wrench's rows).
    """

    n_samples: int
    duration_s: float
    cutoff_hz: float
    velocity_from: str
    solver_status: str
    condition_number: float
    t: np.ndarray
    validation: Validation
    halves_mass: tuple[float, float]
    second_log: Validation | None = None
    pipeline_bias: np.ndarray | None = None


@dataclass(frozen=True)
class Inertia:
    """The inertia a motion identified, with its own verdict.

    Attributes:
        inertia_com_ee: (3, 3) about the CoM, ee axes (kg m^2).
        inertia_cov: (9, 9) its covariance, flattened row-major; inertia_std: (3, 3).
        params: (10,) m, m c, I at the ee origin (Pinocchio's order); params_cov: (10, 10).
        unconstrained_params: (10,) the plain least squares' (maybe not a body).
        verdict: ``identified`` where every principal moment is determined (``trust``),
            else ``not determined``; reasons: why not.
        dof: the degrees of freedom of the inertia's variance (the fewest of its six
            entries'), inf where it is known rather than estimated; params_dof: (10,) each
            parameter's.
    """

    inertia_com_ee: np.ndarray
    inertia_cov: np.ndarray
    inertia_std: np.ndarray
    params: np.ndarray
    params_cov: np.ndarray
    unconstrained_params: np.ndarray
    verdict: str
    reasons: tuple[str, ...] = ()
    dof: float = np.inf
    params_dof: np.ndarray = field(default_factory=lambda: np.full(10, np.inf))

    @property
    def t95(self) -> float:
        """The 95 % quantile a principal moment's std is multiplied by (``trust.t95``)."""
        return t95(self.dof)


@dataclass(frozen=True)
class JointTorques:
    """The joint torques' side of an estimate (N m, or currents turned into N m by gains).

    Attributes:
        torque_std: (n,) the noise that weighs their rows: one averaged reading at rest,
            one sample (white) along a motion.
        noise_from: how ``torque_std`` was set ("given", "samples", "residuals").
        arm_model: where the arm's own torques came from along a motion (an empty run, an
            identified arm model, the URDF's model), or None at rest (the empty windows).
        gains_source: the drive gains the currents were turned into torques with, or None.
        gains_cov: (4, 4) the part of the (mass, CoM) covariance from the gains, or None.
        drift_std: the torque sensor's drift taken in (N m / sqrt(s); 0: none).
        tau_before, tau_after: (k, n) at rest: the empty arm's torques carried to the poses
            and the holding ones; None along a motion.
        side_friction: at rest, poses read from both sides: their stuck friction and the
            share their mean left (``estimation.side_friction.SideFriction``), or None.
        offsets, offset_drift: (n,) along a motion: the efforts' offsets (mean) and their
            change from start to end; friction: (n, 2) viscous (N m s/rad) and Coulomb
            (N m) with the URDF's model, else None.
        residual_rms: (n,) per joint; delay_s: the efforts' delay behind the positions
            found (s), None where an empty run cancels it.
        alignment: the empty run's alignment (``Alignment.as_dict``), or None.
        tau_payload, tau_payload_fit: (k, n) the payload's torques measured and fitted.
        note: why the empty run did not serve them, or None.
    """

    torque_std: np.ndarray
    noise_from: str = "residuals"
    arm_model: str | None = None
    gains_source: str | None = None
    gains_cov: np.ndarray | None = None
    drift_std: float = 0.0
    tau_before: np.ndarray | None = None
    tau_after: np.ndarray | None = None
    side_friction: SideFriction | None = None
    offsets: np.ndarray | None = None
    offset_drift: np.ndarray | None = None
    friction: np.ndarray | None = None
    residual_rms: np.ndarray | None = None
    delay_s: float | None = None
    alignment: dict | None = None
    tau_payload: np.ndarray | None = None
    tau_payload_fit: np.ndarray | None = None
    note: str | None = None


@dataclass(frozen=True)
class Wrench:
    """The wrist sensor's side of an estimate (force N, torque N m, in ``sensor_frame``).

    Attributes:
        sensor_frame: the URDF frame the wrench is measured in.
        sensor_bias, sensor_bias_std: (6,) the sensor's offsets and their std (at rest, or
            their mean over a motion), None where pairs cancel them.
        sensor_bias_drift: (6,) their change over a motion, or None.
        com_sensor: (3,) the CoM in the sensor frame (at rest), or None.
        tool: where the tool's own wrench came from ("URDF links beyond the sensor
            (nominal)", "empty run ...", "given", "the tool identified before", "none").
        tool_params: (10,) the tool's parameters subtracted (ee frame) along a motion;
            tool_cov: (10, 10); at rest ``tool_mass`` (kg) and ``tool_com_sensor`` (m).
        noise_from: how each window's noise was set (at rest).
        residual_rms: (6,) per axis, or (2,) force and torque RMS at rest (N, N m).
        wrench_std: (6,) the noise per axis that weighs the rows along a motion.
        delay_s: the wrench's delay behind the positions (s), or None.
        fit: the fit at rest in the sensor frame (``StaticWrenchFit``), or None.
        wrench_payload, wrench_payload_fit: (k, 6) the payload's wrench along a motion.
        agreement: the two sources alone compared, or None; alone_refused: {source: why it
            alone does not determine the payload, or None}.
    """

    sensor_frame: str
    sensor_bias: np.ndarray | None = None
    sensor_bias_std: np.ndarray | None = None
    sensor_bias_drift: np.ndarray | None = None
    com_sensor: np.ndarray | None = None
    tool: str = "none"
    tool_params: np.ndarray | None = None
    tool_cov: np.ndarray | None = None
    tool_mass: float = 0.0
    tool_com_sensor: np.ndarray | None = None
    noise_from: str | None = None
    residual_rms: np.ndarray | None = None
    wrench_std: np.ndarray | None = None
    delay_s: float | None = None
    fit: StaticWrenchFit | None = None
    wrench_payload: np.ndarray | None = None
    wrench_payload_fit: np.ndarray | None = None
    agreement: dict | None = None
    alone_refused: dict = field(default_factory=dict)


@dataclass(frozen=True)
class PayloadEstimate:
    """A payload estimate from any source (ee frame, SI units).

    Attributes:
        mass: kg.
        com_ee: (3,) CoM in the ee frame ``frame`` (m); NaN where nothing held determines it.
        cov: (4, 4) covariance of (mass, com_ee) from every modelled error source, or None
            where no uncertainty could be formed (as many readings as unknowns).
        frame: the ee frame's name.
        verdict: ``identified``, ``nothing held`` or ``unreliable`` (``trust``); reasons: one
            line each, saying what would help.
        sources: {source: {quantity: share}}: each source's share of the information
            ("joint_torques", "wrench", "prior"); the shares of a quantity sum to 1 over the
            sources. Quantities: "mass_kg" always; "com_m" (3) and, from a motion,
            "principal_moments_kgm2" (3); before/after pairs "first_moment_kgm" (3, m c).
        std_parts: the mass's std (kg) from each error source, where more than one was
            modelled ({"data and model (block sandwich)": ..., "gains": ...}), else {}.
        unobservable_ee: (3,) the direction the CoM was not seen along (one pose), or None.
        at_rest, motion, inertia, joint_torques, wrench: the parts (module docstring).
        dof: (4,) the degrees of freedom of the variances of (mass, com_ee): few where they
            were estimated from a motion's blocks, inf where the variance is known or came
            from many readings; the 95 % intervals take Student's t of them (``t95``).
    """

    mass: float
    com_ee: np.ndarray
    cov: np.ndarray | None
    frame: str
    verdict: str
    reasons: tuple[str, ...]
    sources: dict
    std_parts: dict = field(default_factory=dict)
    unobservable_ee: np.ndarray | None = None
    at_rest: AtRest | None = None
    motion: Motion | None = None
    inertia: Inertia | None = None
    joint_torques: JointTorques | None = None
    wrench: Wrench | None = None
    dof: np.ndarray = field(default_factory=lambda: np.full(4, np.inf))

    @property
    def std(self) -> np.ndarray | None:
        """(4,) standard deviations of (mass, com_ee) (kg, m), or None."""
        if self.cov is None:
            return None
        return np.sqrt(np.clip(np.diag(self.cov), 0, None))

    @property
    def t95(self) -> np.ndarray:
        """(4,) the 95 % quantiles of (mass, com_ee): Student's t of ``dof``."""
        return np.atleast_1d(t95(self.dof))

    @property
    def interval95_halfwidth(self) -> np.ndarray | None:
        """(4,) the 95 % intervals' half-widths of (mass, com_ee) (kg, m), or None."""
        std = self.std
        return None if std is None else self.t95 * std

    @property
    def interval95_mass(self) -> tuple[float, float] | None:
        """The mass's 95 % interval (kg), or None without a covariance."""
        half = self.interval95_halfwidth
        if half is None:
            return None
        return self.mass - float(half[0]), self.mass + float(half[0])

    @property
    def mode(self) -> str:
        """What it came from, in words: "a motion's wrench and joint torques", ..."""
        names = " and ".join(n.replace("_", " ") for n in self.sources if n != PRIOR)
        return f"{names} at rest" if self.motion is None else f"a motion's {names}"
