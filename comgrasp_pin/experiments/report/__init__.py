"""Figures (PNG) and Markdown tables of the two experiments, beside the paper's numbers.

Two groups of objects, never pooled: the paper's six rods (``PAPER_OBJECTS`` of
``comgrasp_pin.simulation.objects`` when it exists, else obj1-obj6) and extra objects
(anything else, e.g. obj7, a hammer whose head carries the CoM off the rod's axis, and
obj8, a thick rod). Tables, comparisons and verdicts take ``objects`` (default: the paper's
six that are in the rows); the figures draw extra objects in panels or places of their own.

Columns that newer runs add are used when present and reported as "not recorded" when
absent: ``pos_std_m`` (the stated standard deviation of ``pos_esti_m``), ``extra_pose``
(the planner measured at one more pose), ``estimator``.

Layer: inside ``experiments``, under the modules that run trials: it reads rows, ``paper``,
``stats`` and ``simulation.objects``, and imports no runner, sweep or reproduce.
"""

from comgrasp_pin.experiments import paper
from comgrasp_pin.experiments.report.accuracy_plot import accuracy_figure, accuracy_series
from comgrasp_pin.experiments.report.accuracy_tables import accuracy_table, method_comparison
from comgrasp_pin.experiments.report.calibration import calibration_table, calibration_z
from comgrasp_pin.experiments.report.calibration_plot import (
    calibration_figure,
    calibration_section,
)
from comgrasp_pin.experiments.report.common import (
    C_BASELINE,
    C_LINE,
    C_OURS,
    C_REGRASP,
    DEFAULT_PAPER_OBJECTS,
    ESTIMATOR_NAMES,
    LINE_LABEL,
    N01_COV68,
    NOT_RECORDED,
    OBJECTS,
    PAPER_RANGE_DEG,
    PUBLISHED_MARKER,
    TARGET_COV95_BIN,
    TARGET_COV95_OVERALL,
    TARGET_RMS_Z,
    TIE_POINTS,
    com_off_axis_m,
    describe,
    estimator_label,
    object_groups,
    paper_objects,
    recorded,
)
from comgrasp_pin.experiments.report.regrasp import (
    TARGET_BELOW_10,
    TARGET_UP_TO_30,
    extra_pose_summary,
    regrasp_figure,
    regrasp_table,
    success_rates,
)
from comgrasp_pin.experiments.report.verdicts import (
    SHORTFALL,
    accuracy_verdict,
    error_source,
    extra_objects_section,
    regrasp_verdict,
    run_summary,
)
from comgrasp_pin.experiments.report.wrist_sensor import wrist_sensor_table
from comgrasp_pin.experiments.stats import wilson_interval

__all__ = [
    "C_BASELINE",
    "C_LINE",
    "C_OURS",
    "C_REGRASP",
    "DEFAULT_PAPER_OBJECTS",
    "ESTIMATOR_NAMES",
    "LINE_LABEL",
    "N01_COV68",
    "NOT_RECORDED",
    "OBJECTS",
    "PAPER_RANGE_DEG",
    "PUBLISHED_MARKER",
    "SHORTFALL",
    "TARGET_BELOW_10",
    "TARGET_COV95_BIN",
    "TARGET_COV95_OVERALL",
    "TARGET_RMS_Z",
    "TARGET_UP_TO_30",
    "TIE_POINTS",
    "accuracy_figure",
    "accuracy_series",
    "accuracy_table",
    "accuracy_verdict",
    "calibration_figure",
    "calibration_section",
    "calibration_table",
    "calibration_z",
    "com_off_axis_m",
    "describe",
    "error_source",
    "estimator_label",
    "extra_objects_section",
    "extra_pose_summary",
    "method_comparison",
    "object_groups",
    "paper",
    "paper_objects",
    "recorded",
    "regrasp_figure",
    "regrasp_table",
    "regrasp_verdict",
    "run_summary",
    "success_rates",
    "wilson_interval",
    "wrist_sensor_table",
]
