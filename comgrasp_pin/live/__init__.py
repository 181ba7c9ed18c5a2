"""A connected arm, live: plan, move, measure, estimate and set the load (``comgrasp live``).

    protocol.py   the rules, pure: the stops (each pose from both sides), the dynamics
                  factor's cap, when a load may be sent and whether its read-back agrees
    franka.py     a Franka over libfranka's protocol (franky): connect, check, move, read
    session.py    one measurement: the empty run, the payload attached, the loaded run
    franka_sim.py the simulated FR3 (franky-sim, MuJoCo) in its own process, on 127.0.0.1

Needs the ``franka`` extra (franky-control, franky-sim). The robot side (``protocol``,
``franka``, ``session``) imports no MuJoCo; only ``franka_sim``'s server process does.
"""

from comgrasp_pin.live.franka import FrankaArm
from comgrasp_pin.live.franka_sim import FrankaSim, SimPayload, fr3_urdf
from comgrasp_pin.live.session import Recording, measure

__all__ = ["FrankaArm", "FrankaSim", "Recording", "SimPayload", "fr3_urdf", "measure"]
