"""What the torque sensor's drift costs the CoM, by measurement design and estimator.

A Monte Carlo on the UR5's regressor (no contact physics): the realistic preset's link-side
sensor (0.05 N m white noise per 2 ms sample, a random walk of 0.005 N m / sqrt(s)) read
over 1 s windows at the times a trial grasp reads them (docs/results: empty windows at 3 and
6 s, held at 14 and 18 s), two poses (the measurement pose and it rolled by 20 deg), a rod
along ee-x tilted in the jaws, its CoM on the axis. Per design, the RMS error of the CoM's
position along the rod (mm) and the rms of z = error / stated std, for

- ``independent``: each pose's difference with the drift over its own interval, poses taken
  as independent (the estimator before the drift's covariance);
- ``gls``: the differences' full covariance (``estimation.drift``), generalised
  least squares: what the realistic procedure does;
- ``gls, empty last pose first``: the empty arm measured at the rolled pose first, so the
  first pose's interval is shorter;
- ``gls, bracketed``: the empty arm measured again after the rod is put down (about 10 s
  after the last held window), each pose's tau_before the Brownian bridge's interpolation
  of its two empty windows;
- ``no drift``: the white noise alone (the bound any design approaches).

Every design is evaluated on the same draws (one random walk on a 10 ms grid per draw,
each window's white noise drawn once), so that their differences are not the draws'.
Writes ``results/drift_designs.json``. Run: ``python benchmarks/drift_designs.py``.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

import comgrasp_pin as cg
from comgrasp_pin.estimation import AxisPrior
from comgrasp_pin.estimation.drift import mean_min
from comgrasp_pin.estimation.regressor import stacked_regressor
from comgrasp_pin.motion.ik import solve_ik

ROBOT = cg.RobotModel.ur5()
N = ROBOT.nq
DRIFT, WHITE = 0.005, 0.05 / np.sqrt(500)  # N m / sqrt(s); N m per 1 s window at 500 Hz
Q_FIRST = np.array([-0.175, -1.618, 1.229, -1.182, -1.571, -0.438])  # an accuracy trial's


def _rolled(q: np.ndarray, deg: float) -> np.ndarray:
    T = ROBOT.ee_pose(q)
    c, s = np.cos(np.radians(deg)), np.sin(np.radians(deg))
    T[:3, :3] = T[:3, :3] @ np.array([[1, 0, 0], [0, c, -s], [0, s, c]])
    return solve_ik(ROBOT, T, q)


Q = np.array([Q_FIRST, _rolled(Q_FIRST, 20.0)])
HELD = [(14.0, 1.0), (18.0, 1.0)]
DESIGNS = {
    "independent": [[(3.0, 1.0)], [(6.0, 1.0)]],
    "gls": [[(3.0, 1.0)], [(6.0, 1.0)]],
    "gls, empty last pose first": [[(6.0, 1.0)], [(3.0, 1.0)]],
    "gls, bracketed": [[(3.0, 1.0), (29.0, 1.0)], [(6.0, 1.0), (32.0, 1.0)]],
}


def _weights(empties: list, held: tuple) -> list:
    """tau_before's weights on the empty windows: one window, or the bridge between two."""
    if len(empties) == 1:
        return [1.0]
    (a, _), (b, _) = empties
    t = held[0]
    return [(b - t) / (b - a), (t - a) / (b - a)]


def _covariance(design: list, drift: float) -> np.ndarray:
    """(2 n, 2 n) covariance of the two poses' differences (windows' drift and white noise)."""
    spans = [*HELD, *[w for pose in design for w in pose]]
    rows = np.zeros((2, len(spans)))
    column = 2
    for i, empties in enumerate(design):
        rows[i, i] = 1.0
        for w in _weights(empties, HELD[i]):
            rows[i, column] = -w
            column += 1
    M = np.array([[mean_min(u, v) for v in spans] for u in spans])
    per_joint = rows @ (drift**2 * M + WHITE**2 * np.eye(len(spans))) @ rows.T
    return _per_joint_blocks(per_joint)


def _per_joint_blocks(per_joint: np.ndarray) -> np.ndarray:
    """The (2 n, 2 n) pose-major matrix with ``per_joint`` (2, 2) for every joint."""
    cov = np.zeros((2, N, 2, N))
    for j in range(N):
        cov[:, j, :, j] = per_joint
    return cov.reshape(2 * N, 2 * N)


DT = 0.01  # s, the random walk's time step in the Monte Carlo
HORIZON = 34.0  # s, past the last window


def _window_means(walk: np.ndarray, span: tuple) -> np.ndarray:
    """(n,) the walk (steps, n) averaged over the window ``span`` = (start, length) s."""
    a, b = round(span[0] / DT), round((span[0] + span[1]) / DT)
    return walk[a:b].mean(axis=0)


def _differences(walk: np.ndarray, white: dict, design: list) -> np.ndarray:
    """(2, n) each pose's held window minus its tau_before's windows, drift and white noise."""
    out = np.empty((2, N))
    for i, empties in enumerate(design):
        held = _window_means(walk, HELD[i]) + white[HELD[i]]
        before = sum(w * (_window_means(walk, e) + white[e])
                     for w, e in zip(_weights(empties, HELD[i]), empties, strict=True))  # fmt: skip
        out[i] = held - before
    return out


def run(mass: float, x: float, tilt_deg: float, draws: int, rng) -> dict:
    """Every design on the same draws of the walk and the windows' white noise (paired)."""
    th = np.radians(tilt_deg)
    R = np.array([[np.cos(th), 0, np.sin(th)], [0, 1, 0], [-np.sin(th), 0, np.cos(th)]])
    T_obj = np.eye(4)
    T_obj[:3, :3] = R
    com = R @ np.array([x, 0.0, 0.0])
    Y, _ = stacked_regressor(ROBOT, Q)
    dtau = (Y @ np.r_[mass, mass * com]).reshape(2, N)
    prior = AxisPrior.from_rod(T_obj, 0.003)
    cases = {**DESIGNS, "no drift": DESIGNS["gls"]}
    covs = {name: _covariance(d, 0.0 if name == "no drift" else DRIFT) for name, d in cases.items()}
    covs["independent"] = np.diag(np.diag(covs["independent"]))
    spans = {w for d in DESIGNS.values() for pose in d for w in pose} | set(HELD)
    err: dict = {name: [] for name in cases}
    z: dict = {name: [] for name in cases}
    for _ in range(draws):
        steps = DRIFT * np.sqrt(DT) * rng.standard_normal((round(HORIZON / DT), N))
        walk = np.cumsum(steps, axis=0)
        white = {w: WHITE * rng.standard_normal(N) for w in sorted(spans)}
        for name, design in cases.items():
            d = _differences(0.0 * walk if name == "no drift" else walk, white, design)
            est = cg.estimate_com(ROBOT, Q, np.zeros((2, N)), dtau + d, method="ipopt",
                                  com_prior=prior, dtau_cov=covs[name])  # fmt: skip
            e = float(R[:, 0] @ (est.com_ee - com))
            err[name].append(e)
            z[name].append(e / float(np.sqrt(R[:, 0] @ est.cov[1:, 1:] @ R[:, 0])))
    return {name: {"rms_error_mm": 1e3 * float(np.sqrt(np.mean(np.square(err[name])))),
                   "rms_z": float(np.sqrt(np.mean(np.square(z[name]))))}
            for name in cases}  # fmt: skip


def main() -> int:
    draws = int(sys.argv[1]) if len(sys.argv) > 1 else 400
    rng = np.random.default_rng(0)
    rods = [(0.5, 0.06, 3.0), (0.5, 0.06, 20.0), (1.4, 0.03, 3.0), (1.4, 0.03, 25.0)]
    results = []
    for mass, x, tilt in rods:
        row = {"mass_kg": mass, "com_from_grasp_m": x, "tilt_deg": tilt,
               **run(mass, x, tilt, draws, rng)}  # fmt: skip
        results.append(row)
        cells = ", ".join(f"{k} {v['rms_error_mm']:.2f} mm (z {v['rms_z']:.2f})"
                          for k, v in row.items() if isinstance(v, dict))  # fmt: skip
        print(f"{mass} kg, {tilt:.0f} deg: {cells}")
    out = Path(__file__).parent / "results" / "drift_designs.json"
    out.write_text(json.dumps({"draws": draws, "drift_std": DRIFT, "window_white_std": WHITE,
                               "held_windows": HELD, "designs": DESIGNS, "rods": results},
                              indent=1) + "\n")  # fmt: skip
    print(f"wrote {out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
