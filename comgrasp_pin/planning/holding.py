"""How much moment the jaws hold: the grasp's friction budget about the jaw axis.

The box pads touch a rod at their two edges, ``GRIPPER.pad_half[0]`` either side of the
grasp point along the rod; each contact carries friction mu F, and the patch adds a
torsional mu_t F. Held level with its CoM a lever e from the jaws, a rod of mass m loads
them with m g e: it turns once that exceeds the budget (in practice at 0.6-0.8 of it: the
lift's acceleration adds load).
"""

from __future__ import annotations

import numpy as np

from comgrasp_pin.workcell import GRAVITY_WORLD, GRIPPER


def holding_moment(grip_force: float, pad_friction: tuple[float, ...]) -> float:
    """Nominal moment (N m) the jaws resist about their axis: 2 F (mu a + mu_t), with F the
    force of each finger (N), a the pad's half width along the rod (m) and (mu, mu_t) the
    pads' sliding and torsional friction (-, m)."""
    mu, mu_t = pad_friction[0], pad_friction[1]
    return 2.0 * grip_force * (mu * GRIPPER.pad_half[0] + mu_t)


def holding_lever(mass: float, grip_force: float, pad_friction: tuple[float, ...]) -> float:
    """Grasp-to-CoM distance (m) at which the weight of a rod of ``mass`` (kg), held level
    in the cell's gravity (``workcell.GRAVITY_WORLD``), reaches ``holding_moment``."""
    return holding_moment(grip_force, pad_friction) / (mass * float(np.linalg.norm(GRAVITY_WORLD)))
