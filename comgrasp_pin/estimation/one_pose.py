"""The one-pose closed form in Python floats: 3x3 normal equations without LAPACK calls.

One pose observes v = G0 (m, m c_wy, -m c_wx) (the mass and the CoM's horizontal offset
c_w in the world; ``regressor.one_pose_basis``) through the rows z = (J_lin_z, J_ang_x,
J_ang_y) of the world-aligned ee Jacobian: dtau = z^T v. The 3x3 normal matrix N = z z^T,
z b and b^T b come out of one product; N's inverse (adjugate) and eigenvalues
(trigonometric formula) take a microsecond in Python floats, where each NumPy call on a
3x3 costs about as much. The results are those of ``closed_form.gram_solution`` (and of
``np.linalg.lstsq``) to ~1e-13 relative (tests/test_closed_form.py).
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin

from comgrasp_pin.estimation.estimate import ComEstimate, new_estimate, refuse_empty_gripper
from comgrasp_pin.estimation.regressor import G0
from comgrasp_pin.robot import RobotModel

_WORLD_ALIGNED = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
_TWO_THIRDS_PI = 2.0 * math.pi / 3.0


def sym3_eigenvalues(a, b, c, d, e, f) -> tuple[float, float, float]:
    """Eigenvalues (largest, middle, smallest) of the symmetric 3x3 [[a, b, c], [b, d, e], ...].

    The trigonometric formula; absolute accuracy ~1e-15 times the largest, as LAPACK's.
    """
    p1 = b * b + c * c + e * e
    q3 = (a + d + f) / 3.0
    p2 = (a - q3) * (a - q3) + (d - q3) * (d - q3) + (f - q3) * (f - q3) + 2.0 * p1
    if p2 <= 0.0:
        return q3, q3, q3
    p = math.sqrt(p2 / 6.0)
    x, y, z = (a - q3) / p, (d - q3) / p, (f - q3) / p
    bb, cc, ee = b / p, c / p, e / p
    half_det = 0.5 * (x * (y * z - ee * ee) - bb * (bb * z - ee * cc) + cc * (bb * ee - y * cc))
    phi = math.acos(min(1.0, max(-1.0, half_det))) / 3.0
    largest = q3 + 2.0 * p * math.cos(phi)
    smallest = q3 + 2.0 * p * math.cos(phi + _TWO_THIRDS_PI)
    return largest, 3.0 * q3 - largest - smallest, smallest


def estimate(
    robot: RobotModel,
    q: np.ndarray,
    dtau: np.ndarray,
    sigma: float | None,
    floor: float,
    noise_floor: float,
) -> ComEstimate | None:
    """``estimate_com(method="lstsq")`` at one pose ``q`` (n,), or None (the SVD path).

    Args:
        robot: the arm.
        q: (n,) checked configuration.
        dtau: (n,) torque differences (N m).
        sigma: std of each reading (N m, the same on every joint), or None: then estimated
            from the residuals (floored at ``noise_floor``) where n > 3.
        floor: smallest accepted ratio of N's extreme eigenvalues (1 / cond(Yr)^2).
        noise_floor: see ``closed_form.NOISE_FLOOR``.

    Returns:
        The estimate, or None where the smallest eigenvalue of N is below ``floor`` times the
        largest (ill-conditioned: left to the SVD path).
    """
    model, data, fid = robot.model, robot.data, robot.ee_frame_id
    J = pin.computeFrameJacobian(model, data, q, fid, _WORLD_ALIGNED)
    T = data.oMf[fid].homogeneous
    J[5] = dtau  # J is ours and its last row (J_ang_z) is not needed: b rides along
    Z = J[2:6]  # (z0, z1, z2, b)
    (a, b, c, r0), (_, d, e, r1), (_, _, f, r2), _ = (Z @ Z.T).tolist()
    lam_max, lam_mid, lam_min = sym3_eigenvalues(a, b, c, d, e, f)
    if not lam_min > floor * lam_max:
        return None
    # N^-1 = adj(N) / det(N), N = [[a, b, c], [b, d, e], [c, e, f]]
    i00, i01, i02 = d * f - e * e, c * e - b * f, b * e - c * d
    i11, i12, i22 = a * f - c * c, b * c - a * e, a * d - b * b
    s = 1.0 / (a * i00 + b * i01 + c * i02)
    v0 = (i00 * r0 + i01 * r1 + i02 * r2) * s
    v1 = (i01 * r0 + i11 * r1 + i12 * r2) * s
    v2 = (i02 * r0 + i12 * r1 + i22 * r2) * s
    residuals = np.array([-v0, -v1, -v2, 1.0]) @ Z  # dtau - z^T v
    rss = float(residuals @ residuals)
    n = len(residuals)
    noise_std = None
    if sigma is not None:
        var = 2.0 * sigma * sigma  # of a difference of two readings
    elif n > 3:
        noise_std = max(math.sqrt(rss / (n - 3)), noise_floor)
        var = noise_std * noise_std
    else:
        var = None
    mass = v0 / G0
    # cov(w) = var N^-1 / G0^2 for w = v / G0 = (m, m c_wy, -m c_wx)
    k = None if var is None else var * s / (G0 * G0)
    refuse_empty_gripper(mass, None if k is None else k * i00, math.sqrt(lam_max / lam_min))
    R0, R1, R2, _ = T.tolist()
    cy, mcx = v1 / v0, v2 / v0  # c_wy, -c_wx
    com = [cy * R1[0] - mcx * R0[0], cy * R1[1] - mcx * R0[1], cy * R1[2] - mcx * R0[2]]
    # com_ee, gravity in the ee frame, the singular values of Yr = G0 z^T (and 0 along gravity)
    sv = [G0 * math.sqrt(lam_max), G0 * math.sqrt(max(lam_mid, 0.0)), G0 * math.sqrt(lam_min)]
    out = np.array(com + [-R2[0], -R2[1], -R2[2]] + sv + [0.0])
    cov = None
    if k is not None:
        inv_m = 1.0 / mass
        # D = d(m, c_ee)/dw: row 0 (1, 0, 0); rows 1-3 (-c_ee, R1, -R0) / m
        D = np.array(
            [
                [1.0, 0.0, 0.0],
                [-com[0] * inv_m, R1[0] * inv_m, -R0[0] * inv_m],
                [-com[1] * inv_m, R1[1] * inv_m, -R0[1] * inv_m],
                [-com[2] * inv_m, R1[2] * inv_m, -R0[2] * inv_m],
            ]
        )
        C = np.array([[i00, i01, i02], [i01, i11, i12], [i02, i12, i22]])
        cov = (D * k) @ C @ D.T
    return new_estimate(out[:3], mass, cov, out[3:6], residuals.reshape(1, n),
                        math.sqrt(rss / n), out[6:], math.sqrt(lam_max / lam_min), "lstsq",
                        "closed_form", 0, T.reshape(1, 4, 4), noise_std)  # fmt: skip
