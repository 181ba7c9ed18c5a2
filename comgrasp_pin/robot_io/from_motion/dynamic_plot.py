"""A motion's payload torques, measured against predicted out of sample, one panel per joint.

What a person checks at a glance: does the identified payload explain what the joints
felt on parts of the motion it was not fitted on? Each panel shows the payload's measured
torque (the efforts minus the arm's own and the offsets) and its held-out prediction, with
the held-out RMS and the share explained in the title; the verdict heads the figure.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from comgrasp_pin.errors import OutputError


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
