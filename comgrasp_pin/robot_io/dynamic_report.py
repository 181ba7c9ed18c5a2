"""A motion's payload estimate as RESULT.json (DESIGN.md 4c, 4d) and as a few lines for a person."""

from __future__ import annotations

import numpy as np

from comgrasp_pin.estimation.payload_regressor import PARAMETER_NAMES
from comgrasp_pin.robot_io.dynamic import EMPTY_RUN, NOMINAL, DynamicEstimate
from comgrasp_pin.robot_io.verdict import Z95


def payload_fields(est, frame: str, covers: str) -> dict:
    """RESULT.json's fields of any motion's payload estimate (4b, 4c), SI units.

    ``est``: a ``DynamicEstimate`` or a ``wrench_estimate.WrenchDynamicEstimate``;
    ``covers``: the error sources its std covers, in words.
    """
    std = np.sqrt(np.clip(np.diag(est.cov), 0, None))
    return {
        "mass_kg": est.mass,
        "com_m": est.com_ee.tolist(),
        "frame": frame,
        "cov": est.cov.tolist(),
        "unobservable": None,
        "n_poses": None,
        "std": {"mass_kg": float(std[0]), "com_m": std[1:].tolist(), "covers": covers,
                "mass_kg_by_source": est.std_parts},
        "interval95_mass_kg": [est.mass - Z95 * float(std[0]), est.mass + Z95 * float(std[0])],
        "verdict": est.verdict,
        "reasons": list(est.reasons),
        "halves_mass_kg": list(est.halves_mass),
        "inertia_kgm2": est.inertia_com_ee.tolist(),
        "inertia_std_kgm2": est.inertia_std.tolist(),
        "inertia_about": "the CoM, axes of frame",
        "params": dict(zip(PARAMETER_NAMES, est.params.tolist(), strict=True)),
        "params_cov": est.params_cov.tolist(),
        "params_about": "m (kg), m c (kg m), inertia at the frame's origin (kg m^2)",
        "unconstrained_params": est.unconstrained_params.tolist(),
        "condition_number": est.condition_number,
        "method": "dynamic",
        "n_samples": est.n_samples,
        "duration_s": est.duration_s,
        "cutoff_hz": est.cutoff_hz,
        "velocity_from": est.velocity_from,
        "solver_status": est.solver_status,
    }  # fmt: skip


def dynamic_result_dict(est: DynamicEstimate, frame: str) -> dict:
    """RESULT.json: the fields of the static estimate's (4b) plus the inertia (4c), SI units."""
    covers = "noise and the model's error (block jackknife), the drive gains, the arm model"
    return {
        **payload_fields(est, frame, covers),
        "residual_rms_Nm": est.residual_rms.tolist(),
        "validation": est.validation.as_dict(),
        "validation_log": None if est.second_log is None else {
            "rms_Nm": est.second_log.rms_Nm.tolist(),
            "explained": est.second_log.explained.tolist(),
            "explained_total": est.second_log.explained_total,
        },
        "alignment": est.alignment,
        "gains": est.gains_source,
        "effort_delay_s": est.delay_s,
        "arm_model": est.arm_model,
        "offsets_Nm": est.offsets.tolist(),
        "friction": None if est.friction is None else {
            "viscous_Nms_per_rad": est.friction[:, 0].tolist(),
            "coulomb_Nm": est.friction[:, 1].tolist(),
        },
        "torque_std_Nm": est.torque_std.tolist(),
    }  # fmt: skip


def mass_lines(est, std: np.ndarray) -> list[str]:
    """The summary's mass with its std and 95 % interval, and the std by source."""
    return [
        f"  mass  {est.mass:.4f} +- {std[0]:.4f} kg (std; 95 %: {est.mass - Z95 * std[0]:.3f} "
        f"to {est.mass + Z95 * std[0]:.3f} kg)",
        "        std by source: " + ", ".join(f"{k} {v:.4f}" for k, v in est.std_parts.items()),
    ]


def moment_lines(est, frame: str) -> list[str]:
    """The summary's principal moments about the CoM with their std and axes."""
    moments, axes = np.linalg.eigh(est.inertia_com_ee)
    lines = ["  principal moments of inertia about the CoM (kg m^2), axes in " + frame + ":"]
    for value, u in zip(moments, axes.T):
        # std of each principal moment: the inertia's covariance projected on u u^T
        s = float(np.sqrt(max(np.kron(u, u) @ est.inertia_cov @ np.kron(u, u), 0)))
        lines.append(f"    {value:.3e} +- {s:.1e}  along {np.array2string(u, precision=3)}")
    return lines


def dynamic_summary(est: DynamicEstimate, frame: str) -> str:
    """Mass, CoM, principal moments with their std; where the arm's own torques came from."""
    std = np.sqrt(np.clip(np.diag(est.cov), 0, None))
    c = 1e3 * est.com_ee
    arm = {
        EMPTY_RUN: "the empty-arm run subtracted",
        NOMINAL: "the URDF's NOMINAL model stands for the arm (last resort), friction identified",
    }.get(est.arm_model, "the arm's identified model (identify-arm) stands for the arm")
    lines = [
        f"payload from a {est.duration_s:.1f} s motion ({est.n_samples} samples after a "
        f"{est.cutoff_hz:g} Hz zero-phase filter; velocities from {est.velocity_from}); {arm}",
        *mass_lines(est, std),
        f"  CoM in {frame}:  x {c[0]:8.2f} +- {1e3 * std[1]:.2f} mm",
        f"                 y {c[1]:8.2f} +- {1e3 * std[2]:.2f} mm",
        f"                 z {c[2]:8.2f} +- {1e3 * std[3]:.2f} mm",
        *moment_lines(est, frame),
    ]
    lines += [
        f"  condition number of the logged motion {est.condition_number:.1f} (scaled regressor)",
        f"  residual RMS per joint {np.array2string(est.residual_rms, precision=3)} N m",
        f"  held out ({est.validation.folds} folds): RMS per joint "
        f"{np.array2string(est.validation.rms_Nm, precision=3)} N m, "
        f"{100 * est.validation.explained_total:.1f} % of the torque difference explained",
        f"  the motion's halves alone: {est.halves_mass[0]:.4f} and {est.halves_mass[1]:.4f} kg",
    ]
    if est.second_log is not None:
        v = est.second_log
        lines.append(f"  on the second log: RMS per joint {np.array2string(v.rms_Nm, precision=3)}"
                     f" N m, {100 * v.explained_total:.1f} % explained")  # fmt: skip
    if est.alignment is not None:
        a = est.alignment
        lines.append(f"  empty run aligned: its time = loaded time {a['shift_s']:+.3f} s, "
                     f"positions {1e3 * a['rms_gap_rad']:.2f} mrad apart (rms)")  # fmt: skip
    if est.delay_s is not None:
        lines.append(f"  the efforts lag the positions by {1e3 * est.delay_s:.1f} ms (found)")
    if est.gains_source is not None:
        lines.append(f"  motor currents turned into torques with gains: {est.gains_source}")
    lines.append(f"VERDICT: {est.verdict}")
    lines += [f"  - {r}" for r in est.reasons]
    return "\n".join(lines)
