"""A motion's wrench estimate as RESULT.json (DESIGN.md 4c-4e) and as a few lines for a person."""

from __future__ import annotations

import numpy as np

from comgrasp_pin.robot_io.dynamic_report import mass_lines, moment_lines, payload_fields
from comgrasp_pin.robot_io.wrench_estimate import WrenchDynamicEstimate
from comgrasp_pin.robot_io.wrench_report import bias_line

COVERS = (
    "noise and the model's error (block jackknife), the tool's parameters, the arm model (joint "
    "torques with an identified arm model)"
)


def _validation(est: WrenchDynamicEstimate) -> dict:
    """The held-out prediction per source: the wrench's axes (N, N m), the joints (N m)."""
    v = est.validation
    out = {
        "method": f"{v.folds} contiguous folds, each predicted from the others",
        "explained_total": v.explained_total,
        "wrench": {"rms_N": v.rms_Nm[:3].tolist(), "rms_Nm": v.rms_Nm[3:6].tolist(),
                   "explained": v.explained[:6].tolist()},
    }  # fmt: skip
    if est.joint_torques is not None:
        out["joint_torques"] = {"rms_Nm": v.rms_Nm[6:].tolist(),
                                "explained": v.explained[6:].tolist()}  # fmt: skip
    return out


def _joint_torques(est: WrenchDynamicEstimate) -> dict | None:
    j = est.joint_torques
    if j is None:
        return None
    return {
        "arm_model": j.arm_model,
        "torque_std_Nm": j.torque_std.tolist(),
        "offsets_Nm": j.offsets.tolist(),
        "offset_drift_Nm": j.offset_drift.tolist(),
        "friction": None if j.friction is None else {
            "viscous_Nms_per_rad": j.friction[:, 0].tolist(),
            "coulomb_Nm": j.friction[:, 1].tolist(),
        },
        "residual_rms_Nm": j.residual_rms.tolist(),
        "effort_delay_s": j.delay_s,
        "alignment": j.alignment,
        "note": j.note,
    }  # fmt: skip


def wrench_dynamic_result_dict(est: WrenchDynamicEstimate, frame: str) -> dict:
    """RESULT.json: the motion's payload fields (4c, 4d) plus the sensor's (4e), SI units."""
    return {
        **payload_fields(est, frame, COVERS),
        "source": "wrench" if est.joint_torques is None else "wrench and joint torques",
        "sensor_frame": est.sensor_frame,
        "sensor_bias": est.sensor_bias.tolist(),
        "sensor_bias_std": est.sensor_bias_std.tolist(),
        "sensor_bias_units": "force_x, force_y, force_z (N), torque_x, torque_y, torque_z (N m)",
        "sensor_bias_about": "the mean over the motion; sensor_bias_drift is its change over it",
        "sensor_bias_drift": est.sensor_bias_drift.tolist(),
        "wrench_delay_s": est.delay_s,
        "wrench_std": est.wrench_std.tolist(),
        "residual_rms_N": est.residual_rms_wrench[:3].tolist(),
        "residual_rms_Nm": est.residual_rms_wrench[3:].tolist(),
        "validation": _validation(est),
        "tool": {"source": est.tool, "params": est.tool_params.tolist(),
                 "params_cov": est.tool_cov.tolist(), "frame": frame},
        "contributions": est.contributions,
        "sources_agreement": est.agreement,
        "alone_refused": est.alone_refused,
        "joint_torques": _joint_torques(est),
    }  # fmt: skip


def wrench_dynamic_summary(est: WrenchDynamicEstimate, frame: str) -> str:
    """Mass, CoM, principal moments with their std; the sensor's bias; each source's share."""
    std = np.sqrt(np.clip(np.diag(est.cov), 0, None))
    c = 1e3 * est.com_ee
    lines = [
        f"payload from a {est.duration_s:.1f} s motion seen by the wrist sensor "
        f"({est.sensor_frame}; {est.n_samples} samples after a {est.cutoff_hz:g} Hz zero-phase "
        f"filter); the tool's own wrench: {est.tool}",
        *mass_lines(est, std),
        f"  CoM in {frame}: ({c[0]:.2f}, {c[1]:.2f}, {c[2]:.2f}) mm (std {1e3 * std[1]:.2f}, "
        f"{1e3 * std[2]:.2f}, {1e3 * std[3]:.2f})",
        *moment_lines(est, frame),
    ]
    lines += [
        bias_line(est.sensor_bias, est.sensor_bias_std),
        f"  residual RMS: force {np.array2string(est.residual_rms_wrench[:3], precision=3)} N, "
        f"torque {np.array2string(est.residual_rms_wrench[3:], precision=4)} N m",
        f"  held out ({est.validation.folds} folds): "
        f"{100 * est.validation.explained_total:.1f} % of the readings explained",
        f"  the motion's halves alone: {est.halves_mass[0]:.4f} and {est.halves_mass[1]:.4f} kg",
    ]
    for name, share in est.contributions.items():
        com = ", ".join(f"{100 * s:.0f}" for s in share["com_m"])
        lines.append(f"  share of the information from {name}: mass {100 * share['mass_kg']:.0f} "
                     f"%, CoM ({com}) %")  # fmt: skip
    if est.joint_torques is not None:
        lines.append(f"  joint torques: the arm's own from {est.joint_torques.arm_model}")
        if est.joint_torques.note:
            lines.append(f"    ({est.joint_torques.note})")
    lines.append(f"VERDICT: {est.verdict}")
    lines += [f"  - {r}" for r in est.reasons]
    return "\n".join(lines)
