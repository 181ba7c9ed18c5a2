"""The one-pose closed form in Python floats: the 3x3 normal equations without LAPACK.

One pose observes v = G0 (m, m c_wy, -m c_wx) (the mass and the CoM's horizontal offset
c_w in the world; ``regressor.one_pose_basis``) through the rows z = (J_lin_z, J_ang_x,
J_ang_y) of the world-aligned ee Jacobian: dtau = z^T v. The 3x3 normal matrix N = z z^T,
z b and b^T b come out of one product; N's inverse (adjugate) and eigenvalues
(trigonometric formula) take a microsecond in Python floats, where each NumPy call on a
3x3 costs about as much (LAPACK only where two eigenvalues nearly coincide, MIN_GAP). The
results are those of ``closed_form.gram_solution`` (and of ``np.linalg.lstsq``) to ~1e-13
relative (tests/test_closed_form.py).
"""

from __future__ import annotations

import math
import operator

import numpy as np
import pinocchio as pin

from comgrasp_pin.estimation.estimate import (
    MASS_SIGMAS,
    MIN_MASS_KG,
    ComEstimate,
    check_finite_result,
    construct,
    refuse_empty_gripper,
)
from comgrasp_pin.estimation.regressor import G0
from comgrasp_pin.estimation.small_linalg import eigvalsh
from comgrasp_pin.robot import RobotModel

_WORLD_ALIGNED = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
MIN_GAP = 1e-2
"""The trigonometric formula's eigenvalues lose digits (1e-11 of the largest at a relative
gap of 1e-6) where two nearly coincide: below this relative gap LAPACK computes them."""
_TWO_THIRDS_PI = 2.0 * math.pi / 3.0


def sym3_eigenvalues(a, b, c, d, e, f) -> tuple[float, float, float]:
    """Eigenvalues (largest, middle, smallest) of the symmetric 3x3 [[a, b, c], [b, d, e], ...].

    The trigonometric formula: accurate to ~1e-15 times the largest where the eigenvalues are
    MIN_GAP apart (relative to the largest), as LAPACK's; less where two nearly coincide.
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
    gram = Z @ Z.T
    (a, b, c, r0), (_, d, e, r1), (_, _, f, r2), _ = gram.tolist()
    lam_max, lam_mid, lam_min = sym3_eigenvalues(a, b, c, d, e, f)
    if min(lam_max - lam_mid, lam_mid - lam_min) < MIN_GAP * lam_max:  # (near) double: LAPACK
        lam_min, lam_mid, lam_max = eigvalsh(gram[:3, :3]).tolist()
    if not lam_min > floor * lam_max:
        return None
    # N^-1 = adj(N) / det(N), N = [[a, b, c], [b, d, e], [c, e, f]]
    i00, i01, i02 = d * f - e * e, c * e - b * f, b * e - c * d
    i11, i12, i22 = a * f - c * c, b * c - a * e, a * d - b * b
    s = 1.0 / (a * i00 + b * i01 + c * i02)
    v0 = (i00 * r0 + i01 * r1 + i02 * r2) * s
    v1 = (i01 * r0 + i11 * r1 + i12 * r2) * s
    v2 = (i02 * r0 + i12 * r1 + i22 * r2) * s
    z0, z1, z2, dtau_list = Z.tolist()
    n = len(dtau_list)
    residuals = [t - (v0 * x + v1 * y + v2 * z) for x, y, z, t in zip(z0, z1, z2, dtau_list)]
    rss = sum(map(operator.mul, residuals, residuals))
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
    threshold = MIN_MASS_KG if k is None else MASS_SIGMAS * math.sqrt(max(k * i00, 0.0))
    if not mass > threshold:  # refused: the error says why
        refuse_empty_gripper(mass, None if k is None else k * i00, math.sqrt(lam_max / lam_min))
    R0, R1, R2, _ = T.tolist()
    cy, mcx = v1 / v0, v2 / v0  # c_wy, -c_wx
    com = [cy * R1[0] - mcx * R0[0], cy * R1[1] - mcx * R0[1], cy * R1[2] - mcx * R0[2]]
    sv = [G0 * math.sqrt(lam_max), G0 * math.sqrt(max(lam_mid, 0.0)), G0 * math.sqrt(lam_min)]
    # One array of com_ee, gravity in the ee frame, the singular values of Yr = G0 z^T (and
    # 0 along gravity), the residuals and the covariance: NumPy calls cost more than these
    # few dozen products in Python floats.
    values = com + [-R2[0], -R2[1], -R2[2]] + sv + [0.0] + residuals
    if k is not None:
        values += _delta_method(k * i00, k * i01, k * i02, k * i11, k * i12, k * i22,
                                com, R0, R1, 1.0 / mass)  # fmt: skip
    rms = math.sqrt(rss / n)
    if not math.isfinite(mass + rms + sum(values)):  # Python floats never warn
        cov_check = None if k is None else np.array(values[10 + n :]).reshape(4, 4)
        check_finite_result(mass=mass, com_ee=np.array(com), cov=cov_check, residual_rms=rms)
    out = np.array(values)
    out.setflags(write=False)  # and so every view of it
    T.setflags(write=False)
    cov = None if k is None else out[10 + n :].reshape(4, 4)
    return construct(out[:3], mass, cov, out[3:6], out[10 : 10 + n].reshape(1, n), rms,
                     out[6:10], math.sqrt(lam_max / lam_min), "lstsq", "closed_form", 0,
                     T.reshape(1, 4, 4), noise_std)  # fmt: skip


def _delta_method(c00, c01, c02, c11, c12, c22, com, R0, R1, inv_m) -> list[float]:
    """cov(m, c_ee) = D C D^T (4 x 4, row-major) for cov(w) = C (symmetric, 3 x 3).

    D = d(m, c_ee)/dw for w = (m, m c_wy, -m c_wx) and c_ee = (w1 R[1] - w2 R[0]) / m:
    row 0 is (1, 0, 0), row 1 + j is d_j = (-c_j, R1_j, -R0_j) / m. Written out: 75
    products in Python floats cost less than the NumPy calls they replace.
    """
    x0, y0, z0 = -com[0] * inv_m, R1[0] * inv_m, -R0[0] * inv_m
    x1, y1, z1 = -com[1] * inv_m, R1[1] * inv_m, -R0[1] * inv_m
    x2, y2, z2 = -com[2] * inv_m, R1[2] * inv_m, -R0[2] * inv_m
    # h_j = C d_j
    a0, b0, e0 = (
        c00 * x0 + c01 * y0 + c02 * z0,
        c01 * x0 + c11 * y0 + c12 * z0,
        c02 * x0 + c12 * y0 + c22 * z0,
    )
    a1, b1, e1 = (
        c00 * x1 + c01 * y1 + c02 * z1,
        c01 * x1 + c11 * y1 + c12 * z1,
        c02 * x1 + c12 * y1 + c22 * z1,
    )
    a2, b2, e2 = (
        c00 * x2 + c01 * y2 + c02 * z2,
        c01 * x2 + c11 * y2 + c12 * z2,
        c02 * x2 + c12 * y2 + c22 * z2,
    )
    # d_i . h_j
    s00, s11, s22 = (
        x0 * a0 + y0 * b0 + z0 * e0,
        x1 * a1 + y1 * b1 + z1 * e1,
        x2 * a2 + y2 * b2 + z2 * e2,
    )
    s01, s02, s12 = (
        x0 * a1 + y0 * b1 + z0 * e1,
        x0 * a2 + y0 * b2 + z0 * e2,
        x1 * a2 + y1 * b2 + z1 * e2,
    )
    return [
        c00, a0, a1, a2,
        a0, s00, s01, s02,
        a1, s01, s11, s12,
        a2, s02, s12, s22,
    ]  # fmt: skip
