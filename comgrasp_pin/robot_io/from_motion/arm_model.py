"""The empty arm's own dynamics, identified from a run of any motion (``comgrasp identify-arm``).

A URDF's inertials are a vendor's CAD estimate, and it holds no friction and no sensor
offsets: on a real UR10e the nominal model reads the empty arm as a 0.8 kg payload. Here the
arm's torques are identified from an excitation run, as robot identification does it:

    tau = W_B(q, qd, qdd) beta + F_v qd + F_c tanh(qd / COULOMB_SPEED) + offsets(t)

- W is Pinocchio's joint-torque regressor (``computeJointTorqueRegressor``, 10 parameters
  per link); many of its columns are zero or dependent. The base parameters beta are the
  columns a column-pivoted QR (``scipy.linalg.qr``) keeps on random states, the standard
  numerical route (Gautier 1991; FIGAROH does the same). We use Pinocchio and SciPy rather
  than FIGAROH: the library already holds Pinocchio's model and the weighting, filtering and
  uncertainty machinery, and FIGAROH brings a YAML configuration and plotting we would not use.
- Friction per joint, viscous and Coulomb; offsets and their drift per run, and the
  efforts' delay behind the positions (``motion_system.delay_column``), none of them kept:
  they change between runs and are identified again with the payload.
- A weak prior pulls each base parameter towards the URDF's value (its std is the value
  itself, or a floor): directions the run does not excite stay at the vendor's figure, and
  the covariance stays finite.

What ``--arm-model`` carries into a payload's interval: the identification's delete-a-block
block sandwich replicates (``dynamic_uncertainty``), each pushed through the payload's fit, so
that the arm model's noise and model error reach the payload's parameters replicate by
replicate (a per-parameter widening of the 40-odd correlated base parameters' covariance
overstated the payload's std five times on the Panda). The model's terms are filtered like
the torques (``motion_system``).
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pinocchio as pin

from comgrasp_pin.errors import InvalidInputError, LogError
from comgrasp_pin.estimation import block_sandwich as bs
from comgrasp_pin.estimation import dynamic_uncertainty as du
from comgrasp_pin.robot import RobotModel
from comgrasp_pin.robot_io.from_motion.motion_signals import (
    CUTOFF_HZ,
    MotionSamples,
    motion_samples,
)
from comgrasp_pin.robot_io.from_motion.motion_system import (
    COULOMB_SPEED,
    delay_column,
    fast_signals,
    friction_columns,
    joint_columns,
    lowpassed,
    offset_columns,
    row_noise,
)
from comgrasp_pin.robot_io.log_files.joint_readers import JointLog

PRIOR_FLOOR = {"mass": 0.5, "first": 0.05, "inertia": 0.01}
"""The prior's std where the URDF's base parameter is near zero: kg, kg m, kg m^2."""
QR_TOL = 1e-8
"""A regressor column is a base parameter when QR's diagonal exceeds this share of the largest."""
RANDOM_STATES = 40
"""Random (q, qd, qdd) on which the base columns are chosen (structural, not the run's)."""


@dataclass(frozen=True)
class ArmModel:
    """An arm's identified dynamics.

    Attributes:
        joint_names: the arm's joints, in chain order.
        base_columns: (p,) indices of W's columns that are base parameters.
        params: (p + 2 n,) the base parameters, then viscous (N m s/rad) and Coulomb (N m)
            friction per joint.
        cov: their covariance, the white noise's (Laplace, prior included): for a reader.
        replicates: (B, p + 2 n) block sandwich replicates (``estimation.block_sandwich``):
            how the identification's noise and model error reach a payload estimated with
            this model, replicate by replicate.
        nominal: (p + 2 n,) the URDF's base parameters (zero friction), for comparison.
        residual_rms_Nm: (n,) on the identification run.
        validation: held-out check on the identification run (``Validation.as_dict``).
        gains: (n,) N m/A used to turn currents into torques, or None (torques logged).
        urdf_sha256: the URDF file's hash (the kinematics the model belongs to).
        source: the run's file; duration_s, cutoff_hz: its motion and filter.
    """

    joint_names: tuple[str, ...]
    base_columns: np.ndarray
    params: np.ndarray
    cov: np.ndarray
    replicates: np.ndarray
    nominal: np.ndarray
    residual_rms_Nm: np.ndarray
    validation: dict
    gains: np.ndarray | None
    urdf_sha256: str
    source: str
    duration_s: float
    cutoff_hz: float


def base_columns(robot: RobotModel, seed: int = 0) -> np.ndarray:
    """Indices of the joint-torque regressor's base columns (column-pivoted QR)."""
    from scipy.linalg import qr

    rng = np.random.default_rng(seed)
    lo = np.where(np.isfinite(robot.q_lower), robot.q_lower, -np.pi)
    hi = np.where(np.isfinite(robot.q_upper), robot.q_upper, np.pi)
    rows = []
    for _ in range(RANDOM_STATES):
        q = rng.uniform(lo, hi)
        qd, qdd = rng.normal(size=(2, robot.nq))
        rows.append(pin.computeJointTorqueRegressor(robot.model, robot.data, q, qd, qdd))
    W = np.vstack(rows)
    _, R, piv = qr(W, pivoting=True, mode="economic")
    d = np.abs(np.diag(R))
    return np.sort(piv[: int(np.sum(d > QR_TOL * d[0]))])


def arm_columns(robot: RobotModel, columns: np.ndarray, S: MotionSamples) -> np.ndarray:
    """(k n, p + 2 n) Phi with tau_arm = Phi @ params, rows sample-major."""
    W = np.array([pin.computeJointTorqueRegressor(robot.model, robot.data, q, qd, qdd)
                  for q, qd, qdd in zip(S.q, S.qd, S.qdd)])  # fmt: skip
    k, n = S.q.shape
    fric = joint_columns(friction_columns(S)).reshape(k, n, -1)
    return np.concatenate([W[:, :, columns], fric], axis=2).reshape(k * n, -1)


def nominal_params(robot: RobotModel, columns: np.ndarray) -> np.ndarray:
    """The URDF's base parameters (then zero friction), by least squares on random states."""
    from scipy.linalg import lstsq

    pi = np.concatenate([robot.model.inertias[j].toDynamicParameters()
                         for j in range(1, robot.model.njoints)])  # fmt: skip
    rng = np.random.default_rng(1)
    W = np.vstack([pin.computeJointTorqueRegressor(robot.model, robot.data,
                   *rng.normal(size=(3, robot.nq))) for _ in range(RANDOM_STATES)])  # fmt: skip
    beta = lstsq(W[:, columns], W @ pi)[0]
    return np.concatenate([beta, np.zeros(2 * robot.nq)])


def _prior_std(nominal: np.ndarray, columns: np.ndarray, n: int) -> np.ndarray:
    kinds = columns % 10
    floor = np.where(kinds == 0, PRIOR_FLOOR["mass"],
                     np.where(kinds < 4, PRIOR_FLOOR["first"], PRIOR_FLOOR["inertia"]))  # fmt: skip
    std = np.maximum(np.abs(nominal[: len(columns)]), floor)
    return np.concatenate([std, np.full(2 * n, np.inf)])  # friction: no prior


def identify_arm(
    robot: RobotModel,
    log: JointLog,
    window: tuple[float, float] | None = None,
    cutoff_hz: float = CUTOFF_HZ,
) -> ArmModel:
    """Identify the empty arm's base parameters and friction from a run of any motion.

    Raises:
        MotionLogError: the log cannot give a motion (see ``motion_signals``).
    """
    S = motion_samples(robot, log, window, cutoff_hz)
    k, n = S.q.shape
    cols = base_columns(robot)
    fast = fast_signals(robot, log, window, cutoff_hz)
    Phi = lowpassed(
        fast, cutoff_hz, lambda F: arm_columns(robot, cols, F).reshape(len(F.t), n, -1), S.t
    ).reshape(k * n, -1)
    A_x = np.column_stack([joint_columns(offset_columns(S)), delay_column(fast, S)])
    A = np.column_stack([Phi, A_x])
    b = S.tau.reshape(-1)
    nominal = nominal_params(robot, cols)
    prior_std = np.concatenate([_prior_std(nominal, cols, n), np.full(A_x.shape[1], np.inf)])
    prior_mean = np.concatenate([nominal, np.zeros(A_x.shape[1])])
    sigma = row_noise(np.column_stack([Phi, A_x]), b, k, n)
    w = np.tile(1.0 / sigma, k)
    P_inv = np.where(np.isfinite(prior_std), 1.0 / prior_std**2, 0.0)
    Aw = A * w[:, None]
    H = Aw.T @ Aw + np.diag(P_inv)
    beta = np.linalg.solve(H, Aw.T @ (b * w) + P_inv * prior_mean)
    p = Phi.shape[1]
    laplace = np.linalg.inv(H)[:p, :p]
    residual = (A @ beta - b).reshape(k, n)
    scale = float(np.mean((residual / sigma) ** 2))  # the rows' noise as the residuals say
    blocks = du.contiguous_blocks(k, du.block_count(float(S.t[-1] - S.t[0])))
    replicates = bs.block_sandwich(A, b, w, k, n, blocks, p, (P_inv, prior_mean)).replicates
    cov = scale * laplace
    return ArmModel(
        tuple(robot.joint_names), cols, beta[:p], cov, replicates, nominal,
        np.sqrt(np.mean(residual**2, axis=0)), du.held_out(Phi, A_x, b, w, S.t, k, n).as_dict(),
        None if log.current_gains is None else np.asarray(log.current_gains, float),
        urdf_sha256(robot), log.source, float(S.t[-1] - S.t[0]), S.cutoff_hz,
    )  # fmt: skip


def urdf_sha256(robot: RobotModel) -> str:
    """The robot's URDF file's SHA-256, or "" where it was not built from a file."""
    path = getattr(robot, "urdf_path", None)
    if path is None or not Path(path).is_file():
        return ""
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def check_matches(model: ArmModel, robot: RobotModel, log: JointLog) -> None:
    """Refuse an arm model that belongs to other joints, or to other drive gains."""
    if tuple(model.joint_names) != tuple(robot.joint_names):
        raise InvalidInputError(
            f"the arm model is of the joints {list(model.joint_names)}, this arm's are "
            f"{list(robot.joint_names)}: identify this arm (comgrasp identify-arm)"
        )
    gains = log.current_gains
    same = (model.gains is None and gains is None) or (
        model.gains is not None
        and gains is not None
        and np.allclose(model.gains, np.asarray(gains, float), rtol=1e-9)
    )
    if not same:
        raise InvalidInputError(
            f"the arm model was identified with drive gains {_text(model.gains)}, this log "
            f"is read with {_text(gains)}: use the same --current-gains for both (or "
            "identify the arm again with these)"
        )


def _text(g) -> str:
    return "none (logged torques)" if g is None else np.array2string(np.asarray(g), precision=4)


FORMAT = "comgrasp arm model 1"


def arm_model_dict(model: ArmModel) -> dict:
    """ARM.json: everything ``load_arm_model`` needs, and what a person reads."""
    n = len(model.joint_names)
    std = np.sqrt(np.clip(np.diag(model.cov), 0, None))
    return {
        "format": FORMAT,
        "joint_names": list(model.joint_names),
        "base_columns": model.base_columns.tolist(),
        "params": model.params.tolist(),
        "params_about": "base parameters of Pinocchio's joint-torque regressor's columns "
        "base_columns (10 per link: m, m c, I at the joint), then viscous friction (N m s/rad) "
        "and Coulomb friction (N m) per joint",
        "cov": model.cov.tolist(),
        "replicates": model.replicates.tolist(),
        "nominal_params": model.nominal.tolist(),
        "friction": {"viscous_Nms_per_rad": model.params[-2 * n : -n].tolist(),
                     "coulomb_Nm": model.params[-n:].tolist(),
                     "viscous_std": std[-2 * n : -n].tolist(), "coulomb_std": std[-n:].tolist()},
        "coulomb_speed_rad_s": COULOMB_SPEED,
        "residual_rms_Nm": model.residual_rms_Nm.tolist(),
        "validation": model.validation,
        "current_gains_Nm_per_A": None if model.gains is None else model.gains.tolist(),
        "urdf_sha256": model.urdf_sha256,
        "source": model.source,
        "duration_s": model.duration_s,
        "cutoff_hz": model.cutoff_hz,
    }  # fmt: skip


def load_arm_model(path: str | Path) -> ArmModel:
    """Read ARM.json (``comgrasp identify-arm``).

    Raises:
        LogError: unreadable, not an arm model, or fields of the wrong size.
    """
    try:
        d = json.loads(Path(path).read_text())
    except (OSError, ValueError) as exc:
        raise LogError(f"--arm-model {path}: cannot read it as JSON ({exc})") from None
    if not isinstance(d, dict) or d.get("format") != FORMAT:
        raise LogError(
            f"--arm-model {path}: not an arm model written by comgrasp identify-arm (its "
            f"'format' must be {FORMAT!r})"
        )
    try:
        names = tuple(str(x) for x in d["joint_names"])
        cols = np.array(d["base_columns"], dtype=int)
        params, cov = np.array(d["params"], float), np.array(d["cov"], float)
        replicates = np.array(d["replicates"], float)
        nominal = np.array(d["nominal_params"], float)
        gains = d.get("current_gains_Nm_per_A")
        model = ArmModel(
            names, cols, params, cov, replicates, nominal, np.array(d["residual_rms_Nm"], float),
            dict(d["validation"]), None if gains is None else np.array(gains, float),
            str(d["urdf_sha256"]), str(d["source"]), float(d["duration_s"]),
            float(d["cutoff_hz"]),
        )  # fmt: skip
    except (OSError, ValueError, KeyError, TypeError) as exc:
        raise LogError(
            f"--arm-model {path}: not an arm model written by comgrasp identify-arm ({exc})"
        ) from None
    p = len(cols) + 2 * len(names)
    if (params.shape != (p,) or cov.shape != (p, p) or replicates.ndim != 2
            or replicates.shape[1] != p or not np.all(np.isfinite(replicates))):  # fmt: skip
        raise LogError(f"--arm-model {path}: {len(params)} parameters, {p} expected")
    return model
