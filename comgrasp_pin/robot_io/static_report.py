"""A static estimate's RESULT.json and its summary lines.

The static path's (``estimate``); the dynamic path's are in ``dynamic_report``.
"""

from __future__ import annotations

import numpy as np

from comgrasp_pin.estimation import ComEstimate
from comgrasp_pin.robot_io.estimate import LogEstimate


def estimate_fields(est: ComEstimate, frame: str) -> dict:
    """RESULT.json's fields of a static estimate (DESIGN.md section 4b), CoM in ``frame``."""
    u = est.unobservable_ee
    return {
        "mass_kg": est.mass,
        "com_m": [float(v) for v in est.com_ee],
        "frame": frame,
        "cov": None if est.cov is None else np.asarray(est.cov).tolist(),
        "unobservable": None if u is None else [float(v) for v in u],
        "n_poses": est.n_poses,
        "residual_rms_Nm": est.residual_rms,
    }


def result_dict(result: LogEstimate, frame: str) -> dict:
    """The RESULT.json contents (DESIGN.md section 4b): SI units, CoM in the ee frame."""
    est = result.estimate
    std = est.std
    return {
        **estimate_fields(est, frame),
        "std": None if std is None else _std_dict(result, std),
        "torque_std_Nm": result.torque_std.tolist(),
        "torque_std_from": result.noise_from,
        "torque_drift_Nm_per_sqrt_s": result.drift_std,
        "method": est.method,
        "solver_status": est.solver_status,
        "condition_number": est.condition_number,
        "q_rad": result.q.tolist(),
        "windows": {
            "before": [[r.t0, r.t1, r.n_samples] for r in result.before],
            "after": [[r.t0, r.t1, r.n_samples] for r in result.after],
        },
    }


def _std_dict(result: LogEstimate, std: np.ndarray) -> dict:
    """RESULT.json's ``std``; with the gains' covariance, the mass's std per source."""
    out: dict = {"mass_kg": float(std[0]), "com_m": std[1:].tolist()}
    parts = result.mass_std_by_source
    if parts is not None:
        out["covers"] = "the torque noise and the drive gains"
        out["mass_kg_by_source"] = parts
    return out


def summary(result: LogEstimate, frame: str) -> str:
    """A few lines for a person: mass and CoM with their std, what was not observed and why."""
    est = result.estimate
    std = est.std
    s = np.full(4, np.nan) if std is None else std
    c = est.com_ee
    lines = [
        f"payload from {est.n_poses} static pose(s), {est.method} "
        f"(torque std {result.noise_from}: {np.mean(result.torque_std):.3g} N m per averaged "
        "reading" + (f"; drift {result.drift_std:g} N m/sqrt(s)" if result.drift_std else "") + ")",
        f"  mass  {est.mass:.4f} +- {s[0]:.4f} kg",
        f"  CoM in {frame}:  x {1e3 * c[0]:8.2f} +- {1e3 * s[1]:.2f} mm",
        f"                 y {1e3 * c[1]:8.2f} +- {1e3 * s[2]:.2f} mm",
        f"                 z {1e3 * c[2]:8.2f} +- {1e3 * s[3]:.2f} mm",
        f"  residual RMS {est.residual_rms:.3g} N m",
    ]
    parts = result.mass_std_by_source
    if parts is not None:
        lines.insert(2, f"  mass std from the noise {parts['noise']:.4f} kg, from the drive "
                        f"gains {parts['gains']:.4f} kg")  # fmt: skip
    if est.unobservable_ee is not None:
        u = np.array2string(np.asarray(est.unobservable_ee), precision=3)
        lines.insert(2, f"  CoM: a line in {frame}; below, its point nearest the origin")
        lines.append(
            f"  unobservable: the CoM along {u} ({frame}) is set to 0, and the +- above hold "
            "across that line only: the CoM can be anywhere along it. That is gravity's "
            "direction at the pose(s): a weight along its own line of action exerts no moment, "
            "so static torques fix only the vertical line through the CoM. Add poses that turn "
            "the wrist against gravity (comgrasp plan-poses)."
        )
    return "\n".join(lines)
