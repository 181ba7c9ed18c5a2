"""The largest magnitudes a robot log's values may have: beyond them no sensor gives them.

Every log reader (the project's CSV, a UR RTDE recording, a ROS 2 bag, the wrench CSV, bag
and RTDE readers) refuses a value past these ceilings, naming its line (or message) and
column (``robot_io.log_files.log_values``). They are not tolerances: a damaged file or a column that
holds another quantity (``1e300`` in a current, a time in nanoseconds) would otherwise flow
through the fit into a confident, wrong payload. So each one is a physical ceiling at least
ten times above the largest reading any real sensor of its kind reports, and a real log is
never refused by them (the real UR10e, Panda and TIAGo logs of ../shared/realdata peak at
1940 s, 3.2 rad, 1.3 rad/s, 144 N m and 18 A).

Re-exported by ``comgrasp_pin.config``; SI units, magnitudes (|x| <= the ceiling).
"""

from __future__ import annotations

MAX_ABS_TIME_S = 1e10
"""A sample's time, s. Clocks in logs are seconds since the epoch (1.7e9 in 2024; 1e10 is the
year 2286) or since the controller started (a UR's ``timestamp``: 1e10 s is 300 years of
uptime). A time in ms or ns since the epoch (1.7e12, 1.7e18) is refused: the logs' times
are seconds."""

MAX_ABS_JOINT_POSITION_RAD = 1e4
"""A joint position, rad (m for a prismatic joint). Revolute arm joints turn within a few
turns (a UR's +-2 pi, 6.3 rad); a continuous joint that winds up keeps counting, and 1e4 rad
is 1600 turns. No linear axis is 10 km long."""

MAX_ABS_JOINT_VELOCITY_RAD_S = 1e4
"""A joint velocity, rad/s (m/s for a prismatic joint). Arm joints move at up to a few rad/s
(a UR's 3.14, a Panda's 2.6); a driver that logs the motor's side sees the gear ratio times
that, at most the 20 000 rpm (2100 rad/s) of the fastest servo motors. 1e4 rad/s is
95 000 rpm."""

MAX_ABS_JOINT_EFFORT = 1e6
"""A joint effort as logged: a joint torque (N m), a prismatic joint's force (N), or a motor
current (A, or mA where a driver publishes that) before drive gains. The largest industrial
arms hold about 1e5 N m at the shoulder (a 1 t payload at 3 m plus the arm's own weight);
servo drives give at most a few hundred A (1e5 mA); no linear axis pushes 100 t."""

MAX_ABS_FORCE_N = 1e6
"""A force/torque sensor's force, N. The largest six-axis sensors sold are rated at about
1e5 N (ATI's Omega331 class); wrist sensors at 1e2 to 1e3 N (a Robotiq FT 300-S 300 N, an
ATI Axia80 500 to 900 N, a UR e-Series' built-in one 50 N)."""

MAX_ABS_TORQUE_NM = 1e5
"""A force/torque sensor's torque, N m. The largest six-axis sensors are rated at several
thousand N m; wrist sensors at 1 to 1e2 N m (an Axia80 20 N m, a UR e-Series' 10 N m)."""
