"""Drive gains: a joint's torque from its motor's current, N m per A, with their uncertainty.

A Universal Robots arm logs motor currents, not joint torques; torque = K * current per
joint, K the drive gain (gear ratio times the motor's torque constant). Nominal gains are
known to about 10 %, which moves an identified mass by as much: the gains' covariance enters
the estimate's covariance.

Given as ``K1,...,Kn`` on the command line (``--current-gains``, with ``--gain-std R``, the
relative std), or as the JSON that ``comgrasp calibrate-gains`` writes (``gains_json``)::

    {"gains_Nm_per_A": [K1, ..., Kn], "cov": [[...n...], ...n rows...],
     "joint_names": [J1, ..., Jn]}  # joint_names optional; other keys ignored
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from comgrasp_pin import file_checks, validate
from comgrasp_pin.errors import InvalidInputError

GAINS_KEY = "gains_Nm_per_A"
COV_KEY = "cov"
NAMES_KEY = "joint_names"


@dataclass(frozen=True)
class Gains:
    """Drive gains, one per arm joint in the chain's order.

    Attributes:
        values: (n,) gains, N m per A, positive.
        cov: (n, n) their covariance, (N m per A)^2, symmetric positive semi-definite
            (zeros where the gains' uncertainty was not given).
        source: where they come from, for reports: "command line, gain std 10 %", or the
            JSON's path.
        joint_names: the joints they belong to (a calibrate-gains JSON names them), or None.
    """

    values: np.ndarray
    cov: np.ndarray
    source: str = ""
    joint_names: tuple[str, ...] | None = None

    def __post_init__(self) -> None:
        """Check the shapes and values; both arrays become read-only float copies."""
        values = np.array(validate.real_array(self.values, "Gains.values"), dtype=float)
        cov = np.array(validate.real_array(self.cov, "Gains.cov"), dtype=float)
        _check_values(values, len(values), self.source)
        cov = _checked_cov(cov, len(values), self.source)
        if self.joint_names is not None and len(self.joint_names) != len(values):
            raise InvalidInputError(
                f"drive gains ({self.source}): {len(self.joint_names)} joint names for "
                f"{len(values)} gains; give one name per gain, or none"
            )
        for a in (values, cov):
            a.flags.writeable = False
        object.__setattr__(self, "values", values)
        object.__setattr__(self, "cov", cov)
        if self.joint_names is not None:
            object.__setattr__(self, "joint_names", tuple(str(j) for j in self.joint_names))

    @property
    def std(self) -> np.ndarray:
        """(n,) the gains' standard deviations, N m per A."""
        return np.sqrt(np.diag(self.cov))


def _check_values(values: np.ndarray, n: int, source: str) -> None:
    if values.shape != (n,):
        raise InvalidInputError(
            f"drive gains ({source}): {n} gains expected (one per arm joint, N m per A), "
            f"got shape {values.shape}"
        )
    if not np.all(np.isfinite(values)) or not np.all(values > 0):
        raise InvalidInputError(
            f"drive gains ({source}): every gain must be a positive finite number of N m per "
            f"A (a UR10e's are about 8 to 11); got {values.tolist()}"
        )


def _checked_cov(cov: np.ndarray, n: int, source: str) -> np.ndarray:
    """``cov`` symmetrised, after checking it is (n, n), finite, symmetric and PSD."""
    what = f"drive gains ({source}): the covariance"
    if cov.shape != (n, n):
        raise InvalidInputError(f"{what} must be {n} x {n} ((N m/A)^2), got shape {cov.shape}")
    if not np.all(np.isfinite(cov)):
        raise InvalidInputError(f"{what} has NaN or inf entries; give finite numbers")
    scale = max(float(np.max(np.abs(cov))), 1e-300)
    if not np.allclose(cov, cov.T, rtol=1e-9, atol=1e-9 * scale):
        raise InvalidInputError(f"{what} is not symmetric; give cov[i][j] == cov[j][i]")
    cov = (cov + cov.T) / 2
    lowest = float(np.linalg.eigvalsh(cov)[0]) if n else 0.0
    if lowest < -1e-9 * scale:
        raise InvalidInputError(
            f"{what} is not positive semi-definite (an eigenvalue {lowest:.3g}); give a "
            "covariance, e.g. the diagonal of the gains' variances"
        )
    return cov


GAIN_CORRELATION = 0.5
"""The correlation between two joints' gain errors given as ``--gain-std``: half of each
gain's variance is shared by all joints. A drive gain is a motor's torque constant times its
gear ratio and efficiency; the torque constant's temperature dependence (about -0.1 %/K for
NdFeB magnets) and a data sheet's figure for a whole motor family err alike on every joint,
the unit-to-unit spread does not. On the real UR10e the gains calibrated on a known mass are
all above the published ones (1 to 32 %, shoulder and elbow 13 and 20 %): mostly a common
error. 0.5 is the middle between independent (0) and one common error (1); --gain-correlation
sets it, and docs/robot.md gives the UR10e's interval under both ends."""


def relative_cov(
    values: np.ndarray, gain_std: float, correlation: float = GAIN_CORRELATION
) -> np.ndarray:
    """(n, n) the gains' covariance: each known to ``gain_std`` of itself, errors correlated."""
    s = gain_std * np.asarray(values, dtype=float)
    n = len(s)
    return np.outer(s, s) * (correlation * np.ones((n, n)) + (1 - correlation) * np.eye(n))


def _check_gain_std(gain_std: float | None) -> None:
    if gain_std is not None and not (np.isfinite(gain_std) and gain_std >= 0):
        raise InvalidInputError(
            f"--gain-std {gain_std}: the gains' relative standard deviation must be a finite "
            "number >= 0, e.g. 0.1 for nominal gains known to 10 %"
        )


def parse_gains(
    text: str,
    n: int,
    gain_std: float | None,
    joint_names: Sequence[str] | None = None,
    correlation: float = GAIN_CORRELATION,
) -> Gains:
    """The drive gains of ``text``: ``K1,...,Kn`` (N m per A) or a calibrate-gains JSON's path.

    With numbers, cov = (gain_std K)(gain_std K)^T times the correlation matrix
    (``relative_cov``); ``gain_std`` None gives a zero covariance and says in ``source``
    that the gains' uncertainty is not given. With a JSON, its ``cov`` is taken, unless
    ``gain_std`` is given: that REPLACES it by the relative one (the JSON's gains, the
    user's uncertainty).

    Args:
        text: comma-separated numbers, or the path of a JSON (``gains_json``'s format).
        n: the arm's number of joints.
        gain_std: the gains' relative standard deviation (0.1: 10 %), or None.
        correlation: between two joints' relative gain errors, 0 to 1 (``GAIN_CORRELATION``).
        joint_names: the robot's joints in chain order; a JSON naming others is refused.

    Raises:
        InvalidInputError: not n gains (n is said), a gain not positive and finite,
            ``gain_std`` negative or not finite; the JSON unreadable, a key missing, a cov
            that is not a symmetric PSD n x n matrix, or joint names that differ from the
            robot's (both listed).
    """
    _check_gain_std(gain_std)
    if not (np.isfinite(correlation) and 0 <= correlation <= 1):
        raise InvalidInputError(
            f"--gain-correlation {correlation}: a correlation between 0 (independent gain "
            "errors) and 1 (one error common to all joints)"
        )
    parts = [p.strip() for p in str(text).split(",")]
    numbers = _numbers(parts)
    if numbers is None and ("," in text or not _looks_like_a_file(text)):
        raise InvalidInputError(
            f"--current-gains {text!r}: give {n} comma-separated numbers K1,...,K{n} (N m "
            "per A) or the path of the JSON that comgrasp calibrate-gains writes"
        )
    if numbers is not None:
        if len(numbers) != n:
            raise InvalidInputError(
                f"--current-gains {text!r}: {n} gains expected (one per arm joint, N m per A), "
                f"got {len(numbers)}"
            )
        values = np.array(numbers)
        _check_values(values, n, "--current-gains")
        if gain_std is None:
            return Gains(
                values,
                np.zeros((n, n)),
                "command line, gain std not given: the gains' uncertainty is not in the covariance",
            )
        source = f"command line, gain std {100 * gain_std:g} %, correlation {correlation:g}"
        return Gains(values, relative_cov(values, gain_std, correlation), source)
    return _from_json(Path(text), n, gain_std, joint_names, correlation)


def _numbers(parts: list[str]) -> list[float] | None:
    try:
        return [float(p) for p in parts]
    except ValueError:
        return None


def _looks_like_a_file(text: str) -> bool:
    try:
        return text.lower().endswith(".json") or Path(text).exists()
    except (OSError, ValueError):  # a name with a NUL byte, too long
        return False


def _from_json(
    path: Path, n: int, gain_std: float | None, names: Sequence[str] | None, correlation: float
) -> Gains:
    data = file_checks.read_json(path, "gains JSON", InvalidInputError)
    where = f"gains JSON {path}"
    if not isinstance(data, dict) or GAINS_KEY not in data or COV_KEY not in data:
        raise InvalidInputError(
            f"{where} lacks the keys {GAINS_KEY!r} ({n} gains, N m per A) and {COV_KEY!r} "
            f"({n} x {n}); write it with comgrasp calibrate-gains (or give K1,...,K{n})"
        )
    try:
        values = np.array(data[GAINS_KEY], dtype=float)
        cov = np.array(data[COV_KEY], dtype=float)
    except (TypeError, ValueError):
        raise InvalidInputError(
            f"{where}: {GAINS_KEY!r} must be a list of {n} numbers and {COV_KEY!r} a list of "
            f"{n} lists of {n} numbers"
        ) from None
    _check_values(values, n, str(path))
    json_names = data.get(NAMES_KEY)
    if json_names is not None:
        if not isinstance(json_names, list) or not all(isinstance(j, str) for j in json_names):
            raise InvalidInputError(f"{where}: {NAMES_KEY!r} must be a list of {n} joint names")
        json_names = tuple(json_names)
        if names is not None and json_names != tuple(names):
            raise InvalidInputError(
                f"{where} holds the gains of the joints {list(json_names)}, not of this "
                f"robot's {list(names)}: calibrate the gains on this arm's URDF"
            )
    if gain_std is not None:
        cov = relative_cov(values, gain_std, correlation)
        source = f"{path} (its covariance replaced by --gain-std {gain_std:g})"
    else:
        source = str(path)
    return Gains(values, _checked_cov(cov, n, str(path)), source, json_names)


def gains_json(
    values: np.ndarray | Sequence[float],
    cov: np.ndarray | Sequence[Sequence[float]],
    joint_names: Sequence[str] | None,
    **extra: object,
) -> dict:
    """The calibrate-gains JSON (a dict for ``json.dump``) that ``parse_gains`` reads back.

    Args:
        values: (n,) gains, N m per A.
        cov: (n, n) their covariance, (N m per A)^2.
        joint_names: the n joints in chain order, or None (the key is then left out).
        **extra: further keys (how they were calibrated, a known mass, the logs); they must
            not be the format's own keys.

    Raises:
        InvalidInputError: bad gains or covariance (as ``Gains``), or an extra key that is
            one of the format's own.
    """
    clash = {GAINS_KEY, COV_KEY, NAMES_KEY} & set(extra)
    if clash:
        raise InvalidInputError(
            f"gains_json: {sorted(clash)} are the format's own keys; "
            "pass them as values, cov and joint_names"
        )
    gains = Gains(
        np.asarray(values, dtype=float),
        np.asarray(cov, dtype=float),
        "gains_json",
        None if joint_names is None else tuple(joint_names),
    )
    out: dict = {GAINS_KEY: gains.values.tolist(), COV_KEY: gains.cov.tolist()}
    if gains.joint_names is not None:
        out[NAMES_KEY] = list(gains.joint_names)
    return {**out, **extra}
