"""A payload estimate for a person: a few lines for every estimate mode, a motion's figure.

``summary(est)``: what it came from, the mass with its std and 95 % interval, the CoM, the
inertia where a motion gave it, what each source found (the joint torques' arm model and
noise, the sensor's bias and tool), the checks (held out, halves), each source's share, and
the verdict with its reasons.

``plot_validation(est, ...)``: a motion's payload torques, measured against predicted out of
sample, one panel per joint. What a person checks at a glance: does the identified payload
explain what the joints felt on parts of the motion it was not fitted on? Each panel shows
the payload's measured torque (the efforts minus the arm's own and the offsets) and its
held-out prediction, with the held-out RMS and the share explained in the title; the
verdict heads the figure.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from comgrasp_pin.errors import OutputError
from comgrasp_pin.estimation.trust import principal_moments
from comgrasp_pin.robot_io.results.estimate_result import (
    Inertia,
    JointTorques,
    Motion,
    PayloadEstimate,
    Wrench,
)

LABELS = {"mass_kg": "mass", "com_m": "CoM", "first_moment_kgm": "m c",
          "principal_moments_kgm2": "principal moments"}  # fmt: skip
"""The sources' shares, by their keys in ``PayloadEstimate.sources``."""


def _vec(values, scale: float = 1.0, precision: int = 3) -> str:
    return np.array2string(scale * np.asarray(values, dtype=float), precision=precision)


def _head(est: PayloadEstimate) -> str:
    m, r, w = est.motion, est.at_rest, est.wrench
    if r is not None:
        text = f"payload from {r.n_poses} pose(s) at rest ({est.mode}, {r.method})"
    elif m is not None:
        text = (f"payload from a {m.duration_s:.1f} s motion ({est.mode}; {m.n_samples} samples "
                f"after a {m.cutoff_hz:g} Hz zero-phase filter; velocities from "
                f"{m.velocity_from})")  # fmt: skip
    else:
        text = f"payload ({est.mode})"
    if w is not None:
        text += f"; sensor frame {w.sensor_frame}, the tool's own wrench: {w.tool}"
    return text


def _student(dof: float) -> str:
    """The interval's words where the variance was estimated from few blocks, else ''."""
    return f", Student's t, {dof:.0f} dof" if np.isfinite(dof) else ""


def _mass_and_com(est: PayloadEstimate) -> list[str]:
    std, interval = est.std, est.interval95_mass
    if std is None or interval is None:
        lines = [f"  mass  {est.mass:.4f} kg (no uncertainty)"]
        std = np.full(4, np.nan)
    else:
        lo, hi = interval
        lines = [f"  mass  {est.mass:.4f} +- {std[0]:.4f} kg (std; 95 %: {lo:.3f} to {hi:.3f} kg"
                 f"{_student(est.dof[0])})"]  # fmt: skip
    if est.std_parts:
        lines.append("        std by source: "
                     + ", ".join(f"{k} {v:.4f}" for k, v in est.std_parts.items()))  # fmt: skip
    if not np.all(np.isfinite(est.com_ee)):
        return [*lines, "  CoM: not determined"]
    c, s = 1e3 * est.com_ee, 1e3 * std[1:]
    if est.unobservable_ee is not None:
        lines.append(f"  CoM: a line in {est.frame}; below, its point nearest the origin")
    lines += [f"  CoM in {est.frame}:  {axis} {c[i]:8.2f} +- {s[i]:.2f} mm"
              for i, axis in enumerate("xyz")]  # fmt: skip
    return lines


def _inertia(i: Inertia, frame: str) -> list[str]:
    moments, axes, std = principal_moments(i.inertia_com_ee, i.inertia_cov)
    lines = [f"  principal moments of inertia about the CoM (kg m^2), axes in {frame} "
             f"(inertia {i.verdict}); std, 95 % half-width{_student(i.dof)}:"]  # fmt: skip
    for value, u, s in zip(moments, axes.T, std):
        lines.append(f"    {value:.3e} +- {s:.1e} (95 %: +- {i.t95 * s:.1e})  along {_vec(u)}")
    return lines + [f"    - {r}" for r in i.reasons]


def _joint_torques(j: JointTorques, at_rest: bool) -> list[str]:
    lines = []
    if j.arm_model is not None:
        lines.append(f"  joint torques: the arm's own from {j.arm_model}")
    if j.note:
        lines.append(f"    ({j.note})")
    if at_rest:
        drift = f"; drift {j.drift_std:g} N m/sqrt(s)" if j.drift_std else ""
        lines.append(f"  torque std ({j.noise_from}): {np.mean(j.torque_std):.3g} N m per averaged "
                     f"reading{drift}")  # fmt: skip
    if j.side_friction is not None:
        f = j.side_friction
        lines.append(f"  stuck friction (the sides' spread, RMS over poses) "
                     f"{_vec(np.sqrt(np.mean(f.spread**2, axis=0)))} N m; the sides' mean "
                     f"left {f.share_left:.2f} of it")  # fmt: skip
    if j.residual_rms is not None:
        lines.append(f"  residual RMS per joint {_vec(j.residual_rms)} N m")
    if j.alignment is not None:
        a = j.alignment
        lines.append(f"  empty run aligned: its time = loaded time {a['shift_s']:+.3f} s, "
                     f"positions {1e3 * a['rms_gap_rad']:.2f} mrad apart (rms)")  # fmt: skip
    if j.delay_s is not None:
        lines.append(f"  the efforts lag the positions by {1e3 * j.delay_s:.1f} ms (found)")
    if j.gains_source is not None:
        lines.append(f"  motor currents turned into torques with gains: {j.gains_source}")
    return lines


def _wrench(w: Wrench) -> list[str]:
    lines = []
    b, bs = w.sensor_bias, w.sensor_bias_std
    if b is not None and bs is not None:
        lines.append(
            f"  sensor bias: force ({b[0]:.3f}, {b[1]:.3f}, {b[2]:.3f}) N "
            f"(std {bs[:3].max():.3f}), torque ({b[3]:.4f}, {b[4]:.4f}, {b[5]:.4f}) N m "
            f"(std {bs[3:].max():.4f})"
        )
    if w.tool_mass > 0:
        lines.append(f"  a tool beyond the sensor ({w.tool_mass:.3f} kg) subtracted")
    if w.fit is not None and w.residual_rms is not None:
        lines.append(
            f"  residuals {w.residual_rms[0]:.3g} N, {w.residual_rms[1]:.3g} N m RMS (chi2/dof "
            f"{w.fit.chi2_dof:.2f}; covariance scaled by {w.fit.scale:.2f}; gravity spread "
            f"{w.fit.spread_deg[0]:.0f} and {w.fit.spread_deg[1]:.0f} deg)"
        )
    elif w.residual_rms is not None:
        lines.append(f"  residual RMS: force {_vec(w.residual_rms[:3])} N, torque "
                     f"{_vec(w.residual_rms[3:], precision=4)} N m")  # fmt: skip
    return lines


def _motion(m: Motion) -> list[str]:
    v = m.validation
    lines = [
        f"  condition number of the logged motion {m.condition_number:.1f} (scaled regressor)",
        f"  held out ({v.folds} folds): RMS per row {_vec(v.rms_Nm)} (N m; a wrench's rows N, "
        f"N m), {100 * v.explained_total:.1f} % of the readings explained",
        f"  the motion's halves alone: {m.halves_mass[0]:.4f} and {m.halves_mass[1]:.4f} kg",
    ]
    if m.second_log is not None:
        s = m.second_log
        lines.append(f"  on the second log: RMS per joint {_vec(s.rms_Nm)} N m, "
                     f"{100 * s.explained_total:.1f} % explained")  # fmt: skip
    return lines


def _shares(est: PayloadEstimate) -> list[str]:
    """Each source's share of the information, where more than one gave some."""
    if len(est.sources) < 2:
        return []
    lines = []
    for name, share in est.sources.items():
        parts = [f"{LABELS.get(key, key)} {_vec(100 * np.atleast_1d(value), precision=0)} %"
                 for key, value in share.items()]  # fmt: skip
        lines.append(f"  share of the information from {name.replace('_', ' ')}: "
                     + ", ".join(parts))  # fmt: skip
    return lines


def summary(est: PayloadEstimate) -> str:
    """Mass, CoM (and inertia) with their std, what each source found, the verdict."""
    lines = [_head(est), *_mass_and_com(est)]
    if est.inertia is not None:
        lines += _inertia(est.inertia, est.frame)
    if est.joint_torques is not None:
        lines += _joint_torques(est.joint_torques, est.at_rest is not None)
    if est.wrench is not None:
        lines += _wrench(est.wrench)
    if est.motion is not None:
        lines += _motion(est.motion)
    lines += _shares(est)
    if est.unobservable_ee is not None:
        lines.append(
            f"  unobservable: the CoM along {_vec(est.unobservable_ee)} ({est.frame}) is set "
            "to 0, and the +- above hold across that line only. That is gravity's direction "
            "at the pose: a weight exerts no moment along its own line of action."
        )
    lines.append(f"VERDICT: {est.verdict}")
    lines += [f"  - {r}" for r in est.reasons]
    return "\n".join(lines)


def plot_validation(est, joint_names, path: str | Path, title: str = "") -> Path:
    """Write the PNG of a motion's estimate's held-out validation; returns its path."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    v = est.motion.validation
    n = v.measured.shape[1]
    fig, axes = plt.subplots(n, 1, figsize=(10, 1.7 * n + 1.2), sharex=True, squeeze=False)
    t = v.t - v.t[0]
    edges = [t[i[0]] for i in np.array_split(np.arange(len(t)), v.folds)][1:]
    for j, ax in enumerate(axes[:, 0]):
        ax.plot(t, v.measured[:, j], color="0.25", lw=1.0, label="measured")
        ax.plot(t, v.predicted[:, j], color="tab:orange", lw=1.0, label="predicted (held out)")
        for e in edges:
            ax.axvline(e, color="0.8", lw=0.8, zorder=0)
        ax.set_ylabel(f"{joint_names[j]}\n(N m)", fontsize=8)
        ax.set_title(f"RMS {v.rms_Nm[j]:.3f} N m, explained {100 * v.explained[j]:.0f} %",
                     fontsize=8, loc="right")  # fmt: skip
        ax.tick_params(labelsize=8)
    axes[0, 0].legend(loc="upper left", fontsize=8, ncol=2)
    axes[-1, 0].set_xlabel("time in the motion (s); grey lines: the folds")
    m_std = float(np.sqrt(est.cov[0, 0]))
    inertia = "" if est.inertia is None else f" (inertia: {est.inertia.verdict})"
    head = (f"{title + ': ' if title else ''}payload {est.mass:.3f} ± {m_std:.3f} kg, verdict "
            f"{est.verdict.upper()}{inertia}: {100 * v.explained_total:.0f} % of the held-out "
            "readings explained")  # fmt: skip
    fig.suptitle(head, fontsize=10)
    fig.tight_layout()
    path = Path(path)
    try:
        fig.savefig(path, dpi=110)
    except OSError as exc:
        raise OutputError(f"cannot write {path}: {exc}") from None
    finally:
        plt.close(fig)
    return path
