"""What the robot does and sees, with no ground truth: the trial grasp (a measurement), pick
and place, putting a rod back. They drive a ``Cell`` (``cell``: the robot's skills and eyes)
and announce their phases (``phases``: a log line, a video caption).

Layer: imports ``planning``, ``perception``, ``motion``, ``estimation``, ``robot`` and the
shared modules; never ``simulation``, so a real robot's ``Cell`` runs them unchanged.
"""
