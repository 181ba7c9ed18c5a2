"""LAPACK on small matrices without NumPy's per-call argument checks (3 us of a 10 us estimate).

``eigvalsh`` and ``inv`` are the gufuncs behind ``np.linalg.eigvalsh`` (lower triangle) and
``np.linalg.inv``: the same LAPACK routines, the same results to the bit, on one matrix or
a stack. Unlike NumPy's wrappers they do not raise on a singular matrix (they return NaN or
inf): callers check the conditioning first. Where NumPy lays them out differently, the
public functions stand in.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

eigvalsh: Callable[[np.ndarray], np.ndarray] = np.linalg.eigvalsh
inv: Callable[[np.ndarray], np.ndarray] = np.linalg.inv
try:
    from numpy.linalg import _umath_linalg

    eigvalsh, inv = _umath_linalg.eigvalsh_lo, _umath_linalg.inv
except (ImportError, AttributeError):  # pragma: no cover - another NumPy layout
    pass
