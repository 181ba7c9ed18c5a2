"""Checking the estimator's inputs: shapes, finiteness, options. Errors say what is valid."""

from __future__ import annotations

import numpy as np

from comgrasp_pin import validate
from comgrasp_pin.errors import InvalidInputError
from comgrasp_pin.robot import RobotModel

METHODS = ("lstsq", "ipopt")
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
    from comgrasp_pin.estimation.prior import AxisPrior

    if method not in METHODS:
        raise InvalidInputError(f"unknown method {method!r}; valid methods are {METHODS}")
    check_rcond(rcond)
    if loss not in LOSSES:
        raise InvalidInputError(f"unknown loss {loss!r}; valid losses are {LOSSES}")
    if loss == "huber" and torque_std is None:
        raise InvalidInputError(
            "loss='huber' needs torque_std: its threshold huber_delta is counted in standard "
            "deviations of a torque difference"
        )
    validate.number(huber_delta, "huber_delta", low=0.0, low_open=True)
    if com_prior is not None and not isinstance(com_prior, AxisPrior):
        raise InvalidInputError(f"com_prior must be an AxisPrior or None, got {com_prior!r}")
    if method == "lstsq" and (loss != "l2" or com_prior is not None):
        raise InvalidInputError(
            "a robust loss or a com_prior needs method='ipopt' (lstsq is the closed form of "
            "the plain least squares)"
        )


def check_rcond(rcond: object) -> float:
    """``rcond`` as a float in (0, 1); InvalidInputError otherwise."""
    return validate.number(rcond, "rcond", low=0.0, high=1.0, low_open=True, high_open=True)


def validate_inputs(
    robot: RobotModel,
    q: np.ndarray,
    tau_before: np.ndarray,
    tau_after: np.ndarray,
    torque_std: float | np.ndarray | None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """(Q (k, n), dtau (k, n), sigma (n,) or None) from the raw inputs, or a clear error."""
    if not isinstance(robot, RobotModel):
        raise InvalidInputError(f"robot must be a RobotModel, got {type(robot).__name__}")
    n = robot.nq
    arrays = {}
    for name, value in (("q", q), ("tau_before", tau_before), ("tau_after", tau_after)):
        try:
            arrays[name] = np.asarray(value, dtype=float)
        except (TypeError, ValueError) as exc:
            raise InvalidInputError(f"{name} is not a numeric array: {exc}") from None
    shape = arrays["q"].shape
    if arrays["q"].ndim not in (1, 2) or shape[-1] != n or (len(shape) == 2 and shape[0] < 1):
        raise InvalidInputError(
            f"q must have shape ({n},) for one pose or (k, {n}) for k >= 1 poses (the robot "
            f"has {n} joints), got {shape}"
        )
    for name, a in arrays.items():
        if a.shape != shape:
            raise InvalidInputError(f"{name} has shape {a.shape} but q has shape {shape}")
        bad = ~np.isfinite(a)
        if bad.any():
            where = np.argwhere(bad.reshape(-1, n)).tolist()
            raise InvalidInputError(f"{name} contains NaN or inf at (pose, joint) {where}")
    sigma = None
    if torque_std is not None:
        try:
            sigma = np.broadcast_to(np.asarray(torque_std, dtype=float), (n,)).copy()
        except (TypeError, ValueError):
            raise InvalidInputError(
                f"torque_std must be a scalar or shape ({n},), got {np.shape(torque_std)}"
            ) from None
        if not np.all(np.isfinite(sigma) & (sigma > 0)):
            raise InvalidInputError(f"torque_std must be finite and > 0, got {torque_std}")
    Q = arrays["q"].reshape(-1, n)
    dtau = (arrays["tau_after"] - arrays["tau_before"]).reshape(-1, n)
    if not np.all(np.isfinite(dtau)):
        raise InvalidInputError("tau_after - tau_before overflows (values too large)")
    return Q, dtau, sigma
