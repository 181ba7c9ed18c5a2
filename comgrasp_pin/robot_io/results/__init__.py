"""What an estimate gives back, and whether to trust it.

The payload-estimate result type, RESULT.json and the summary lines, the verdict
rules and the gate for payload files. It imports no estimator: every path uses it.
"""

from comgrasp_pin.estimation.trust import inertia_verdict, judge, require_identified
from comgrasp_pin.robot_io.results.estimate_result import (
    AtRest,
    Inertia,
    JointTorques,
    Motion,
    PayloadEstimate,
    Wrench,
)
from comgrasp_pin.robot_io.results.report import summary
from comgrasp_pin.robot_io.results.result_file import read_result, result_dict, write_result

__all__ = [
    "PayloadEstimate",
    "AtRest",
    "Motion",
    "Inertia",
    "JointTorques",
    "Wrench",
    "result_dict",
    "write_result",
    "read_result",
    "summary",
    "judge",
    "inertia_verdict",
    "require_identified",
]
