"""Payload mass and CoM (ee frame) from a wrist force/torque sensor before and after a grasp.

The wrench the held payload adds to the sensor's reading, at rest in a pose where gravity
is g_s in the sensor frame, is linear in the joint-torque path's unknowns theta = (m, m c_ee):

    dw = [ m g_s ;  (m c_s) x g_s ],   m c_s = m p + R (m c_ee)
       = [[g_s, 0], [-[g_s]x p, -[g_s]x R]] theta                       (6 rows per pose)

with (R, p) the ee frame's pose in the sensor frame (fixed: both on the last link). The rows
go through the same solver as the joint torques' (``estimator.solve_rows``): the same
observability (one pose loses the CoM along gravity), least squares or IPOPT with the rod's
axis as a prior, the payload's motion in the jaws between poses, the same refusals. The
sensor's bias cancels in the difference; its drift between the two windows does not and
belongs in the rows' noise.

Given joint torques of the same windows too, both sets of rows are stacked, each weighed by
its own noise; ``source_shares`` says how much of the information on each unknown came
from each.

What the sensor carries beyond the payload, the tool, is the URDF's links beyond the sensor
frame (``tool_beyond``): a difference before/after the grasp cancels it, an estimate from
orientations alone (``robot_io.at_rest.wrench_static``) subtracts it.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from comgrasp_pin import validate
from comgrasp_pin.errors import InvalidInputError
from comgrasp_pin.estimation.estimate import ComEstimate
from comgrasp_pin.estimation.estimator import RCOND, carried, solve_rows
from comgrasp_pin.estimation.inputs import check_arrays, check_dtau_cov, check_options
from comgrasp_pin.estimation.prior import AxisPrior
from comgrasp_pin.estimation.regressor import stacked_regressor
from comgrasp_pin.robot import RobotModel, check_frame

UNKNOWNS = ("mass", "m c_x", "m c_y", "m c_z")


def T_sensor_ee(robot: RobotModel, sensor_frame: str) -> np.ndarray:
    """(4, 4) the ee frame's pose in the sensor frame; both must be on the last link."""
    return robot.T_frame_ee(sensor_frame, "sensor frame")


def _parent_frame(robot: RobotModel, f_id: int) -> int:
    """The frame ``f_id`` hangs from.

    A joint the reduced model locked (a finger) becomes a frame that is its own parent there;
    the full model still knows its parent link.
    """
    model = robot.model
    up = model.frames[f_id].parentFrame
    if up != f_id:
        return up
    full = robot.full_model
    name = full.frames[full.frames[full.getFrameId(model.frames[f_id].name)].parentFrame].name
    return model.getFrameId(name)


def tool_beyond(robot: RobotModel, sensor_frame: str) -> pin.Inertia:
    """The URDF's links beyond ``sensor_frame`` as one body, in the sensor frame.

    A link is beyond the sensor when its chain of parent frames reaches the sensor frame
    without leaving the sensor's rigid body (the last joint's). The sensor frame's own link
    counts as beyond it, the tool side (a hand named as the sensor frame: the sensor sits at
    its mounting face); a sensor's frame is best a massless link of its own.
    """
    model = robot.model
    check_frame(model, sensor_frame, "sensor frame")
    s_id = model.getFrameId(sensor_frame)
    joint = model.frames[s_id].parentJoint
    total = pin.Inertia.Zero()
    own = model.frames[model.frames[s_id].parentFrame]  # a link's inertia is on its joint's frame
    if model.frames[s_id].type == pin.FrameType.BODY and own.type == pin.FrameType.FIXED_JOINT:
        total += own.placement.act(own.inertia)
    for f_id, frame in enumerate(model.frames):
        if frame.parentJoint != joint or frame.inertia.mass <= 0:
            continue
        up, seen = f_id, set()
        while up != s_id and up not in seen and model.frames[up].parentJoint == joint:
            seen.add(up)
            up = _parent_frame(robot, up)
        if up == s_id:
            total += frame.placement.act(frame.inertia)
    return model.frames[s_id].placement.actInv(total)


def tool_wrench(robot: RobotModel, q: np.ndarray, sensor_frame: str) -> np.ndarray:
    """(6,) the gravity wrench of the URDF's links beyond the sensor at ``q`` (N, N m)."""
    tool = tool_beyond(robot, sensor_frame)
    g = robot.frame_pose(q, sensor_frame)[:3, :3].T @ robot.model.gravity.linear
    return np.r_[tool.mass * g, np.cross(tool.mass * tool.lever, g)]


def wrench_regressor(
    robot: RobotModel, Q: np.ndarray, sensor_frame: str
) -> tuple[np.ndarray, np.ndarray]:
    """Rows (k*6, 4) of the wrench change in theta = (m, m c_ee), and T_world_ee (k, 4, 4)."""
    T_se = T_sensor_ee(robot, sensor_frame)
    R, p = T_se[:3, :3], T_se[:3, 3]
    g = robot.model.gravity.linear
    rows, T = [], []
    for q in Q:
        T_world_s = robot.frame_pose(q, sensor_frame)
        g_s = T_world_s[:3, :3].T @ g
        Z = np.zeros((6, 4))
        Z[:3, 0] = g_s
        Z[3:, 0] = -pin.skew(g_s) @ p
        Z[3:, 1:] = -pin.skew(g_s) @ R
        rows.append(Z)
        T.append(T_world_s @ T_se)
    return np.vstack(rows), np.array(T)


def _wrench_noise(wrench_std, wrench_cov, k: int) -> tuple[np.ndarray | None, np.ndarray | None]:
    """(row_std (6k,), None) or (None, Cholesky factor) of the wrench differences' noise."""
    if (wrench_std is None) == (wrench_cov is None):
        raise InvalidInputError(
            "give wrench_std (each difference's std: 6 numbers, N and N m, or one per row) "
            "or wrench_cov (the differences' full covariance), exactly one"
        )
    if wrench_cov is not None:
        return None, check_dtau_cov(wrench_cov, 6 * k, None)
    std = validate.real_array(wrench_std, "wrench_std").ravel()
    if std.size == 6:
        std = np.tile(std, k)
    if std.size != 6 * k or not np.all(np.isfinite(std) & (std > 0)):
        raise InvalidInputError(
            f"wrench_std must be 6 or {6 * k} finite numbers > 0 (N, N m), got {std.size}"
        )
    return std, None


def estimate_com_wrench(
    robot: RobotModel,
    q: np.ndarray,
    wrench_before: np.ndarray,
    wrench_after: np.ndarray,
    sensor_frame: str,
    wrench_std: np.ndarray | None = None,
    wrench_cov: np.ndarray | None = None,
    method: str = "lstsq",
    com_prior: AxisPrior | None = None,
    payload_motion_ee: np.ndarray | None = None,
    torques: tuple | None = None,
    rcond: float = RCOND,
) -> ComEstimate:
    """Mass and CoM (ee frame) from the wrench change at k poses, with the torques' if given.

    Args:
        robot: the arm; its model's gravity is the one the readings were taken under.
        q: (k, n) the static configurations (rad).
        wrench_before: (k, 6) mean readings without the payload (force N, torque N m,
            sensor frame).
        wrench_after: (k, 6) the same holding it.
        sensor_frame: the URDF frame of the sensor, on the last link.
        wrench_std: (6,) or (6 k,) std of each difference (N, N m); or
        wrench_cov: (6 k, 6 k) their covariance, pose-major (a drift shared across poses).
        method: as ``estimate_com``.
        com_prior: as ``estimate_com``.
        payload_motion_ee: as ``estimate_com``.
        rcond: as ``estimate_com``.
        torques: (tau_before, tau_after, dtau_cov) of the same windows ((k, n), (k, n),
            (k n, k n)) to use as well, or None for the wrench alone.

    Raises:
        InvalidInputError, UnobservableError, EmptyGripperError, SolverError: as
            ``estimate_com``.
    """
    check_options(method, rcond, "l2", 3.0, com_prior, None)
    n = robot.model.nq
    Q = validate.real_array(q, "q").reshape(-1, n)
    k = len(Q)
    dw = validate.real_array(wrench_after, "wrench_after") - validate.real_array(
        wrench_before, "wrench_before"
    )
    if dw.shape != (k, 6) or not np.all(np.isfinite(dw)):
        raise InvalidInputError(
            f"wrench_before and wrench_after must be finite, shape ({k}, 6), got {dw.shape}"
        )
    Y, T = wrench_regressor(robot, Q, sensor_frame)
    std, chol = _wrench_noise(wrench_std, wrench_cov, k)
    b = dw.ravel()
    if torques is not None:
        Y, b, std, chol = _with_torques(robot, Q, Y, b, std, chol, torques)
    if payload_motion_ee is not None:  # per pose: its torque rows, then its wrench rows
        Y = carried(Y, payload_motion_ee, k)
    g = robot.model.gravity.linear
    return solve_rows(Y, b, T, g, std, chol, method, rcond, com_prior=com_prior)


def _with_torques(robot, Q, Y_w, b_w, std_w, chol_w, torques):
    """The torque rows stacked with the wrench rows pose by pose, one covariance for all."""
    tau_before, tau_after, dtau_cov = torques
    _, dtau, _ = check_arrays(robot, Q, tau_before, tau_after, None)
    k, n = dtau.shape
    chol_t = check_dtau_cov(dtau_cov, k * n, None)
    if chol_t is None:
        raise InvalidInputError("torques need their differences' covariance (k n, k n)")
    Y_t, _ = stacked_regressor(robot, Q)
    cov_w = chol_w @ chol_w.T if chol_w is not None else np.diag(std_w**2)
    cov_t = chol_t @ chol_t.T
    order = np.concatenate(
        [
            np.r_[np.arange(i * n, (i + 1) * n), k * n + np.arange(6 * i, 6 * i + 6)]
            for i in range(k)
        ]
    )  # pose-major: pose i's n torque rows, then its 6 wrench rows
    Y = np.vstack([Y_t, Y_w])[order]
    b = np.concatenate([dtau.ravel(), b_w])[order]
    cov = np.zeros((k * (n + 6), k * (n + 6)))
    cov[: k * n, : k * n], cov[k * n :, k * n :] = cov_t, cov_w
    return Y, b, None, np.linalg.cholesky(cov[np.ix_(order, order)])


def source_shares(
    blocks: dict[str, tuple[np.ndarray, np.ndarray]], directions: dict | None = None
) -> dict[str, dict]:
    """How much of the information on each unknown each source gave (shares sum to 1).

    Args:
        blocks: per source, (Y (rows, 4) its rows in theta, cov (rows, rows) their noise).
        directions: {name: (4,) a} the combinations a . theta to share out; None: each of
            ``UNKNOWNS``.

    Returns:
        per source, {name: a^T C F_s C a / a^T C a}: F_s = Y^T cov^-1 Y is the source's
        Fisher information and C the inverse of their sum, so that a^T C a, the combined
        variance, splits into one non-negative part per source (the pseudo-inverse where
        one pose leaves a direction unseen; a combination with no information shares 0).
    """
    if directions is None:
        directions = dict(zip(UNKNOWNS, np.eye(4), strict=True))
    F = {name: Y.T @ np.linalg.solve(cov, Y) for name, (Y, cov) in blocks.items()}
    C = np.linalg.pinv(sum(F.values()), rcond=1e-10, hermitian=True)
    out: dict[str, dict] = {name: {} for name in F}
    for label, a in directions.items():
        Ca = C @ np.asarray(a, dtype=float)
        total = float(a @ Ca)
        for name, Fs in F.items():
            out[name][label] = float(Ca @ Fs @ Ca) / total if total > 0 else 0.0
    return out
