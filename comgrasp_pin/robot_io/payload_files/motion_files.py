"""An excitation motion out: JSON, CSV, a URScript servoj program, a ROS 2 JointTrajectory.

- JSON (``motion_dict``): the series, the samples, the limits, the condition numbers and
  every setting.
- CSV: ``time`` (s) and, per joint J, ``J.position``, ``J.velocity``, ``J.acceleration``
  (the log columns of ``robot_io.log_files.joint_readers``), one row per sample.
- URScript: ``movej`` to the start, then one ``servoj(q, 0, 0, t, lookahead_time, gain)``
  per control period ``t`` (UR's script manual: t = 0.008 s on CB3, 0.002 s on e-Series;
  lookahead_time 0.03-0.2 s, gain 100-2000), then ``stopj``. A 6-joint UR arm only.
- ROS 2: a ``trajectory_msgs/msg/JointTrajectory`` as YAML (joint_names; points with
  positions, velocities, accelerations, time_from_start {sec, nanosec}) every ``period_s``
  from the first period on (the arm must be at the start, where the point at 0 would be),
  ending at rest: for a joint_trajectory_controller (the topic, or the ``trajectory`` of a
  FollowJointTrajectory goal).
"""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np

from comgrasp_pin.errors import InvalidInputError, OutputError
from comgrasp_pin.estimation.payload_regressor import PARAMETER_NAMES
from comgrasp_pin.planning.excitation import ExcitationMotion
from comgrasp_pin.planning.measurement_poses import UR_JOINTS
from comgrasp_pin.robot_io.payload_files.controller_files import write_text

SERIES = "q(t) = q0 + sum_l a_l/(w l) sin(w l t) - b_l/(w l) (cos(w l t) - 1), w = 2 pi/period"


def motion_dict(m: ExcitationMotion) -> dict:
    """The motion's JSON: series, samples, limits, condition numbers, settings."""
    return {
        "joint_names": list(m.joint_names),
        "ee_frame": m.ee_frame,
        "duration_s": m.duration_s,
        "fourier": {
            "formula": SERIES,
            "period_s": m.series.period_s,
            "q0_rad": m.series.q0.tolist(),
            "a_rad_s": m.series.a.tolist(),
            "b_rad_s": m.series.b.tolist(),
        },  # fmt: skip
        "condition_number": m.condition_number,
        "condition_number_si": m.condition_number_si,
        "parameter_names": list(PARAMETER_NAMES),
        "parameter_scale": m.parameter_scale.tolist(),
        "limits": {
            "q_lower_rad": m.q_lower.tolist(),
            "q_upper_rad": m.q_upper.tolist(),
            "velocity_rad_s": m.velocity_limit.tolist(),
            "acceleration_rad_s2": m.acceleration_limit.tolist(),
        },  # fmt: skip
        "peak_velocity_share": m.peak_velocity_share.tolist(),
        "peak_acceleration_share": m.peak_acceleration_share.tolist(),
        "min_height_m": m.min_height_m,
        "gravity_m_s2": m.gravity.tolist(),
        "settings": dataclasses.asdict(m.settings),
        "solver_status": list(m.solver_status),
        "plan_time_s": m.plan_time_s,
        "samples": {
            "time_s": m.t.tolist(),
            "q_rad": m.q.tolist(),
            "qd_rad_s": m.qd.tolist(),
            "qdd_rad_s2": m.qdd.tolist(),
        },  # fmt: skip
    }


def write_json(m: ExcitationMotion, path: str | Path) -> Path:
    """Write ``motion_dict(m)`` to ``path``."""
    return write_text(path, json.dumps(motion_dict(m), indent=1) + "\n")


def write_csv(m: ExcitationMotion, path: str | Path) -> Path:
    """Write the samples: ``time``, then ``J.position``, ``J.velocity``, ``J.acceleration``."""
    header = ["time"] + [f"{n}.{f}" for f in ("position", "velocity", "acceleration")
                         for n in m.joint_names]  # fmt: skip
    path = Path(path)
    try:
        np.savetxt(path, np.column_stack([m.t, m.q, m.qd, m.qdd]), delimiter=",",
                   header=",".join(header), comments="", fmt="%.10g")  # fmt: skip
    except OSError as exc:
        raise OutputError(f"cannot write the CSV {path}: {exc}") from None
    return path


def _times(m: ExcitationMotion, period_s: float) -> np.ndarray:
    """Times period_s, 2 period_s, ... up to and including the motion's end (s)."""
    if not 0 < period_s <= 0.1:
        raise InvalidInputError(f"the output period must be in (0, 0.1] s, got {period_s}")
    count = int(round(m.duration_s / period_s))
    return np.arange(1, count + 1) * (m.duration_s / count)


def urscript_program(
    m: ExcitationMotion,
    period_s: float = 0.008,
    lookahead_time: float = 0.1,
    gain: float = 300.0,
    a_movej: float = 0.5,
    v_movej: float = 0.3,
) -> str:
    """A URScript program: movej to the start, one servoj per ``period_s``, stopj."""
    if len(m.joint_names) != UR_JOINTS:
        raise InvalidInputError(
            f"a URScript servoj program needs a {UR_JOINTS}-joint UR arm; this one has "
            f"{len(m.joint_names)} joints (use the ROS 2 or CSV output)"
        )
    t = _times(m, period_s)
    q = m.series.evaluate(t)[0]
    fmt = lambda v: "[" + ", ".join(f"{x:.6f}" for x in v) + "]"  # noqa: E731
    lines = [
        "# excitation motion planned by comgrasp_pin (comgrasp plan-motion): "
        f"{m.duration_s:g} s, scaled condition number {m.condition_number:.1f}",
        f"# record /joint_states (positions, velocities, efforts); servoj every {period_s:g} s",
        "def comgrasp_excitation():",
        f"  movej({fmt(m.series.q0)}, a={a_movej:g}, v={v_movej:g})",
        *(f"  servoj({fmt(qi)}, 0, 0, {period_s:g}, {lookahead_time:g}, {gain:g})" for qi in q),
        f"  stopj({a_movej:g})",
        "end",
        "comgrasp_excitation()",
        "",
    ]
    return "\n".join(lines)


def ros2_trajectory_yaml(m: ExcitationMotion, period_s: float = 0.02) -> str:
    """The motion as a trajectory_msgs/msg/JointTrajectory in YAML, a point every period_s."""
    t = _times(m, period_s)
    q, qd, qdd = m.series.evaluate(t)
    qd[-1] = qdd[-1] = 0.0  # at rest (rounding): the controller refuses a moving end
    fmt = lambda v: "[" + ", ".join(f"{x:.9g}" for x in v) + "]"  # noqa: E731
    out = [
        "# trajectory_msgs/msg/JointTrajectory planned by comgrasp_pin (comgrasp plan-motion);",
        f"# move the arm to the start first: {fmt(m.series.q0)} (rad)",
        "joint_names: [" + ", ".join(m.joint_names) + "]",
        "points:",
    ]
    for ti, qi, vi, ai in zip(t, q, qd, qdd):
        ns = int(round(ti * 1e9))
        out += [f"  - positions: {fmt(qi)}", f"    velocities: {fmt(vi)}",
                f"    accelerations: {fmt(ai)}",
                f"    time_from_start: {{sec: {ns // 10**9}, nanosec: {ns % 10**9}}}"]  # fmt: skip
    return "\n".join(out) + "\n"


def write_urscript(m: ExcitationMotion, path: str | Path, **options) -> Path:
    """Write ``urscript_program(m, **options)`` to ``path``."""
    return write_text(path, urscript_program(m, **options))


def write_ros2(m: ExcitationMotion, path: str | Path, **options) -> Path:
    """Write ``ros2_trajectory_yaml(m, **options)`` to ``path``."""
    return write_text(path, ros2_trajectory_yaml(m, **options))


def read_motion(path: str | Path, joint_names) -> tuple[np.ndarray, ...]:
    """A motion JSON of ``write_json`` (comgrasp plan-motion) for the arm of ``joint_names``.

    Returns:
        (t, q, qd, qdd): its samples, (k,) s from 0, (k, n) rad, rad/s, rad/s^2.

    Raises:
        InvalidInputError: not such a JSON, another arm's joints, samples not finite or times
            not increasing.
    """
    try:
        d = json.loads(Path(path).read_text())
        s = d["samples"]
        t, q, qd, qdd = (np.asarray(s[k], dtype=float)
                         for k in ("time_s", "q_rad", "qd_rad_s", "qdd_rad_s2"))  # fmt: skip
        names = tuple(d["joint_names"])
    except (OSError, ValueError, KeyError, TypeError) as exc:
        raise InvalidInputError(f"{path}: not a motion of comgrasp plan-motion ({exc})") from None
    if names != tuple(joint_names):
        raise InvalidInputError(
            f"{path}: a motion of the joints {list(names)}, not of this arm's "
            f"{list(joint_names)}: plan it for this arm's URDF"
        )
    n = len(names)
    shapes_ok = t.ndim == 1 and len(t) >= 2 and all(a.shape == (len(t), n) for a in (q, qd, qdd))
    if not shapes_ok or not all(np.all(np.isfinite(a)) for a in (t, q, qd, qdd)):
        raise InvalidInputError(f"{path}: samples must be finite, time (k,) and q, qd, qdd "
                                f"(k, {n}) with k >= 2")  # fmt: skip
    if np.any(np.diff(t) <= 0) or t[0] != 0:
        raise InvalidInputError(f"{path}: sample times must start at 0 s and increase")
    return t, q, qd, qdd
