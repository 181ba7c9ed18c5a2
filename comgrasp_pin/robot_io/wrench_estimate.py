"""What ``estimate_wrench_dynamic`` returns: the payload, the sensor's bias, each source's share."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from comgrasp_pin.robot_io import dynamic_uncertainty as du


@dataclass(frozen=True)
class JointTorquePart:
    """The joint torques' own unknowns where they were fitted with the wrench (N m, SI).

    Attributes:
        arm_model: where the arm's own torques came from (``payload_system``'s sources).
        torque_std: (n,) the noise per joint that weighs their rows (white).
        offsets: (n,) the efforts' offsets (mean over the motion); offset_drift: (n,) their
            change from the motion's start to its end.
        friction: (n, 2) viscous (N m s/rad) and Coulomb (N m) with the URDF's model, or None.
        residual_rms: (n,) per joint.
        delay_s: the efforts' delay behind the positions, or None with an empty run.
        alignment: the empty run's alignment (``Alignment.as_dict``), or None.
        tau_payload, tau_payload_fit: (k, n) the payload's torques measured and fitted.
        note: why the empty run did not serve the joint torques, or None.
    """

    arm_model: str
    torque_std: np.ndarray
    offsets: np.ndarray
    offset_drift: np.ndarray
    friction: np.ndarray | None
    residual_rms: np.ndarray
    delay_s: float | None
    alignment: dict | None
    tau_payload: np.ndarray
    tau_payload_fit: np.ndarray
    note: str | None


@dataclass(frozen=True)
class WrenchDynamicEstimate:
    """A payload identified from a motion's wrench (ee frame, SI units).

    The payload's fields are those of ``dynamic.DynamicEstimate`` with the same meaning.

    Attributes:
        mass: kg.
        com_ee: (3,) CoM (m).
        inertia_com_ee: (3, 3) inertia about the CoM, ee axes (kg m^2).
        params: (10,) m, m c, I at the ee origin (Pinocchio's order).
        params_cov: (10, 10) their covariance: the data and the model (block jackknife), the
            tool's parameters, the arm model's (joint torques with ``arm_model``).
        cov: (4, 4) covariance of (mass, com_ee).
        inertia_std: (3, 3) std of each entry of ``inertia_com_ee``.
        inertia_cov: (9, 9) covariance of ``inertia_com_ee`` flattened row-major.
        condition_number: of the stacked regressor, rows in noise units, columns scaled by a
            1 kg payload 0.1 m out (``payload_regressor.parameter_scale``).
        sensor_frame: the URDF frame of the wrench.
        sensor_bias: (6,) the sensor's offsets, force (N) and torque (N m), sensor frame,
            their mean over the motion; sensor_bias_std: (6,) their std (noise, the
            jackknife, the tool); sensor_bias_drift: (6,) their change over the motion.
        delay_s: the wrench's delay behind the positions found (s).
        wrench_std: (6,) the noise per axis that weighs the wrench's rows (white; N, N m).
        residual_rms_wrench: (6,) per axis (N, N m).
        tool: where the tool's parameters came from (``wrench_dynamic.TOOL_*``).
        tool_params: (10,) the tool's parameters subtracted (ee frame); tool_cov: (10, 10).
        contributions: {source: {"mass_kg": share, "com_m": [3 shares],
            "principal_moments_kgm2": [3 shares]}}: each source's share of the information
            (``wrench_combined.contributions``); the shares of a quantity sum to 1.
        agreement: the two sources alone compared (``wrench_combined.agreement``), or None.
        alone_refused: {source: why it alone does not determine the payload, or None}.
        joint_torques: the joint torques' own unknowns, or None where not used.
        n_samples, duration_s: samples fitted and the motion's length (s).
        cutoff_hz: the filter's cutoff; velocity_from: "log" or "positions".
        solver_status: IPOPT's, or "not run: ..." where no payload was seen.
        unconstrained_params: (10,) the plain least squares' parameters.
        t: (k,) the fitted samples' times (s from the log's start).
        wrench_payload: (k, 6) the payload's wrench as measured (tool, bias, drift removed);
            wrench_payload_fit: (k, 6) the fitted payload's.
        std_parts: the mass's std (kg) from each source of error.
        validation: the held-out prediction over every row (``dynamic_uncertainty``).
        verdict: "identified" or "unreliable"; reasons: why, one line each.
        halves_mass: (m1, m2) kg, each half of the motion alone.
    """

    mass: float
    com_ee: np.ndarray
    inertia_com_ee: np.ndarray
    params: np.ndarray
    params_cov: np.ndarray
    cov: np.ndarray
    inertia_std: np.ndarray
    inertia_cov: np.ndarray
    condition_number: float
    sensor_frame: str
    sensor_bias: np.ndarray
    sensor_bias_std: np.ndarray
    sensor_bias_drift: np.ndarray
    delay_s: float
    wrench_std: np.ndarray
    residual_rms_wrench: np.ndarray
    tool: str
    tool_params: np.ndarray
    tool_cov: np.ndarray
    contributions: dict
    agreement: dict | None
    alone_refused: dict
    joint_torques: JointTorquePart | None
    n_samples: int
    duration_s: float
    cutoff_hz: float
    velocity_from: str
    solver_status: str
    unconstrained_params: np.ndarray
    t: np.ndarray
    wrench_payload: np.ndarray
    wrench_payload_fit: np.ndarray
    std_parts: dict
    validation: du.Validation
    verdict: str
    reasons: tuple[str, ...]
    halves_mass: tuple[float, float]
