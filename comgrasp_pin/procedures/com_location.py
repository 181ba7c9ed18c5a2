"""Where the CoM lies along the held rod according to the trial grasp's readings.

``locate_com`` turns ``HeldReadings`` into the estimates: the torque differences weighed by
their noise (``pair_noise``), the poses stacked with the rod's motion between the side views
(``rod_motion``), the CoM met with the rod's axis, and how well that point is known by
source (``uncertainty.std_parts``). The noise is the sensor's white noise (the ideal
preset's), or the windows' measured spread and the sensor's drift as a full covariance: a
random walk shared by every window, so that two poses' differences whose empty-to-held
intervals overlap in time share that much drift (generalised least squares then takes most
of it out where the poses differ). Pure functions; no ground truth here. N m, m, rad.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from comgrasp_pin.config import (
    DepthLineErrorConfig,
    DepthNoiseConfig,
    TorqueSensorConfig,
    WrenchSensorConfig,
)
from comgrasp_pin.estimation import AxisPrior, ComEstimate, com_along_axis, estimate_com
from comgrasp_pin.estimation.drift import difference_covariance, difference_weights
from comgrasp_pin.perception import SideView
from comgrasp_pin.procedures import uncertainty
from comgrasp_pin.procedures.measurement import HeldReadings
from comgrasp_pin.procedures.rod_motion import depth_agrees, paired_depth_line, rod_motion
from comgrasp_pin.procedures.wrench_readings import JOINT_TORQUES, WrenchRows
from comgrasp_pin.robot import RobotModel


@dataclass(frozen=True)
class ComLocation:
    """Where the CoM lies along the rod, by which path, and how well it is known.

    Attributes:
        estimate: the estimate used; estimate_line: the paper's (one pose, least squares).
        x_com: CoM along the perceived rod from its perceived centre (m); x_line: the
            paper's (the vertical CoM line met with the axis).
        path: "one pose", or "k poses" with k their number (see ``locate_com``).
        std: the standard deviation of the CoM point along the rod (m), from every source
            in ``std_parts`` (``procedures.uncertainty``): estimator, slip, tilt, views.
        shares: with both sources, each one's share of the information on the mass and on
            the CoM along the rod ({source: {"mass": s, "com_along_rod": s}}); else None.
    """

    estimate: ComEstimate
    estimate_line: ComEstimate
    x_com: float
    x_line: float
    path: str
    std: float
    std_parts: dict
    shares: dict | None = None


def locate_com(
    robot: RobotModel,
    held: HeldReadings,
    estimator: str,
    noise: NoiseRule,
    depth_bounds: tuple[float, float],
    calibration: DepthNoiseConfig,
    depth_line: DepthLineErrorConfig | None,
    source: str = JOINT_TORQUES,
    wrench: WrenchSensorConfig | None = None,
) -> ComLocation:
    """The CoM along the rod from the readings.

    The paper's: one pose, least squares, the vertical CoM line met with the rod's axis.
    Ours (``estimator``: "ipopt" adds the side view's ``axis_prior``; "lstsq" is the closed
    form without it): every pose whose view saw the rod, stacked with the rod's motion in
    the jaws since the first (``rod_motion``; a view's depth line is used where it differs
    from the first's within ``depth_bounds``, m and rad: ``depth_agrees``), the 3-D CoM
    projected on the axis; the first pose alone when no other view saw it. ``noise``: how
    the torque differences' noise is known (``pair_noise``). ``calibration``: the
    side camera's stated accuracy and its depth resolution, ``depth_line`` its depth
    line's error model (``uncertainty.std_parts``; None: the slices' scatter alone). A
    payload not measurably above zero: EmptyGripperError. ``source``: the joint torques,
    the wrist sensor's wrench or both (``wrench_readings``; ``wrench``: its data sheet).
    """
    use = [i for i, view in enumerate(held.views) if view is not None]
    pair = pair_noise([held.before[i] for i in use], [held.after[i] for i in use], noise)
    q = np.array([held.after[i].q for i in use])
    tau_a = np.array([held.after[i].tau for i in use])
    tau_b = np.array([held.tau_before[i] for i in use])
    first_view = held.views[use[0]]
    # each later view's depth line from the slices it shares with the first's
    views = [first_view, *(paired_depth_line(first_view, held.views[i]) for i in use[1:])]
    side, T_obj = held.side, held.side.T_ee_obj
    prior = axis_prior(side) if estimator == "ipopt" else None

    rows = None if source == JOINT_TORQUES else WrenchRows.of(robot, held, use, wrench, source)

    def estimate(k: int, method: str, prior: AxisPrior | None, motion=None) -> ComEstimate:
        first = pair.first(k, robot.nq)
        if rows is not None:
            torques = (tau_b[:k], tau_a[:k], first.covariance(k, robot.nq)) if rows.both else None
            return rows.estimate(robot, q[:k], method, prior, motion, torques)
        return estimate_com(robot, q[:k], tau_b[:k], tau_a[:k], method=method,
                            torque_std=first.std, com_prior=prior, payload_motion_ee=motion,
                            dtau_cov=first.cov)  # fmt: skip

    def stacked(views: list, depth: list, slides: list) -> ComEstimate:
        motions = [rod_motion(views[0], v, s, depth=d) for v, d, s in zip(views[1:], depth,
                   slides, strict=True)]  # fmt: skip
        return estimate(len(views), estimator, prior, np.stack([np.eye(4), *motions]))

    def position(views: list, depth: list, slides: list) -> float:
        return com_along_axis(stacked(views, depth, slides), views[0].T_ee_obj)

    est_line = estimate(1, "lstsq", None)
    x_line = com_along_axis(est_line, T_obj)
    est = est_line if prior is None else estimate(1, "ipopt", prior)
    path, depth = "one pose", []
    if len(use) > 1:
        # Several poses, the rod where each view saw it: the CoM is fixed in the rod, so
        # the poses stack with the rod's motion since the first (the grasp's compliance, a
        # slip).
        depth = [depth_agrees(side, v, *depth_bounds) for v in views[1:]]
        est, path = stacked(views, depth, [0.0] * len(depth)), f"{len(use)} poses"
    off_axis = None
    if path == "one pose" and prior is None:
        # the closed form meets the vertical CoM line with the axis: a CoM off the axis by
        # h moves that point by h tan(theta) (the prior's std is the h the view allows)
        off_axis = axis_prior(side).std * abs(np.tan(side.theta))
    parts = uncertainty.std_parts(est, views, depth, depth_bounds, position, calibration,
                                  off_axis, depth_line)  # fmt: skip
    std = float(np.sqrt(sum(v * v for v in parts.values())))
    shares = None
    if rows is not None and rows.both:
        k = est.n_poses
        shares = rows.shares(robot, q[:k], pair.first(k, robot.nq).covariance(k, robot.nq), T_obj)
    return ComLocation(est, est_line, com_along_axis(est, T_obj), x_line, path, std, parts,
                       shares)  # fmt: skip


def axis_prior(side: SideView) -> AxisPrior:
    """The prior on the CoM from the side view: near the rod's axis. The CoM lies within the
    rod's cross-section, which the side camera sees reach ``off_axis`` from the axis; half of
    that is one standard deviation across the axis, combined with how well the axis itself
    was located (``axis_std``)."""
    std = float(np.hypot(0.5 * side.off_axis, side.axis_std))
    return AxisPrior.from_rod(side.T_ee_obj, std)


@dataclass(frozen=True)
class NoiseRule:
    """How the torque differences' noise is known (``pair_noise``).

    Attributes:
        std_from: "spec" or "measured" (``TrialConfig.torque_std_from``).
        torque: the sensor's data sheet (``noise_std``, ``drift_std``).
        modelled: tau_before is the model's, not measured (``TrialConfig.tau_before``).
    """

    std_from: str
    torque: TorqueSensorConfig
    modelled: bool


@dataclass(frozen=True)
class PairNoise:
    """The noise of the stacked torque differences tau_after - tau_before, for
    ``estimate_com``: one of ``std`` (each reading's std, N m, the differences independent)
    or ``cov`` ((k n, k n) covariance of the differences, pose-major, N m^2).
    """

    std: float | None
    cov: np.ndarray | None

    def covariance(self, k: int, n: int) -> np.ndarray:
        """(k n, k n) the first ``k`` poses' differences' covariance (a difference of two
        readings of ``std`` each where no full covariance is known)."""
        if self.cov is not None:
            return self.cov[: k * n, : k * n]
        return 2.0 * float(self.std) ** 2 * np.eye(k * n)

    def first(self, k: int, n: int) -> PairNoise:
        """The noise of the first ``k`` poses' differences (``n`` joints)."""
        return self if self.cov is None else PairNoise(None, self.cov[: k * n, : k * n])

    def subset(self, poses: list[int], n: int) -> PairNoise:
        """The noise of the differences of ``poses`` only."""
        if self.cov is None:
            return self
        rows = np.concatenate([np.arange(i * n, (i + 1) * n) for i in poses])
        return PairNoise(None, self.cov[np.ix_(rows, rows)])


def drift_cov(before: list, after: list, drift_std: float) -> np.ndarray:
    """(k n, k n) covariance of the k differences' (after - before) white noise and drift
    (``estimation.drift``). Each difference is its held window minus its empty window;
    where ``before`` is None (tau_before from the model, carried by the measured poses'
    mean offset), minus the mean of the measured poses' empty windows."""
    measured = [b for b in before if b is not None]
    windows = [*after, *measured]
    count = iter(range(len(measured)))
    weights = difference_weights([None if b is None else next(count) for b in before],
                                 len(measured))  # fmt: skip
    spans = [(float(m.time), float(m.duration)) for m in windows]
    white = np.array([np.asarray(m.std_error, dtype=float) for m in windows])
    return difference_covariance(spans, white, weights, drift_std)


def pair_noise(before: list, after: list, rule: NoiseRule) -> PairNoise:
    """The noise of the torque differences for the estimator.

    ``before``, ``after``: the TorqueMeasurements at each pose (``before`` None where the
    model gave tau_before). ``rule.std_from``: "spec", the sensor's white noise over the
    samples averaged (the ideal preset's; ``pair_std``); "measured", the windows' spread
    and the sensor's drift (``drift_std``, from its data sheet) with its correlation across
    poses and windows (``drift_cov``), where every time is known and some empty window was
    measured; else per joint as ``pair_std``.
    """
    timed = all(np.isfinite(m.time) for m in [*before, *after] if m is not None)
    if rule.std_from == "measured" and timed and any(b is not None for b in before):
        return PairNoise(None, drift_cov(before, after, rule.torque.drift_std))
    std = pair_std(before, after, rule)
    if isinstance(std, float):
        return PairNoise(std, None)
    return PairNoise(None, np.diag(np.tile(2.0 * std**2, len(after))))


def pair_std(before: list, after: list, rule: NoiseRule) -> float | np.ndarray:
    """The std of each averaged reading (N m; scalar, or (6,) per joint) for the estimator.

    ``before``, ``after``: the TorqueMeasurements at each pose (``before`` None where the
    model gave tau_before). ``rule.std_from``: "spec", the sensor's white noise
    (``noise_std``) over the samples averaged (the ideal preset's; with tau_before
    ``modelled`` a difference has one reading's); "measured", per joint, the windows'
    spread and the sensor's drift (``drift_std``, from its data sheet) over the time between
    the empty and the held window: a random walk adds drift^2 * elapsed to a difference.
    """
    torque, modelled = rule.torque, rule.modelled
    if rule.std_from == "spec":
        n_std = torque.noise_std / np.sqrt(after[0].n_samples)
        return max(n_std * (np.sqrt(0.5) if modelled else 1.0), 1e-6)
    variances = []
    for b, a in zip(before, after, strict=True):
        if b is None:  # one reading: its variance is the difference's
            variances.append(0.5 * a.std_error**2)
            continue
        elapsed = abs(a.time - b.time)
        diff = b.std_error**2 + a.std_error**2 + torque.drift_std**2 * elapsed
        variances.append(0.5 * diff)
    return np.maximum(np.sqrt(np.mean(variances, axis=0)), 1e-6)
