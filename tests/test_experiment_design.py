"""The accuracy experiment's design: target tilts, the calibrated curves and their
inversion, and where the grasps go relative to the true CoM."""

import json

import numpy as np
import pytest

from comgrasp_pin.config import EpisodeConfig
from comgrasp_pin.experiments import design, tilt_calibration, tilt_curves
from comgrasp_pin.experiments.design import (
    invert_curve,
    lever_for_tilt,
    load_calibration,
    target_tilt,
    target_tilts,
    tilt_curve,
    wrap_tilt,
)
from comgrasp_pin.experiments.tilt_curves import monotone, step_levers
from comgrasp_pin.experiments.trials import (
    ACCURACY_COM_RANGE,
    ACCURACY_GRASP_OFFSET,
    ACCURACY_LEVER_RANGE,
    accuracy_grasp,
    trial_seed,
)
from comgrasp_pin.planning.holding import holding_lever
from comgrasp_pin.simulation.objects import OBJECTS
from comgrasp_pin.workcell import GRIPPER

PAPER_TRIALS = 50


def test_holding_lever_is_the_pads_moment_over_the_weight():
    # 2 fingers x 15 N x (0.8 x 12 mm + 2 mm) = 0.348 N m; a 0.5 kg rod weighs 4.905 N.
    assert np.isclose(holding_lever(0.5, 15.0, (0.8, 0.002, 1e-4)), 0.348 / 4.905)
    assert np.isclose(holding_lever(1.0, 30.0, (0.8, 0.002)), 2 * 0.348 / 9.81)


@pytest.mark.parametrize("run_seed", [0, 1, 7, 123])
def test_targets_fill_every_5_deg_bin_below_30_deg_at_the_papers_size(run_seed):
    targets = target_tilts(PAPER_TRIALS, run_seed)
    assert np.all((targets >= 0.0) & (targets <= 90.0))
    counts, _ = np.histogram(targets, bins=np.arange(0.0, 30.1, 5.0))
    assert np.all(counts >= 7), counts
    rest = targets[targets >= 30.0]
    assert len(rest) == PAPER_TRIALS - counts.sum() and len(rest) >= 5
    assert rest.max() - rest.min() > 30.0  # spread over 30-90 deg, not piled up
    # Within a bin the targets spread out: no two of a bin's 7+ closer than 0.2 deg.
    for lo in range(0, 30, 5):
        inside = np.sort(targets[(targets >= lo) & (targets < lo + 5)])
        assert np.min(np.diff(inside)) > 0.2


def test_a_trials_target_depends_on_its_index_and_run_seed_only():
    # the same trial index -> the same target, whatever the number of trials (--resume)
    np.testing.assert_array_equal(target_tilts(20, 3), target_tilts(PAPER_TRIALS, 3)[:20])
    assert target_tilt(17, 3) == target_tilt(17, 3)
    assert target_tilt(17, 3) != target_tilt(17, 4)
    # fewer trials still cover every bin evenly: 25 trials give 3-4 targets per bin
    counts, _ = np.histogram(target_tilts(25), bins=np.arange(0.0, 30.1, 5.0))
    assert np.all(counts >= 3)


def test_wrap_tilt_is_modulo_180_deg():
    for deg, wrapped in [(-179.99, 0.01), (174.8, -5.2), (30.0, 30.0), (-95.0, 85.0)]:
        assert np.degrees(wrap_tilt(np.radians(deg))) == pytest.approx(wrapped, abs=1e-9)


def test_monotone_is_pool_adjacent_violators():
    # by hand: 5 and 3 violate the order and pool to their mean 4
    np.testing.assert_allclose(monotone([0.0, 5.0, 3.0, 10.0]), [0.0, 4.0, 4.0, 10.0])
    np.testing.assert_allclose(monotone([3.0, 2.0, 1.0]), [2.0, 2.0, 2.0])
    np.testing.assert_allclose(monotone([0.0, 1.0, 2.0]), [0.0, 1.0, 2.0])


def test_inversion_by_hand_on_a_curve_with_a_plateau_and_a_step():
    levers, tilts = [0.3, 0.5, 0.6, 0.7, 0.8], [0.0, 0.0, 10.0, 50.0, 60.0]
    assert invert_curve(levers, tilts, 0.0) == 0.3  # the first lever that reaches it
    assert invert_curve(levers, tilts, 5.0) == pytest.approx(0.55)  # linear
    assert invert_curve(levers, tilts, 20.0, gap_deg=20.0) == 0.6  # step: the nearer end
    assert invert_curve(levers, tilts, 40.0, gap_deg=20.0) == 0.7
    assert invert_curve(levers, tilts, 20.0, gap_deg=45.0) == pytest.approx(0.625)
    assert invert_curve(levers, tilts, 55.0) == pytest.approx(0.75)
    assert invert_curve(levers, tilts, 89.0) == 0.8  # beyond the curve: its end
    with pytest.raises(ValueError, match="must not decrease"):
        invert_curve(levers, [0.0, 5.0, 3.0, 10.0, 20.0], 4.0)


SIDES = (1.0, -1.0)


def test_every_object_is_calibrated_with_a_monotone_curve_per_side_within_the_lever_range():
    objects = load_calibration()["objects"]
    assert set(objects) == set(OBJECTS)
    for name in objects:
        for side in SIDES:
            levers, tilts = tilt_curve(name, side)
            assert np.all(np.diff(levers) > 0) and np.all(np.diff(tilts) >= 0)
            assert ACCURACY_LEVER_RANGE[0] <= levers[0]
            assert levers[-1] <= ACCURACY_LEVER_RANGE[1]
            # the monotone curve is the median of the raw tilts pooled over neighbouring
            # levers (pooled by hand here), made monotone
            raw = objects[name][design.side_key(side)]["abs_tilt_deg"]
            pooled = tilt_curves.pooled_median(levers, raw)  # by hand below
            np.testing.assert_allclose(tilts, monotone(pooled), atol=2e-3)
            # holds level first, turns past the paper's range later
            assert tilts[0] < 2.0 and tilts[-1] > 35.0


@pytest.mark.parametrize("side", SIDES)
@pytest.mark.parametrize("name", sorted(OBJECTS))
def test_the_inversion_is_monotone_and_hits_calibrated_points_exactly(name, side):
    levers, tilts = tilt_curve(name, side)
    grid = np.linspace(0.0, 90.0, 1801)
    inverse = np.array([lever_for_tilt(name, t, side) for t in grid])
    assert np.all(np.diff(inverse) >= 0)
    assert levers[0] <= inverse.min() and inverse.max() <= levers[-1]
    rising = np.flatnonzero(np.diff(tilts) > 0) + 1  # first points reaching their tilt
    for i in rising:
        assert lever_for_tilt(name, tilts[i], side) == levers[i]


def test_accuracy_grasps_lie_on_the_handle_at_the_calibrated_lever_from_the_com():
    config = EpisodeConfig()
    all_sides = set()
    for name, obj in OBJECTS.items():
        lever = holding_lever(obj.mass, config.motion.grip_force, config.world.pad_friction)
        handle = obj.parts[0]
        sides = []
        for k in range(PAPER_TRIALS):
            seed = trial_seed(0, name, k)
            pos_real, offset = accuracy_grasp(name, seed, config)
            assert ACCURACY_COM_RANGE[0] * obj.length <= abs(pos_real) + 1e-12
            assert abs(pos_real) <= ACCURACY_COM_RANGE[1] * obj.length + 1e-12
            assert abs(offset) <= ACCURACY_GRASP_OFFSET * obj.length + 1e-12
            # both pads on the handle
            half_pad = GRIPPER.pad_half[0]
            assert handle.x0 <= offset - half_pad and offset + half_pad <= handle.x1
            # the lever the design asked for, on the centre's side of the CoM
            side = np.sign(pos_real)
            sides.append(side)
            ratio = lever_for_tilt(name, target_tilt(k, 0), side)
            ratio = np.clip(ratio, *ACCURACY_LEVER_RANGE)
            assert abs(offset - pos_real) == pytest.approx(ratio * lever, abs=1e-9)
            assert np.sign(pos_real - offset) == side
        all_sides.update(sides)
        # The same seed gives the same grasp (baseline/regrasp comparisons, --resume).
        seed = trial_seed(2, name, 3)
        assert accuracy_grasp(name, seed, config) == accuracy_grasp(name, seed, config)
        assert accuracy_grasp(name, seed, config) != accuracy_grasp(name, seed + 1, config)
    assert all_sides == {1.0, -1.0}  # the CoM on either side of the centre, as designed


def test_a_higher_target_never_gets_a_shorter_lever():
    targets = np.sort(target_tilts(PAPER_TRIALS))
    for name in OBJECTS:
        for side in SIDES:
            ratios = np.array([lever_for_tilt(name, t, side) for t in targets])
            assert np.all(np.diff(ratios) >= 0)


@pytest.mark.slow
def test_a_calibrated_grasp_settles_at_its_recorded_tilt():
    """The calibration is current: one of its grasps, run again, settles where it did."""
    curve = load_calibration()["objects"]["obj4"]["+x"]
    i = int(np.argmin(np.abs(np.array(curve["median_abs_tilt_deg"]) - 15.0)))
    lever = curve["lever_ratio"][i]
    task = {"object": "obj4", "lever": lever, "side": 1.0,
            "seed": tilt_calibration.calibration_seed("obj4", lever, 0, 1.0)}  # fmt: skip
    row = tilt_calibration.tilt_trial(task)
    assert not row["dropped"]
    assert abs(row["tilt_deg"]) == pytest.approx(curve["abs_tilt_deg"][i][0], abs=1.0)


def test_the_side_whose_curve_reaches_the_target_is_chosen(tmp_path):
    # +x jumps from 1 to 40 deg between two levers; -x climbs steadily: a 15 deg target
    # goes to -x, at the lever its curve gives by hand (0.6 + 0.1 * (15 - 10) / 20)
    jump = {"lever_ratio": [0.5, 0.6, 0.61, 0.9], "tilt_deg": [0.0, 1.0, 40.0, 60.0]}
    steady = {"lever_ratio": [0.5, 0.6, 0.7, 0.9], "tilt_deg": [0.0, 10.0, 30.0, 60.0]}
    curve = {"+x": jump, "-x": steady}
    path = tmp_path / "calibration.json"
    path.write_text(json.dumps({"objects": {"obj4": curve}}))
    for u in (0.1, 0.9):
        side, lever = design.side_and_lever("obj4", 15.0, u, str(path))
        assert side == -1.0 and lever == pytest.approx(0.625)
    # where both reach it alike, u decides, half and half
    flat = {"lever_ratio": [0.5, 0.6, 0.7, 0.8, 0.9], "tilt_deg": [0.0, 15.0, 30.0, 45.0, 60.0]}
    path.write_text(json.dumps({"objects": {"obj4": {"+x": flat, "-x": flat}}}))
    load_calibration.cache_clear()
    assert design.side_and_lever("obj4", 37.5, 0.2, str(path)) == (1.0, pytest.approx(0.75))
    assert design.side_and_lever("obj4", 37.5, 0.8, str(path)) == (-1.0, pytest.approx(0.75))
    load_calibration.cache_clear()


def test_weighted_median_by_hand():
    assert tilt_curves.weighted_median([3.0, 1.0, 2.0], [1.0, 1.0, 1.0]) == 2.0
    assert tilt_curves.weighted_median([1.0, 2.0], [1.0, 1.0]) == 1.5  # half and half
    assert tilt_curves.weighted_median([1.0, 10.0], [3.0, 1.0]) == 1.0


def test_pooled_median_weights_levers_by_their_share_of_the_window():
    # by hand, window 0.74 +- 0.015: 0.74 is nearest over [0.725, 0.7405] (0.0155 of 0.03),
    # the three refined levers past the step share the rest, 0.70 none
    levers = [0.70, 0.74, 0.741, 0.742, 0.743]
    shares = tilt_curves.lever_shares(levers, 0.74, 0.015)
    np.testing.assert_allclose(shares * 0.03, [0.0, 0.0155, 0.001, 0.001, 0.0125], atol=1e-12)
    tilts = [[10.0], [18.0, 18.0], [70.0], [70.0], [70.0]]
    pooled = tilt_curves.pooled_median(levers, tilts)
    # 18 deg holds 0.517 of the weight: the step is not moved before 0.74 (an unweighted
    # median of the window's grasps, 18, 18, 70, 70, 70, would say 70)
    assert pooled[1] == 18.0
    assert pooled[0] == 10.0 and pooled[-1] == 70.0


def test_step_levers_bisect_steps_only_down_to_the_minimum_step():
    # by hand: 18 -> 68 deg between 0.74 and 0.76 is a step (> GAP_DEG 20), 0 -> 10 not
    levers, tilts = [0.6, 0.7, 0.74, 0.76, 0.8], [0.0, 10.0, 18.0, 68.0, 70.0]
    assert step_levers(levers, tilts) == [0.75]
    assert step_levers(levers, tilts, gap_deg=5.0) == [0.65, 0.72, 0.75]
    # neighbours closer than MIN_STEP are not split again
    assert step_levers([0.75, 0.75 + 0.9 * tilt_curves.MIN_STEP], [18.0, 68.0]) == []
    assert step_levers([0.75, 0.75 + 1.1 * tilt_curves.MIN_STEP], [18.0, 68.0]) != []


def _fake_tilt(threshold: float):
    """A rod that settles at 20 deg x (lever - 0.6) / 0.15 up to ``threshold`` and swings to
    70 deg beyond: a step the calibration must find."""

    def trial(task):
        r = float(task["lever"])
        tilt = 70.0 if r > threshold else max(0.0, 20.0 * (r - 0.6) / 0.15)
        return {**task, "tilt_deg": -tilt if task["side"] < 0 else tilt, "dropped": False}

    return trial


def test_calibrate_refines_each_step_and_merges_into_the_file(tmp_path, monkeypatch):
    out = tmp_path / "cal.json"
    old = {"made": {"run": "old"}, "objects": {"obj5": {"kept": True}}}
    out.write_text(json.dumps(old))
    monkeypatch.setattr(tilt_calibration, "tilt_trial", _fake_tilt(0.7537))
    data = tilt_calibration.calibrate(["obj4"], out, seeds=[0], workers=1, dense=4, refine=4)
    assert json.loads(out.read_text()) == data
    assert data["objects"]["obj5"] == {"kept": True}  # other objects and runs kept
    assert [r.get("run") for r in data["runs"]] == ["old", None]
    for key in ("+x", "-x"):
        curve = data["objects"]["obj4"][key]
        r, t = np.array(curve["lever_ratio"]), np.array(curve["median_abs_tilt_deg"])
        # the step is bracketed by 4 bisections of the dense grid's 0.75-0.77 (its rise
        # runs 0.65-0.85 in 4 levers, 0.04 apart: 0.73, 0.77, then 0.75, 0.76, 0.755, ...)
        below, above = r[t < 30].max(), r[t > 60].min()
        assert below <= 0.7537 < above and above - below <= 0.04 / 2**4 + 1e-9
        assert t[r == below][0] == pytest.approx(20.0 * (below - 0.6) / 0.15, abs=1e-3)
        # the design's curve is pooled over LEVER_SCATTER: the step is smeared that far
        tilts = np.array(curve["tilt_deg"])
        assert np.all(tilts[r < 0.7537 - tilt_curves.POOL_WIDTH] < 30)
