"""Payload mass and CoM from static joint torques (Pinocchio, NumPy, CasADi; no simulator).

The regressor, the ``ComEstimate`` type, ``estimate_com`` (one least-squares path and
IPOPT), the CoM on the rod's axis, the whole payload's inertial
fit.

Layer: imports only ``robot`` and the shared modules (``geometry``, ``validate``,
``errors``), so it runs on any serial arm's torques, simulated or real.
"""

from comgrasp_pin.estimation.estimate import ComEstimate
from comgrasp_pin.estimation.estimator import estimate_com
from comgrasp_pin.estimation.prior import AxisPrior
from comgrasp_pin.estimation.rod_axis import com_along_axis

__all__ = [
    "AxisPrior",
    "ComEstimate",
    "com_along_axis",
    "estimate_com",
]
