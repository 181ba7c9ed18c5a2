"""The several-pose closed form: the stacked 4x4 normal equations in few NumPy calls.

For k poses the unknowns are theta = (m, m c_ee) (kg, kg m); pose i contributes
dtau_i = Y_i theta with Y_i = G0 [J_lin_z, J_ang_x R[1] - J_ang_y R[0]] (``regressor``).
With v = G0 theta, Y_i^T / G0 = K_i J_i for a 5 x 6 K_i made of R_i's first two rows, and
J_i's unused last row (J_ang_z) carries b_i = dtau_i: one batched product gives every
[Y_i^T / G0; b_i^T], one more the 5 x 5 Gram matrix (N, Y^T b / G0, b^T b). LAPACK's
eigenvalues and inverse of N (NumPy's gufuncs) follow, then the rest in Python floats into
one array, as in ``one_pose``. Results equal ``np.linalg.lstsq`` on the stacked regression
to ~1e-13 relative (tests/test_closed_form.py).
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin

from comgrasp_pin.estimation import small_linalg
from comgrasp_pin.estimation.estimate import (
    MASS_SIGMAS,
    MIN_MASS_KG,
    ComEstimate,
    check_finite_result,
    construct,
    refuse_empty_gripper,
)
from comgrasp_pin.estimation.regressor import G0
from comgrasp_pin.robot import RobotModel

_WORLD_ALIGNED = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
_K_T = np.zeros((6, 5))  # K_i^T without R_i: J_lin_z -> the mass row, J_ang_z (b) -> b
_K_T[2, 0] = 1.0
_K_T[5, 4] = 1.0
_SWAP = np.array([[0.0, 1.0], [-1.0, 0.0]])  # [R0; R1] -> [R1; -R0]


def estimate(
    robot: RobotModel,
    Q: np.ndarray,
    dtau: np.ndarray,
    sigma: float | None,
    floor: float,
    noise_floor: float,
) -> ComEstimate | None:
    """``estimate_com(method="lstsq")`` at k > 1 poses ``Q`` (k, n), or None (the SVD path).

    Args:
        robot: the arm.
        Q: (k, n) checked configurations.
        dtau: (k, n) torque differences (N m).
        sigma: std of each reading (N m, the same on every joint), or None: then estimated
            from the residuals (floored at ``noise_floor``) where k n > 4.
        floor: smallest accepted ratio of N's extreme eigenvalues (1 / cond(Y)^2).
        noise_floor: see ``closed_form.NOISE_FLOOR``.
    """
    k, n = Q.shape
    model, data, fid = robot.model, robot.data, robot.ee_frame_id
    jacobian, oMf = pin.computeFrameJacobian, data.oMf
    J = np.empty((k, 6, n))  # world-aligned ee Jacobians
    T = np.empty((k, 4, 4))  # T_world_ee
    for i, q in enumerate(Q):
        J[i] = jacobian(model, data, q, fid, _WORLD_ALIGNED)
        T[i] = oMf[fid].homogeneous
    J[:, 5] = dtau
    K_t = np.empty((k, 6, 5))
    K_t[:] = _K_T
    K_t[:, 3:5, 1:4] = _SWAP @ T[:, :2, :3]  # rows J_ang_x, J_ang_y -> (R[1], -R[0])
    # [Y^T / G0; b^T] (5, k n), pose-major columns
    Z = (K_t.transpose(0, 2, 1) @ J).transpose(1, 0, 2).reshape(5, k * n)
    P = Z @ Z.T
    N = P[:4, :4]
    lam = small_linalg.eigvalsh(N).tolist()  # ascending
    if not lam[0] > floor * lam[3]:
        return None
    N_inv = small_linalg.inv(N)
    v = N_inv @ P[:4, 4]  # G0 theta
    residuals = Z[4] - v @ Z[:4]  # (k n,)
    rss = float(residuals @ residuals)
    rows = k * n
    noise_std = None
    if sigma is not None:
        var = 2.0 * sigma * sigma  # of a difference of two readings
    elif rows > 4:
        noise_std = max(math.sqrt(rss / (rows - 4)), noise_floor)
        var = noise_std * noise_std
    else:
        var = None
    v0, v1, v2, v3 = v.tolist()
    mass = v0 / G0
    cond = math.sqrt(lam[3] / lam[0])
    scale = None if var is None else var / (G0 * G0)  # cov(theta) = scale N^-1
    (C00, C01, C02, C03), (_, C11, C12, C13), (_, _, C22, C23), (_, _, _, C33) = N_inv.tolist()
    threshold = MIN_MASS_KG if scale is None else MASS_SIGMAS * math.sqrt(max(scale * C00, 0))
    if not mass > threshold:  # refused: the error says why
        refuse_empty_gripper(mass, None if scale is None else scale * C00, cond)
    c0, c1, c2 = v1 / v0, v2 / v0, v3 / v0
    values = [c0, c1, c2] + [G0 * math.sqrt(x) for x in reversed(lam)]
    if scale is not None:
        # the delta method, (m, c) = (t0, t[1:] / t0): G = [[1, 0], [-c / m, I / m]], G C G^T
        a, b = scale / mass, scale / (mass * mass)
        g1, g2, g3 = C01 - c0 * C00, C02 - c1 * C00, C03 - c2 * C00  # C_0j - c_j C_00
        s11 = (C11 - 2.0 * c0 * C01 + c0 * c0 * C00) * b
        s22 = (C22 - 2.0 * c1 * C02 + c1 * c1 * C00) * b
        s33 = (C33 - 2.0 * c2 * C03 + c2 * c2 * C00) * b
        s12 = (C12 - c0 * C02 - c1 * C01 + c0 * c1 * C00) * b
        s13 = (C13 - c0 * C03 - c2 * C01 + c0 * c2 * C00) * b
        s23 = (C23 - c1 * C03 - c2 * C02 + c1 * c2 * C00) * b
        values += [
            scale * C00, a * g1, a * g2, a * g3,
            a * g1, s11, s12, s13,
            a * g2, s12, s22, s23,
            a * g3, s13, s23, s33,
        ]  # fmt: skip
    rms = math.sqrt(rss / rows)
    if not math.isfinite(mass + rms + sum(values)):  # Python floats never warn
        cov_check = None if scale is None else np.array(values[7:]).reshape(4, 4)
        check_finite_result(mass=mass, com_ee=np.array(values[:3]), cov=cov_check,
                            residual_rms=rms)  # fmt: skip
    out = np.array(values)
    out.setflags(write=False)  # and so every view of it
    residuals.setflags(write=False)
    T.setflags(write=False)
    cov = None if scale is None else out[7:].reshape(4, 4)
    return construct(out[:3], mass, cov, None, residuals.reshape(k, n), rms, out[3:7], cond,
                     "lstsq", "closed_form", 0, T, noise_std)  # fmt: skip
