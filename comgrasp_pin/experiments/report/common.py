"""What the report's parts share: object groups, labels, colours, small helpers.

Rows of trials that ended in an internal error (``internal_errors.is_internal_error``: a bug, not
the world's failure) are no outcome: ``rows_of``, through which every table, figure and
verdict takes its rows, leaves them out, so they are in no count, rate or mean, and
``internal_error_note`` names them (the run summary says it).
"""

from __future__ import annotations

import functools
import re
import textwrap
from collections import Counter
from collections.abc import Sequence
from statistics import NormalDist

import numpy as np

from comgrasp_pin.experiments import paper
from comgrasp_pin.experiments.internal_errors import INTERNAL_ERROR, is_internal_error

DEFAULT_PAPER_OBJECTS = ("obj1", "obj2", "obj3", "obj4", "obj5", "obj6")
OBJECTS = DEFAULT_PAPER_OBJECTS  # kept for callers of the old name
PAPER_RANGE_DEG = 30.0  # the paper's accuracy figure stops here
NOT_RECORDED = "not recorded"

# Calibration targets (the project's issue): 95 % coverage overall and per bin, rms z.
TARGET_COV95_OVERALL = (0.93, 0.97)
TARGET_COV95_BIN = 0.90
TARGET_RMS_Z = (0.9, 1.1)
N01_COV68 = 2.0 * NormalDist().cdf(1.0) - 1.0  # 0.6827: N(0, 1) inside ±1σ
TIE_POINTS = 0.1  # method comparison: a grasp is a tie when the two differ by <= this (points)

# Colours and markers that stay apart in grey-scale too: ours dark blue, solid line, filled
# circles; the paper's method in our world orange, dashed line, hollow squares; the paper's
# published values black hollow triangles (obj1) and diamonds (obj6), no line.
C_OURS, C_LINE = "#1b4f8a", "#e0701b"
C_BASELINE, C_REGRASP = "#f4b183", "#2e75b6"
PUBLISHED_MARKER = {"obj1": "^", "obj6": "D"}

ESTIMATOR_NAMES = {
    "ipopt": "IPOPT, two poses, axis prior",
    "lstsq": "least squares, two poses",
}
LINE_LABEL = f"paper's method ({paper.METHOD}), our world"


# --- rows, columns and object groups ------------------------------------------------------


def as_float(value) -> float:
    try:
        return float(value)
    except (TypeError, ValueError):
        return float("nan")


def without_errors(rows: Sequence[dict]) -> list[dict]:
    return [r for r in rows if not r.get("error")]


def outcomes(rows: Sequence[dict]) -> list[dict]:
    """The rows that are outcomes of a trial: all but those of an internal error."""
    return [r for r in rows if not is_internal_error(r)]


def internal_error_note(rows: Sequence[dict], shown: int = 10) -> str:
    """A sentence naming the trials of ``rows`` that ended in an internal error, and saying
    that they are left out of every count, rate and mean; "" when there are none."""
    bad = [r for r in rows if is_internal_error(r)]
    if not bad:
        return ""
    names = [
        f"{r.get('object', '?')} trial {r.get('trial', '?')} ({r.get('method', '?')}): "
        + str(r["error"]).removeprefix(f"{INTERNAL_ERROR}: ")
        for r in bad[:shown]
    ]
    more = f"; and {len(bad) - shown} more" if len(bad) > shown else ""
    return (
        f"{len(bad)} trial(s) ended in an {INTERNAL_ERROR} (an exception that is not a "
        "ComGraspError: a bug, not a failed trial) and are left out of every count, rate and "
        f"mean: {'; '.join(names)}{more}. Their tracebacks are in `NAME.tracebacks.txt` "
        "beside each CSV; `--resume` runs them again."
    )


def column_values(rows: Sequence[dict], name: str) -> np.ndarray:
    return np.array([as_float(r.get(name)) for r in rows], float)


def recorded(rows: Sequence[dict], name: str) -> bool:
    """Whether any row carries a finite value in column ``name``."""
    return bool(np.isfinite(column_values(rows, name)).any()) if rows else False


def natural_key(name: str) -> tuple:
    return tuple(int(t) if t.isdigit() else t for t in re.split(r"(\d+)", name))


@functools.lru_cache(maxsize=1)
def paper_objects() -> tuple[str, ...]:
    """The paper's six objects: ``PAPER_OBJECTS`` of the simulation when it exists."""
    try:
        from comgrasp_pin.simulation import objects as sim_objects

        names = getattr(sim_objects, "PAPER_OBJECTS", None)
    except Exception:  # no simulator here: the paper's objects are obj1-obj6
        names = None
    return tuple(names) if names else DEFAULT_PAPER_OBJECTS


def object_groups(rows: Sequence[dict]) -> tuple[list[str], list[str]]:
    """(the paper's objects, extra objects) present in ``rows``, each in a stable order."""
    present = {str(r["object"]) for r in rows if r.get("object")}
    ours = paper_objects()
    return [o for o in ours if o in present], sorted(present - set(ours), key=natural_key)


def objects_in(rows: Sequence[dict], objects: Sequence[str] | None) -> list[str]:
    """``objects`` as given, or the paper's objects in ``rows``."""
    return list(objects) if objects is not None else object_groups(rows)[0]


def rows_of(rows: Sequence[dict], objects: Sequence[str]) -> list[dict]:
    """The rows of ``objects`` that are outcomes (no internal error's: see the docstring)."""
    keep = set(objects)
    return [r for r in rows if r.get("object") in keep and not is_internal_error(r)]


def _spec(obj: str):
    try:
        from comgrasp_pin.simulation.objects import get_object

        return get_object(obj)
    except Exception:  # unknown object or no simulator: nothing to describe
        return None


def describe(obj: str, width: int = 42) -> str:
    """The object's short description (from its model), or "" when unknown."""
    spec = _spec(obj)
    if spec is None:
        return ""
    text = str(spec.description).split(":")[0]
    return textwrap.shorten(text, width=width, placeholder="…")


def com_off_axis_m(obj: str) -> float | None:
    """Distance of the object's CoM from the handle's axis in its model (m), or None."""
    spec = _spec(obj)
    if spec is None:
        return None
    c = np.asarray(spec.com(), float)
    return float(np.hypot(c[1], c[2]))


def estimator_label(rows: Sequence[dict]) -> str:
    """Legend name of our estimate, from the rows' ``estimator`` column."""
    names = Counter(str(r["estimator"]) for r in rows if r.get("estimator"))
    if not names:
        return "ours: two poses (estimator not recorded)"
    if len(names) == 1:
        (name,) = names
        return f"ours: {ESTIMATOR_NAMES.get(name, name)}"
    return "ours: " + ", ".join(f"{ESTIMATOR_NAMES.get(k, k)} × {n}" for k, n in names.items())


def abs_tilts(rows: Sequence[dict]) -> np.ndarray:
    return np.abs(column_values(rows, "theta_deg"))


def load_pyplot():
    """pyplot, on the Agg backend unless pyplot was already imported (a notebook's inline
    backend, a user's GUI): the report's figures are written to files and closed, and must not
    switch off the caller's figures."""
    import sys

    import matplotlib

    if "matplotlib.pyplot" not in sys.modules:
        matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def bin_label(lo: float, hi: float) -> str:
    return f"{lo:g}–{hi:g}"


def percent(x: float, digits: int = 1) -> str:
    return f"{100 * x:.{digits}f} %" if np.isfinite(x) else "–"


# --- experiment 1: accuracy ------------------------------------------------------------------


def compress_tilt(x):
    """The accuracy figure's x axis: linear to 30 deg, a third as wide beyond."""
    x = np.asarray(x, float)
    return np.where(x <= PAPER_RANGE_DEG, x, PAPER_RANGE_DEG + (x - PAPER_RANGE_DEG) / 3.0)


def expand_tilt(u):
    u = np.asarray(u, float)
    return np.where(u <= PAPER_RANGE_DEG, u, PAPER_RANGE_DEG + (u - PAPER_RANGE_DEG) * 3.0)
