"""Sensitivity of the estimator to the torque sensor's noise, for the notebook.

``noise_sweep`` is pure estimation (Monte Carlo on the regression model, no simulator).
Sweeps of the simulated experiments over any config value (grip force, noise, friction)
are ``experiments.sweep`` (``comgrasp sweep``).
"""

from __future__ import annotations

import numpy as np

from comgrasp_pin.estimation.estimator import estimate_com
from comgrasp_pin.estimation.regressor import stacked_regressor
from comgrasp_pin.robot import RobotModel


def noise_sweep(
    robot: RobotModel,
    poses: np.ndarray,
    mass: float,
    com_ee: np.ndarray,
    sigmas: list[float],
    n_samples: int = 500,
    draws: int = 200,
    seed: int = 0,
) -> list[dict]:
    """CoM error against the torque sensor's noise, measured and predicted.

    Each reading is the mean of ``n_samples`` sensor samples of std sigma (N m), before and
    after grasping, at the (k, n) ``poses``. Returns per sigma: the RMS CoM error over
    ``draws`` noisy draws (m), the standard deviation ``cov`` predicts (m), and the RMS mass
    error (kg). Errors are taken over the observable CoM directions only.
    """
    poses = np.atleast_2d(np.asarray(poses, dtype=float))
    Y, _ = stacked_regressor(robot, poses)
    theta = np.r_[mass, mass * np.asarray(com_ee, dtype=float)]
    dtau = (Y @ theta).reshape(poses.shape)
    rng = np.random.default_rng(seed)
    rows = []
    for sigma in sigmas:
        std = sigma / np.sqrt(n_samples)
        com_err, mass_err, predicted = [], [], None
        for _ in range(draws):
            before = rng.normal(0.0, std, poses.shape)
            after = dtau + rng.normal(0.0, std, poses.shape)
            est = estimate_com(robot, poses, before, after, torque_std=std)
            err = est.com_ee - com_ee
            if est.unobservable_ee is not None:
                err = err - (err @ est.unobservable_ee) * est.unobservable_ee
            com_err.append(err @ err)
            mass_err.append((est.mass - mass) ** 2)
            predicted = float(np.sqrt(np.trace(est.cov[1:, 1:])))
        rows.append({
            "sigma_Nm": sigma,
            "com_rms_m": float(np.sqrt(np.mean(com_err))),
            "com_std_predicted_m": predicted,
            "mass_rms_kg": float(np.sqrt(np.mean(mass_err))),
        })  # fmt: skip
    return rows
