"""The MAP estimate with an ``AxisPrior`` at one pose: all but IPOPT in Python floats.

The general path (``estimator._estimate``) reduces the regression with NumPy, which after an
IPOPT call (its code and data evict the caches) costs some 5 us per call: about 0.2 ms around
a 0.5 ms solve. Here the closed-form warm start, the regression and IPOPT's parameter vector
come from the 3x3 normal equations in Python floats (as ``one_pose``) and one array; IPOPT
solves the same problem (``ipopt.build``) from the same start, so the results are the general
path's (tests/test_closed_form.py). Ill-conditioned poses, no torque_std with three joints or
fewer: None, the general path decides.
"""

from __future__ import annotations

import math
import operator

import numpy as np
import pinocchio as pin

from comgrasp_pin.errors import UnobservableError
from comgrasp_pin.estimation import ipopt, one_pose, small_linalg
from comgrasp_pin.estimation.estimate import (
    ComEstimate,
    check_finite_result,
    construct,
    refuse_empty_gripper,
)
from comgrasp_pin.estimation.prior import AxisPrior
from comgrasp_pin.estimation.regressor import G0
from comgrasp_pin.estimation.rod_axis import MIN_AXIS_GRAVITY_ANGLE
from comgrasp_pin.robot import RobotModel

_WORLD_ALIGNED = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED


def start_on_axis(m0: float, c0, u, prior: AxisPrior) -> list[float]:
    """x0 = (m0, the point of the line c0 + t u nearest the prior's axis), ee frame.

    Raises:
        UnobservableError: the axis runs within MIN_AXIS_GRAVITY_ANGLE of u, the direction
            the torques cannot see.
    """
    d = prior.direction_ee.tolist()
    ud = u[0] * d[0] + u[1] * d[1] + u[2] * d[2]
    if abs(ud) > math.cos(MIN_AXIS_GRAVITY_ANGLE):
        raise UnobservableError(
            f"the prior's axis is {math.degrees(math.acos(min(abs(ud), 1.0))):.2f} deg "
            f"from the direction the torques cannot see (minimum "
            f"{math.degrees(MIN_AXIS_GRAVITY_ANGLE):.2f} deg): it cannot settle the CoM "
            "along it; measure at a pose where the rod is not vertical, or at two poses"
        )
    # P (c0 + t u - p) _|_ P u with P = I - d d^T; P u . P v = u . v - (u . d)(v . d)
    p = prior.point_ee.tolist()
    v = [c0[0] - p[0], c0[1] - p[1], c0[2] - p[2]]
    uv = u[0] * v[0] + u[1] * v[1] + u[2] * v[2]
    vd = v[0] * d[0] + v[1] * d[1] + v[2] * d[2]
    t = (uv - ud * vd) / (1.0 - ud * ud)
    return [m0, c0[0] - t * u[0], c0[1] - t * u[1], c0[2] - t * u[2]]


def estimate(
    robot: RobotModel,
    q: np.ndarray,
    dtau: np.ndarray,
    sigma: float | None,
    floor: float,
    noise_floor: float,
    loss: str,
    delta: float,
    prior: AxisPrior,
) -> ComEstimate | None:
    """``estimate_com(method="ipopt", com_prior=prior)`` at one pose, or None.

    Args:
        robot: the arm.
        q: (n,) checked configuration.
        dtau: (n,) torque differences (N m).
        sigma: std of each reading (N m, the same on every joint), or None.
        floor: smallest accepted ratio of N's extreme eigenvalues (1 / cond(Yr)^2).
        noise_floor: see ``closed_form.NOISE_FLOOR``.
        loss: "l2" or "huber".
        delta: the Huber threshold (standard deviations of a torque difference).
        prior: the ``AxisPrior``.

    Raises:
        UnobservableError, EmptyGripperError, SolverError, InvalidInputError.
    """
    n = len(q)
    if sigma is None and n <= 3:
        return None
    model, data, fid = robot.model, robot.data, robot.ee_frame_id
    J = pin.computeFrameJacobian(model, data, q, fid, _WORLD_ALIGNED)
    T = data.oMf[fid].homogeneous
    J[5] = dtau  # b rides in the unused row J_ang_z (one_pose)
    Z = J[2:6]
    gram = Z @ Z.T
    (a, b, c, r0), (_, d, e, r1), (_, _, f, r2), _ = gram.tolist()
    lam_max, lam_mid, lam_min = one_pose.sym3_eigenvalues(a, b, c, d, e, f)
    if min(lam_max - lam_mid, lam_mid - lam_min) < one_pose.MIN_GAP * lam_max:
        lam_min, lam_mid, lam_max = small_linalg.eigvalsh(gram[:3, :3]).tolist()
    if not lam_min > floor * lam_max:
        return None
    i00, i01, i02 = d * f - e * e, c * e - b * f, b * e - c * d
    i11, i12, i22 = a * f - c * c, b * c - a * e, a * d - b * b
    s = 1.0 / (a * i00 + b * i01 + c * i02)
    v0 = (i00 * r0 + i01 * r1 + i02 * r2) * s  # G0 (m, m c_wy, -m c_wx), the closed form
    v1 = (i01 * r0 + i11 * r1 + i12 * r2) * s
    v2 = (i02 * r0 + i12 * r1 + i22 * r2) * s
    z0, z1, z2, b_list = Z.tolist()
    if sigma is None:  # the noise from the closed form's residuals
        res = [t - (v0 * x + v1 * y + v2 * z) for x, y, z, t in zip(z0, z1, z2, b_list)]
        rss = sum(map(operator.mul, res, res))
        noise_std = max(math.sqrt(rss) / math.sqrt(n - 3), noise_floor)
        weight = 1.0 / noise_std
    else:
        weight = 1.0 / (math.sqrt(2.0) * sigma)  # 1 / std of a difference of two readings
        noise_std = None
    R0, R1, R2, _ = T.tolist()
    m0 = v0 / G0  # m0 = 0: refused after the solve
    cy, mcx = (v1 / v0, v2 / v0) if v0 != 0.0 else (0.0, 0.0)
    c0 = [cy * R1[j] - mcx * R0[j] for j in range(3)]
    x0 = start_on_axis(m0, c0, [-R2[0], -R2[1], -R2[2]], prior)
    # Y = G0 [J_lin_z, J_ang_x R[1] - J_ang_y R[0]] (n, 4), column-major for the parameters
    Y = [G0 * x for x in z0]
    for j in range(3):
        Y += [G0 * (x * R1[j] - y * R0[j]) for x, y in zip(z1, z2)]
    root = 1.0 / weight  # ipopt.parameters: the objective scaled by 1 / max(w)^2
    delta_s = delta * root if loss == "huber" else delta
    point, direction = prior.point_ee.tolist(), prior.direction_ee.tolist()
    params = np.array(Y + b_list + [weight * root] * n + [delta_s, *point, *direction,
                      root / prior.std])  # fmt: skip
    res_ipopt = ipopt.run(ipopt.build(n, 4, loss, True), x0, params, root * root)
    cov = ipopt.laplace_covariance(res_ipopt.hessian)
    m = float(res_ipopt.x[0])
    cond = math.sqrt(lam_max / lam_min)
    refuse_empty_gripper(m, float(cov[0, 0]), cond)
    x = res_ipopt.x.tolist()
    theta = [m, m * x[1], m * x[2], m * x[3]]
    residuals = [
        t - sum(map(operator.mul, theta, (Y[i], Y[n + i], Y[2 * n + i], Y[3 * n + i])))
        for i, t in enumerate(b_list)
    ]
    rms = math.sqrt(sum(map(operator.mul, residuals, residuals)) / n)
    sv = [G0 * math.sqrt(lam_max), G0 * math.sqrt(max(lam_mid, 0.0)), G0 * math.sqrt(lam_min)]
    values = x[1:] + sv + [0.0] + residuals
    if not math.isfinite(m + rms + sum(values) + sum(cov.ravel().tolist())):
        check_finite_result(mass=m, com_ee=np.array(x[1:]), cov=cov, residual_rms=rms)
    out = np.array(values)
    out.setflags(write=False)
    cov.setflags(write=False)
    T.setflags(write=False)
    return construct(out[:3], m, cov, None, out[7:].reshape(1, n), rms, out[3:7], cond, "ipopt",
                     res_ipopt.return_status, res_ipopt.iterations, T.reshape(1, 4, 4),
                     noise_std)  # fmt: skip
