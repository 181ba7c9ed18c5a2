"""The phases a procedure announces (``Cell.announce``): a log line, a video's caption.

An announcement is ``"<phase>: <detail>"`` or the phase alone (``MEASURING`` is followed
by the pose's number); the phase is one of ``PHASES`` and lasts until the next
announcement. ``phase_of`` reads it back.
"""

from __future__ import annotations

BASELINE_GRASP = "grasp at the geometric centre"
EMPTY_ARM = "empty arm"
TRIAL_GRASP = "trial grasp"
CAREFUL_LIFT = "careful lift"
LIFT = "lift"
MEASURING = "measuring at pose"  # followed by the pose's number
PUT_BACK = "put back"
PUT_DOWN = "put-down"
REGRASP = "regrasp at the CoM"
CARRY = "carry"
DROP = "drop"


PHASES = (BASELINE_GRASP, EMPTY_ARM, TRIAL_GRASP, CAREFUL_LIFT, LIFT, MEASURING, PUT_BACK,
          PUT_DOWN, REGRASP, CARRY, DROP)  # fmt: skip


def phase_of(announcement: str) -> str:
    """The phase of ``announcement``: the name in ``PHASES`` it begins with, or else its
    text before the first ``:``."""
    head = announcement.split(":", 1)[0].strip()
    for name in sorted(PHASES, key=len, reverse=True):
        if head == name or head.startswith(name + " "):
            return name
    return head


def trial_grasp_at(offset: float) -> str:
    """The trial grasp's announcement, ``offset`` m along the rod from its perceived centre."""
    if offset == 0.0:
        return f"{TRIAL_GRASP}: at the geometric centre"
    return f"{TRIAL_GRASP}: {100 * offset:+.1f} cm from the centre"
