"""Lay a held rod back on the table when the trial grasp cannot measure it.

When the side camera cannot trust its view of the held rod (``UntrustedImageError``: a real
camera's noise where a steeply hanging handle is fitted), the trial grasp is given up like
one whose rod turned in the jaws: the rod is laid back on the table's put-down spot (not
where it was grasped: a steeply hanging rod laid down there may end at the table's edge,
where the top view cannot measure it) and grasped again
(``pick_and_place.trial_with_retry``), towards the end that went down. The jaws let go
where the rod, toppling about its low end, comes to lie on the spot
(``planning.put_down.put_back_jaws_xy``), not above the spot: a steep rod let go there
lies half its length beyond it.
"""

from __future__ import annotations

import numpy as np

from comgrasp_pin.motion.ik import grasp_frame
from comgrasp_pin.planning.put_down import put_back_jaws_xy
from comgrasp_pin.procedures.cell import Cell, SlipWatch
from comgrasp_pin.workcell import PICK_AREA, PUT_DOWN_XY


def release_height_above_grasp(length: float, centre_hint: float, tilt: float,
                               margin: float) -> float:  # fmt: skip
    """How far above the grasp height (m) the jaws let go of a rod of ``length`` (m) held
    ``centre_hint`` m from its centre and hanging ``tilt`` rad from level, so that its lower
    end is ``margin`` m above the table: the end farthest from the jaws reaches
    (length / 2 + |centre_hint|) sin(tilt) below them."""
    reach = 0.5 * length + abs(centre_hint)
    return reach * abs(np.sin(tilt)) + margin


def put_back(cell: Cell, grasp, length: float, centre_hint: float, watch: SlipWatch,
             duration: float, table_margin: float, area_margin: float) -> None:  # fmt: skip
    """Carry the held rod, as it hangs, to where it comes to lie on the put-down spot
    (``put_back_jaws_xy``, at the largest tilt the watch saw, its ends ``area_margin`` m
    inside the pick area); lower it until its lower end is ``table_margin`` m above the
    table (``grasp``, the GraspPose it was grasped at, gives the height of the jaws on the
    table); let go and retreat, each move taking ``duration`` s."""
    signed = watch.monitor.largest_tilt() if watch.monitor.times else 0.0
    release_z = grasp_frame(grasp)[2, 3] + release_height_above_grasp(
        length, centre_hint, abs(signed), table_margin)  # fmt: skip
    T = cell.robot.ee_pose(cell.q_des)
    T[:2, 3] = put_back_jaws_xy(PUT_DOWN_XY, T[:3, 0], signed, length, centre_hint, PICK_AREA,
                                area_margin)  # fmt: skip
    cell.move_linear(T.copy(), duration)
    T[2, 3] = release_z
    cell.place(T, duration)
