"""The arm's motion: top-down IK, quintic trajectories, Fourier excitation paths.

Layer: imports only ``robot``, ``geometry``, ``workcell`` and ``errors``; no simulator.
"""
