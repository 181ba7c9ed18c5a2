"""Checking the estimator's inputs: shapes, finiteness, options. Errors say what is valid."""

from __future__ import annotations

import math

import numpy as np

from comgrasp_pin import validate
from comgrasp_pin.errors import InvalidInputError
from comgrasp_pin.estimation.prior import AxisPrior
from comgrasp_pin.robot import RobotModel

METHODS = ("lstsq", "ipopt")
MAX_ABS_Q = 1e3
"""Largest joint value accepted (rad or m): beyond it a reading is not a configuration."""
MAX_ABS_TORQUE = 1e6
"""Largest torque reading accepted (N m): no arm joint bears a million N m, and beyond it
the least squares would overflow."""
TORQUE_STD_RANGE = (1e-9, 1e6)
"""Accepted torque_std (N m): no sensor is better than a nano-N m, none worse than a
million; outside, the weights would overflow."""
LOSSES = ("l2", "huber")


def check_options(
    method: str,
    rcond: float,
    loss: str,
    huber_delta: float,
    com_prior: object,
    torque_std: object,
) -> None:
    """Raise InvalidInputError for an option estimate_com does not accept."""
    if method not in METHODS:
        raise InvalidInputError(f"unknown method {method!r}; valid methods are {METHODS}")
    if not (type(rcond) is float and 0.0 < rcond < 1.0):  # the usual case in 50 ns
        validate.number(rcond, "rcond", low=0.0, high=1.0, low_open=True, high_open=True)
    if loss not in LOSSES:
        raise InvalidInputError(f"unknown loss {loss!r}; valid losses are {LOSSES}")
    if loss == "huber" and torque_std is None:
        raise InvalidInputError(
            "loss='huber' needs torque_std: its threshold huber_delta is counted in standard "
            "deviations of a torque difference"
        )
    if not (type(huber_delta) is float and 0.0 < huber_delta < math.inf):
        validate.number(huber_delta, "huber_delta", low=0.0, low_open=True)
    if com_prior is not None and not isinstance(com_prior, AxisPrior):
        raise InvalidInputError(f"com_prior must be an AxisPrior or None, got {com_prior!r}")
    if method == "lstsq" and (loss != "l2" or com_prior is not None):
        raise InvalidInputError(
            "a robust loss or a com_prior needs method='ipopt' (lstsq is the closed form of "
            "the plain least squares)"
        )


def check_arrays(
    robot: RobotModel,
    q: np.ndarray,
    tau_before: np.ndarray,
    tau_after: np.ndarray,
    torque_std: float | np.ndarray | None,
) -> tuple[np.ndarray, np.ndarray, float | np.ndarray | None]:
    """(q, dtau = tau_after - tau_before, sigma), q and dtau in the shape given: (n,) or (k, n).

    sigma, the std of each torque reading (N m): a float where ``torque_std`` is a scalar,
    an (n,) array where it is given per joint, None where it is not given.
    """
    if not isinstance(robot, RobotModel):
        raise InvalidInputError(f"robot must be a RobotModel, got {type(robot).__name__}")
    n = robot.model.nq
    q_arr = validate.real_array(q, "q")
    tb_arr = validate.real_array(tau_before, "tau_before")
    ta_arr = validate.real_array(tau_after, "tau_after")
    shape = q_arr.shape
    if q_arr.ndim not in (1, 2) or shape[-1] != n or (len(shape) == 2 and shape[0] < 1):
        raise InvalidInputError(
            f"q must have shape ({n},) for one pose or (k, {n}) for k >= 1 poses (the robot "
            f"has {n} joints), got {shape}"
        )
    # The quick screen: sums of |values| within the limits clear every value (NaN and inf
    # included) in Python floats, which never warn. Where it does not clear them, the
    # checks in order name the first bad shape or entry.
    if not (
        tb_arr.shape == shape
        and ta_arr.shape == shape
        and q_arr.size <= _SCREEN_SIZE
        # sum|q| <= MAX_ABS_Q and sum|tau| <= MAX_ABS_TORQUE, in one sum
        and (MAX_ABS_TORQUE / MAX_ABS_Q) * sum(map(abs, q_arr.ravel().tolist()))
        + sum(map(abs, tb_arr.ravel().tolist() + ta_arr.ravel().tolist()))
        <= MAX_ABS_TORQUE
    ):
        for name, a, limit in (
            ("q", q_arr, MAX_ABS_Q),
            ("tau_before", tb_arr, MAX_ABS_TORQUE),
            ("tau_after", ta_arr, MAX_ABS_TORQUE),
        ):
            if a.shape != shape:
                raise InvalidInputError(f"{name} has shape {a.shape} but q has shape {shape}")
            _check_values(name, a.reshape(-1, n), limit)
    low, high = TORQUE_STD_RANGE
    sigma: float | np.ndarray | None
    if type(torque_std) is float and low <= torque_std <= high:  # the usual case, fast
        sigma = torque_std
    else:
        sigma = _torque_std(torque_std, n)
    return q_arr, ta_arr - tb_arr, sigma


_SCREEN_SIZE = 64
"""Arrays up to this size are screened by one sum in Python floats; larger ones by NumPy."""


def _check_values(name: str, a: np.ndarray, limit: float) -> None:
    """InvalidInputError naming the (pose, joint) entries of ``a`` (k, n) out of range.

    Out of range: NaN, inf or beyond +-limit.
    """
    bad = ~np.isfinite(a)
    if bad.any():
        where = np.argwhere(bad).tolist()
        raise InvalidInputError(f"{name} contains NaN or inf at (pose, joint) {where}")
    big = np.abs(a) > limit
    if big.any():
        where = np.argwhere(big).tolist()
        raise InvalidInputError(
            f"{name} is beyond +-{limit:g} (no arm's reading) at (pose, joint) {where}"
        )


def check_dtau_cov(dtau_cov: object, rows: int, torque_std: object) -> np.ndarray | None:
    """The lower Cholesky factor L of ``dtau_cov`` (rows, rows) (L L^T = dtau_cov), or None.

    InvalidInputError where it is not a finite, symmetric, positive-definite matrix of the
    stacked torque differences' shape, or where ``torque_std`` is given too.
    """
    if dtau_cov is None:
        return None
    if torque_std is not None:
        raise InvalidInputError(
            "give torque_std (independent readings) or dtau_cov (the differences' full "
            "covariance), not both"
        )
    cov = validate.real_array(dtau_cov, "dtau_cov")
    if cov.shape != (rows, rows):
        raise InvalidInputError(
            f"dtau_cov must have shape ({rows}, {rows}) (k n rows of the stacked torque "
            f"differences, pose-major), got {cov.shape}"
        )
    scale = float(np.max(np.abs(cov))) if cov.size else 0.0
    if not (np.all(np.isfinite(cov)) and np.allclose(cov, cov.T, rtol=1e-9, atol=1e-12 * scale)):
        raise InvalidInputError("dtau_cov must be finite and symmetric")
    try:
        L = np.linalg.cholesky(0.5 * (cov + cov.T))
    except np.linalg.LinAlgError:
        raise InvalidInputError(
            "dtau_cov is not positive definite: every torque difference has some noise of "
            "its own (a covariance of readings is positive definite)"
        ) from None
    diag = np.diag(L)
    if not np.all(diag >= TORQUE_STD_RANGE[0]):
        raise InvalidInputError(
            f"dtau_cov is near singular (a conditional std below {TORQUE_STD_RANGE[0]:g} N m)"
        )
    return L


def _torque_std(torque_std: float | np.ndarray | None, n: int) -> float | np.ndarray | None:
    """The std of each reading: a float for a scalar, an (n,) array per joint, or None."""
    if torque_std is None:
        return None
    low, high = TORQUE_STD_RANGE
    value = validate.real_array(torque_std, "torque_std")
    try:
        sigma = np.broadcast_to(value, (n,)).copy()
    except (TypeError, ValueError):
        raise InvalidInputError(
            f"torque_std must be a scalar or shape ({n},), got {np.shape(torque_std)}"
        ) from None
    if not np.all(np.isfinite(sigma) & (sigma >= low) & (sigma <= high)):
        raise InvalidInputError(
            f"torque_std must be finite and within [{low:g}, {high:g}] N m, got {torque_std}"
        )
    return float(value) if value.ndim == 0 else sigma
