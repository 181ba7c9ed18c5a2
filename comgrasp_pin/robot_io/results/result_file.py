"""RESULT.json: every payload estimate written, and read back, by one schema (DESIGN.md 4f).

``result_dict(est)`` gives the file's contents for any ``PayloadEstimate``: the fields every
estimate has at the top (``schema_version``, ``mass_kg``, ``com_m``, ``cov``, ``std``,
``interval95_*``, ``verdict``, ``reasons``, ``sources``), then one object per part the
estimate has (``at_rest``, ``motion``, ``inertia``, ``joint_torques``, ``wrench``), None for
the others. SI units; the CoM and the inertia in the ee frame ``frame``. ``read_result``
reads a file back, checking its schema; ``prior_of_result`` and ``tool_of_result`` take what
``--prior`` and ``--tool`` need from one.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from comgrasp_pin.errors import InvalidInputError
from comgrasp_pin.estimation.payload_regressor import PARAMETER_NAMES
from comgrasp_pin.robot_io.results import estimate_result as er

SCHEMA_VERSION = 3
"""Raised at every change of a key's name or meaning (CHANGELOG). 1: the files before issue
41; 2: one schema for every mode; 3: intervals of Student's t and their ``dof``, the block
sandwich's ``std`` part, the sources' agreement per quantity (issue 42)."""
BIAS_UNITS = "force_x, force_y, force_z (N), torque_x, torque_y, torque_z (N m)"


def _list(values) -> list | None:
    """Floats of an array (NaN as None: JSON has no NaN), or None."""
    if values is None:
        return None
    a = np.asarray(values, dtype=float)
    out = a.astype(object)
    out[~np.isfinite(a)] = None
    return out.tolist()


def _number(value: float) -> float | None:
    """A float, or None where it is not finite (JSON has no inf)."""
    return float(value) if np.isfinite(value) else None


def result_dict(est: er.PayloadEstimate) -> dict:
    """The RESULT.json contents of ``est``."""
    std, half = est.std, est.interval95_halfwidth
    held = bool(np.all(np.isfinite(est.com_ee)))
    interval = est.interval95_mass
    out = {
        "schema_version": SCHEMA_VERSION,
        "mode": est.mode,
        "frame": est.frame,
        "mass_kg": est.mass,
        "com_m": _list(est.com_ee) if held else None,
        "cov": _list(est.cov) if held else None,
        "std": None if std is None else {
            "mass_kg": float(std[0]), "com_m": _list(std[1:]) if held else None,
            "mass_kg_by_source": est.std_parts or None,
        },
        "interval95_mass_kg": None if interval is None else list(interval),
        "interval95_com_m": None if half is None or not held else [
            [float(c - h), float(c + h)] for c, h in zip(est.com_ee, half[1:])],
        "dof": {"mass": _number(est.dof[0]), "com": _list(est.dof[1:]) if held else None,
                "about": "degrees of freedom of each variance; the 95 % intervals are "
                         "Student's t of them (null: known, the normal's 1.96)"},
        "verdict": est.verdict,
        "reasons": list(est.reasons),
        "sources": est.sources,
        "unobservable": _list(est.unobservable_ee),
    }  # fmt: skip
    out["at_rest"] = None if est.at_rest is None else _at_rest(est.at_rest)
    out["motion"] = None if est.motion is None else _motion(est.motion, est.wrench is not None)
    out["inertia"] = None if est.inertia is None else _inertia(est.inertia)
    j = est.joint_torques
    out["joint_torques"] = None if j is None else _joint_torques(j)
    out["wrench"] = None if est.wrench is None else _wrench(est.wrench)
    return out


def _at_rest(r: er.AtRest) -> dict:
    out = {"n_poses": r.n_poses, "q_rad": _list(r.q), "windows": r.windows,
           "method": r.method, "solver_status": r.solver_status,
           "condition_number": r.condition_number}  # fmt: skip
    if r.fit is not None:
        out["residual_rms"] = r.fit.residual_rms
    return out


def _motion(m: er.Motion, wrench: bool) -> dict:
    validation = m.validation.as_dict()
    if wrench:  # the rows: the wrench's six axes first, then the joints
        v = m.validation
        validation["rows"] = "wrench force_x..torque_z, then the joints (if used)"
        validation["wrench"] = {"rms_N": _list(v.rms_Nm[:3]), "rms_Nm": _list(v.rms_Nm[3:6]),
                                "explained": _list(v.explained[:6])}  # fmt: skip
    return {
        "n_samples": m.n_samples, "duration_s": m.duration_s, "cutoff_hz": m.cutoff_hz,
        "velocity_from": m.velocity_from, "solver_status": m.solver_status,
        "condition_number": m.condition_number, "halves_mass_kg": list(m.halves_mass),
        "validation": validation,
        "pipeline_bias_params": _list(m.pipeline_bias),
        "validation_log": None if m.second_log is None else {
            "rms_Nm": _list(m.second_log.rms_Nm), "explained": _list(m.second_log.explained),
            "explained_total": m.second_log.explained_total},
    }  # fmt: skip


def _inertia(i: er.Inertia) -> dict:
    return {
        "verdict": i.verdict, "reasons": list(i.reasons),
        "inertia_kgm2": _list(i.inertia_com_ee), "inertia_std_kgm2": _list(i.inertia_std),
        "inertia_dof": _number(i.dof), "inertia_t95": i.t95,
        "inertia_about": "the CoM, axes of frame",
        "params": dict(zip(PARAMETER_NAMES, i.params.tolist(), strict=True)),
        "params_cov": _list(i.params_cov),
        "params_about": "m (kg), m c (kg m), inertia at the frame's origin (kg m^2)",
        "unconstrained_params": _list(i.unconstrained_params),
    }  # fmt: skip


def _joint_torques(j: er.JointTorques) -> dict:
    return {
        "torque_std_Nm": _list(j.torque_std), "torque_std_from": j.noise_from,
        "arm_model": j.arm_model, "gains": j.gains_source,
        "torque_drift_Nm_per_sqrt_s": j.drift_std,
        "side_friction": None if j.side_friction is None else {
            "spread_Nm": _list(j.side_friction.spread),
            "share_left": j.side_friction.share_left,
            "own_pose_weight": j.side_friction.own_pose},
        "offsets_Nm": _list(j.offsets), "offset_drift_Nm": _list(j.offset_drift),
        "friction": None if j.friction is None else {
            "viscous_Nms_per_rad": _list(j.friction[:, 0]), "coulomb_Nm": _list(j.friction[:, 1])},
        "residual_rms_Nm": _list(j.residual_rms), "effort_delay_s": j.delay_s,
        "alignment": j.alignment, "note": j.note,
    }  # fmt: skip


def _wrench(w: er.Wrench) -> dict:
    out = {
        "sensor_frame": w.sensor_frame, "sensor_bias": _list(w.sensor_bias),
        "sensor_bias_std": _list(w.sensor_bias_std), "sensor_bias_units": BIAS_UNITS,
        "sensor_bias_drift": _list(w.sensor_bias_drift), "com_sensor_m": None,
        "tool": {"source": w.tool, "params": _list(w.tool_params), "params_cov":
                 _list(w.tool_cov), "mass_kg": w.tool_mass,
                 "com_sensor_m": _list(w.tool_com_sensor)},
        "noise_from": w.noise_from, "wrench_std": _list(w.wrench_std),
        "residual_rms": _list(w.residual_rms), "wrench_delay_s": w.delay_s,
        "agreement": None if w.agreement is None else {
            **w.agreement, "cov_dof": _list(w.agreement["cov_dof"])},
        "alone_refused": w.alone_refused or None,
    }  # fmt: skip
    if w.fit is not None:  # at rest: the fit in the sensor frame, what --tool reads back
        fit = w.fit
        out.update({
            "com_sensor_m": _list(w.com_sensor) if fit.held else None,
            "theta_sensor": _list(fit.theta[:4]), "theta_sensor_cov": _list(fit.theta_cov[:4, :4]),
            "theta_sensor_is": "m (kg), m c (kg m) in the sensor frame: what --tool reads back",
            "chi2_per_dof": fit.chi2_dof, "covariance_scale": fit.scale,
            "gravity_spread_deg": _list(fit.spread_deg),
        })  # fmt: skip
    return out


def write_result(est: er.PayloadEstimate, path: str | Path) -> Path:
    """Write ``est``'s RESULT.json to ``path`` (OutputError where it cannot be written)."""
    from comgrasp_pin.errors import OutputError

    path = Path(path)
    try:
        path.write_text(json.dumps(result_dict(est), indent=2) + "\n")
    except OSError as exc:
        raise OutputError(f"cannot write {path}: {exc}") from None
    return path


def read_result(path: str | Path, option: str = "RESULT.json") -> dict:
    """A RESULT.json read back; InvalidInputError where it is not one of this schema."""
    try:
        data = json.loads(Path(path).read_text())
    except (OSError, ValueError) as exc:
        raise InvalidInputError(f"{option} {path}: not a readable RESULT.json ({exc})") from None
    version = data.get("schema_version") if isinstance(data, dict) else None
    if version != SCHEMA_VERSION:
        raise InvalidInputError(
            f"{option} {path}: RESULT.json schema_version {version!r}, this comgrasp_pin reads "
            f"{SCHEMA_VERSION}: estimate again with this version"
        )
    return data


def prior_of_result(path: str | Path) -> tuple[np.ndarray, np.ndarray]:
    """((4,) mass and CoM, (4, 4) their covariance) of a static estimate's RESULT.json."""
    data = read_result(path, "--prior")
    try:
        mass, com = float(data["mass_kg"]), np.array(data["com_m"], float)
        cov = np.array(data["cov"], float)
    except (KeyError, TypeError, ValueError) as exc:
        raise InvalidInputError(f"--prior {path}: no mass, CoM and cov in it ({exc})") from None
    if cov.shape != (4, 4) or com.shape != (3,) or data.get("unobservable") is not None:
        raise InvalidInputError(
            f"--prior {path}: needs a full 3-D CoM with its 4x4 cov (mass, CoM)"
        )
    return np.concatenate([[mass], com]), cov


def tool_of_result(path: str | Path, sensor_frame: str) -> tuple[np.ndarray, np.ndarray]:
    """((4,) m, m c; (4, 4) cov) in the sensor frame, of a ``--keep-tool`` run's RESULT.json."""
    data = read_result(path, "--tool")
    try:
        w = data["wrench"]
        theta = np.array(w["theta_sensor"], dtype=float)
        cov = np.array(w["theta_sensor_cov"], dtype=float)
        frame, tool_mass = w["sensor_frame"], float(w["tool"]["mass_kg"])
    except (KeyError, TypeError, ValueError) as exc:
        raise InvalidInputError(
            f"--tool {path}: not the RESULT.json of a --wrench --keep-tool run ({exc})"
        ) from None
    if frame != sensor_frame or tool_mass != 0 or theta.shape != (4,) or cov.shape != (4, 4):
        raise InvalidInputError(
            f"--tool {path}: needs a --keep-tool run (nothing subtracted) in the sensor frame "
            f"{sensor_frame!r}; it has {frame!r} and {tool_mass:g} kg subtracted"
        )
    return theta, cov
