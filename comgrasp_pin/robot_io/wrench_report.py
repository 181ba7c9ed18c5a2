"""A static wrench estimate's RESULT.json and its summary lines (DESIGN.md 4b and 4e)."""

from __future__ import annotations

import numpy as np

from comgrasp_pin.robot_io.wrench_static import WrenchStaticEstimate


def _floats(values) -> list:
    return [float(v) for v in np.ravel(values)]


def wrench_result_dict(est: WrenchStaticEstimate, frame: str) -> dict:
    """The RESULT.json contents: SI units, the CoM in the ee frame ``frame``."""
    std = np.sqrt(np.clip(np.diag(est.cov), 0, None))
    fit = est.fit
    return {
        "mass_kg": est.mass,
        "com_m": None if not fit.held else _floats(est.com_ee),
        "frame": frame,
        "cov": np.asarray(est.cov).tolist() if fit.held else None,
        "unobservable": None,
        "n_poses": est.n_poses,
        "residual_rms_Nm": est.residual_rms_Nm,
        "residual_rms_N": est.residual_rms_N,
        "std": {"mass_kg": float(std[0]), "com_m": _floats(std[1:]) if fit.held else None},
        "source": "wrench",
        "sensor_frame": est.sensor_frame,
        "com_sensor_m": None if not fit.held else _floats(est.com_sensor),
        "sensor_bias": _floats(est.sensor_bias),
        "sensor_bias_std": _floats(est.sensor_bias_std),
        "sensor_bias_units": "force_x, force_y, force_z (N), torque_x, torque_y, torque_z (N m)",
        "tool_subtracted": {"mass_kg": est.tool_mass, "com_sensor_m": _floats(est.tool_com_sensor)},
        "theta_sensor": _floats(fit.theta[:4]),
        "theta_sensor_cov": fit.theta_cov[:4, :4].tolist(),
        "theta_sensor_is": "m (kg), m c (kg m) in the sensor frame: what --tool reads back",
        "noise_from": est.noise_from,
        "chi2_per_dof": fit.chi2_dof,
        "covariance_scale": fit.scale,
        "gravity_spread_deg": _floats(fit.spread_deg),
        "verdict": est.verdict,
        "reasons": list(est.reasons),
        "q_rad": est.q.tolist(),
        "windows": [[a, b] for a, b in est.windows],
    }


def bias_line(b: np.ndarray, bs: np.ndarray) -> str:
    """The summary's line of the sensor's six offsets (N, N m) and their largest std."""
    return (
        f"  sensor bias: force ({b[0]:.3f}, {b[1]:.3f}, {b[2]:.3f}) N (std {bs[:3].max():.3f}), "
        f"torque ({b[3]:.4f}, {b[4]:.4f}, {b[5]:.4f}) N m (std {bs[3:].max():.4f})"
    )


def wrench_summary(est: WrenchStaticEstimate, frame: str) -> str:
    """A few lines for a person: mass, CoM and the sensor's bias with their std, the verdict."""
    std = np.sqrt(np.clip(np.diag(est.cov), 0, None))
    fit = est.fit
    lines = [
        f"payload from a wrist sensor ({est.sensor_frame}) at rest in {est.n_poses} "
        f"orientations (gravity spread {fit.spread_deg[0]:.0f} and {fit.spread_deg[1]:.0f} deg)",
        f"  mass {est.mass:.4f} kg (std {std[0]:.4f})",
    ]
    if fit.held:
        c, s = 1e3 * est.com_ee, 1e3 * std[1:]
        lines.append(
            f"  CoM in {frame}: ({c[0]:.2f}, {c[1]:.2f}, {c[2]:.2f}) mm "
            f"(std {s[0]:.2f}, {s[1]:.2f}, {s[2]:.2f})"
        )
    lines.append(bias_line(est.sensor_bias, est.sensor_bias_std))
    if est.tool_mass > 0:
        lines.append(f"  a tool beyond the sensor ({est.tool_mass:.3f} kg) subtracted")
    lines.append(
        f"  residuals {est.residual_rms_N:.3g} N, {est.residual_rms_Nm:.3g} N m RMS "
        f"(chi2/dof {fit.chi2_dof:.2f}; covariance scaled by {fit.scale:.2f})"
    )
    lines.append(f"  verdict: {est.verdict}")
    lines += [f"    - {r}" for r in est.reasons]
    return "\n".join(lines)
