"""Scoring against the truth: what the robot measured, set beside what the simulator knows.

The procedures never see any of this; the experiments and the tests do.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from comgrasp_pin.geometry import invert_transform
from comgrasp_pin.procedures.measurement import TrialMeasurement
from comgrasp_pin.simulation.objects import ObjectState
from comgrasp_pin.workcell import DROP_BOX_INNER_HALF, DROP_BOX_XY, PICK_AREA

DROP_BOX_MARGIN = 0.01
"""A delivered rod's CoM lies at least this far inside the drop box's walls (m) ..."""
DROP_BOX_MAX_Z = 0.12
"""... and below this height (m): it rests in the box."""


@dataclass(frozen=True)
class TrialScore:
    """A trial grasp's measurement against the truth when the side camera saw the rod.

    Attributes:
        pos_real: true CoM along the rod from its geometric centre (m).
        pos_esti: the estimated CoM point expressed along the TRUE rod axis (m).
        pos_esti_line: the same for the paper's single-pose estimate.
        theta_true: the rod's true tilt in the jaws (rad).
        mass_real: kg. grasp_offset: where the jaws held the rod (true, m). length: m.
        pos_esti_by_source: {source: pos_esti} of the locations from the readings' other
            sources (``TrialMeasurement.by_source``; NaN where that source failed).
    """

    pos_real: float
    pos_esti: float
    pos_esti_line: float
    theta_true: float
    mass_real: float
    grasp_offset: float
    length: float
    pos_esti_by_source: dict = field(default_factory=dict)

    @property
    def accuracy(self) -> float:
        """The paper's metric, 1 - 5 |pos_esti - pos_real| / l."""
        return 1.0 - 5.0 * abs(self.pos_esti - self.pos_real) / self.length

    @property
    def accuracy_line(self) -> float:
        """The paper's metric for the paper's single-pose estimate."""
        return 1.0 - 5.0 * abs(self.pos_esti_line - self.pos_real) / self.length

    def accuracy_of(self, source: str) -> float:
        """The paper's metric for the estimate from ``source`` (NaN where it failed)."""
        return 1.0 - 5.0 * abs(self.pos_esti_by_source[source] - self.pos_real) / self.length


def score_trial(
    trial: TrialMeasurement, truth: ObjectState, grasp_offset_true: float, length: float
) -> TrialScore:
    """Score ``trial`` against the rod's ``truth`` at the moment it was measured."""
    T_obj_world = invert_transform(truth.T_world_obj)

    def along_true_rod(x: float) -> float:
        p_com_world = trial.T_world_ee @ trial.T_ee_obj @ np.array([x, 0.0, 0.0, 1.0])
        return float((T_obj_world @ p_com_world)[0])

    T_ee_obj_true = invert_transform(trial.T_world_ee) @ truth.T_world_obj
    return TrialScore(
        pos_real=truth.pos_real,
        pos_esti=along_true_rod(trial.x_com_obj),
        pos_esti_line=along_true_rod(trial.x_com_line),
        theta_true=float(np.arctan2(-T_ee_obj_true[2, 0], T_ee_obj_true[0, 0])),
        mass_real=truth.mass,
        grasp_offset=grasp_offset_true,
        length=length,
        pos_esti_by_source={
            source: along_true_rod(loc.x_com) if not isinstance(loc, str) else float("nan")
            for source, loc in trial.by_source.items()
        },
    )


def in_drop_box(p_world_com: np.ndarray) -> bool:
    """The rod (its CoM at ``p_world_com`` (3,)) rests inside the drop box."""
    x, y = DROP_BOX_XY
    hx, hy = (round(h - DROP_BOX_MARGIN, 9) for h in DROP_BOX_INNER_HALF)
    p = p_world_com
    return bool(abs(p[0] - x) < hx and abs(p[1] - y) < hy and p[2] < DROP_BOX_MAX_Z)


def where_is(p_world_com: np.ndarray) -> str:
    """Where the rod's CoM is, in words (for the record of a failed episode)."""
    x, y, z = p_world_com
    if in_drop_box(p_world_com):
        return "in the drop box"
    if z < -0.05:
        return "on the floor"
    x0, x1, y0, y1 = PICK_AREA
    if z < 0.08 and x0 <= x <= x1 and y0 <= y <= y1:
        return "on the table"
    return f"at ({x:.2f}, {y:.2f}, {z:.2f}) m"
