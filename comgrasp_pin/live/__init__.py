"""A connected arm, live: plan, move, measure, estimate and set the load (``comgrasp live``).

    protocol.py   the rules, pure: the stops (each pose from both sides) and their order,
                  a planned motion's waypoints within the dynamics factor, the factor's
                  cap, when a load may be sent and whether its read-back agrees
    franka.py     a Franka over libfranka's protocol (franky): connect, check, move, play,
                  read
    session.py    one measurement: the empty run, the payload attached, the loaded run,
                  at rest or along a planned motion

Needs the ``franka`` extra (franky-control, franky-sim). It imports no MuJoCo: the simulated
FR3 it talks to with ``--sim`` is the simulation's (``simulation.franka_sim``, in its own
process on 127.0.0.1).
"""

from comgrasp_pin.live.franka import FrankaArm
from comgrasp_pin.live.session import Recording, measure, measure_motion

__all__ = ["FrankaArm", "Recording", "measure", "measure_motion"]
