import math

import numpy as np
import pytest

from comgrasp_pin.experiments.paper import paper_accuracy_at, paper_accuracy_bins
from comgrasp_pin.experiments.stats import (
    CALIBRATION_BINS_DEG,
    bin_masks,
    bin_series,
    binned_calibration,
    binned_mean,
    calibration,
    coverage,
    mean_ci,
    paired_difference,
    slope_through_origin,
    t_quantile,
    wilson_interval,
    z_scores,
)


def test_wilson_interval_known_values():
    # Reference values computed by hand from the Wilson formula: 8/10 -> (0.4902, 0.9433).
    lo, hi = wilson_interval(8, 10)
    assert abs(lo - 0.4902) < 1e-3 and abs(hi - 0.9433) < 1e-3
    assert wilson_interval(0, 20)[0] == 0.0 and wilson_interval(20, 20)[1] == 1.0


def test_binned_mean():
    rows = binned_mean(np.array([1, 2, 6, 31]), np.array([1.0, 3.0, 5.0, 7.0]), (0, 5, 10, 40))
    assert rows[0] == (0, 5, 2.0, 2) and rows[1] == (5, 10, 5.0, 1) and rows[2] == (10, 40, 7.0, 1)


def test_bins_are_half_open_but_the_last_holds_its_top_edge():
    masks = bin_masks(np.array([0.0, 5.0, 10.0, 90.0, 91.0]), (0, 5, 10, 90))
    assert [list(np.flatnonzero(m)) for _, _, m in masks] == [[0], [1], [2, 3]]


def test_paper_values_interpolate():
    assert paper_accuracy_at("obj1", 0.1) == 98.7
    assert abs(paper_accuracy_at("obj6", 30.8) - 59.1) < 1e-12
    assert paper_accuracy_at("obj3", 5.0) is None
    # Bin centres: 1.25 deg lies between the paper's 0.1 (98.7) and 3.2 (97.7); 37.5 is past
    # its last point (30.8); objects 2-5 have no curve.
    obj1 = paper_accuracy_bins("obj1", (0.0, 2.5, 30.0, 45.0))
    assert obj1[0] == pytest.approx(98.7 + (97.7 - 98.7) * (1.25 - 0.1) / (3.2 - 0.1))
    assert obj1[2] is None
    assert paper_accuracy_bins("obj4", (0.0, 2.5)) == [None]


def test_t_quantile_against_printed_tables():
    # Student's t, two-sided 95 % (the 0.975 quantile), from printed tables.
    for df, value in ((1, 12.7062), (2, 4.3027), (4, 2.7764), (9, 2.2622), (30, 2.0423)):
        assert t_quantile(0.975, df) == pytest.approx(value, abs=1e-4)
    assert t_quantile(0.025, 4) == pytest.approx(-2.7764, abs=1e-4)
    assert t_quantile(0.5, 7) == pytest.approx(0.0, abs=1e-9)
    with pytest.raises(ValueError):
        t_quantile(1.0, 3)


def test_mean_ci_by_hand():
    # 1..5: mean 3, s = sqrt(2.5), se = s / sqrt(5) = sqrt(0.5); t(0.975, 4) = 2.776445.
    ci = mean_ci([1.0, 2.0, 3.0, 4.0, 5.0])
    half = 2.776445 * math.sqrt(0.5)
    assert ci.n == 5 and ci.mean == 3.0
    assert ci.lo == pytest.approx(3.0 - half, abs=1e-5) and ci.hi == pytest.approx(3.0 + half)
    one = mean_ci([7.0, float("nan")])  # nan ignored; one value has no interval
    assert one.n == 1 and one.mean == 7.0 and math.isnan(one.lo)
    assert mean_ci([]).n == 0


def test_bin_series_has_nan_where_a_bin_is_empty():
    s = bin_series(np.array([1.0, 2.0, 13.0]), np.array([99.0, 97.0, 90.0]), (0, 5, 10, 15))
    assert list(s.n) == [2, 0, 1]
    assert s.mean[0] == 98.0 and math.isnan(s.mean[1]) and s.mean[2] == 90.0
    # Two values 99 and 97: s = sqrt(2), se = 1, t(0.975, 1) = 12.7062.
    assert s.ci_hi[0] - s.mean[0] == pytest.approx(12.7062, abs=1e-4)
    assert list(s.centre) == [2.5, 7.5, 12.5]


def test_z_scores_and_coverage_by_hand():
    # z exactly ±0.5, ±1.5, ±2.5: inside ±1σ 2 of 6, inside ±1.96σ 4 of 6,
    # rms = sqrt((0.25 + 2.25 + 6.25) / 3), mean 0.
    z_true = np.array([0.5, -0.5, 1.5, -1.5, 2.5, -2.5])
    z = z_scores(0.1 + 0.004 * z_true, np.full(6, 0.1), np.full(6, 0.004))
    assert z == pytest.approx(z_true)
    c = calibration(z)
    assert (c.n, c.inside68, c.inside95) == (6, 2, 4)
    assert c.cov68 == pytest.approx(1 / 3) and c.cov95 == pytest.approx(2 / 3)
    assert c.rms == pytest.approx(math.sqrt(8.75 / 3)) and c.mean == pytest.approx(0.0)
    assert coverage(z, 1.0) == pytest.approx(1 / 3)
    # No std, zero std or nan: no z (left out, not counted as inside or outside).
    bad = z_scores(np.array([1.0, 1.0, 1.0]), np.zeros(3), np.array([np.nan, 0.0, 0.5]))
    assert np.isnan(bad[:2]).all() and bad[2] == 2.0
    assert calibration(bad).n == 1


def test_binned_calibration():
    theta = np.array([1.0, 2.0, 7.0, 70.0, 90.0])
    z = np.array([0.5, 3.0, -1.2, np.nan, 1.0])
    bins = binned_calibration(theta, z, CALIBRATION_BINS_DEG)
    assert [b[2].n for b in bins] == [2, 1, 0, 0, 0, 0, 0, 1]
    assert bins[0][2].inside68 == 1 and bins[0][2].inside95 == 1
    assert bins[1][2].inside68 == 0 and bins[1][2].inside95 == 1


def test_paired_difference_by_hand():
    # d = a - b = (2, 0, -2): mean 0, s = 2, se = 2 / sqrt(3), t(0.975, 2) = 4.302653.
    pd = paired_difference(np.array([3.0, 2.0, 1.0, np.nan]), np.array([1.0, 2.0, 3.0, 1.0]))
    assert (pd.a_better, pd.b_better, pd.ties, pd.diff.n) == (1, 1, 1, 3)
    assert pd.diff.mean == 0.0
    assert pd.diff.hi == pytest.approx(4.302653 * 2 / math.sqrt(3), abs=1e-5)


def test_slope_through_origin():
    assert slope_through_origin(np.array([1.0, 2.0, np.nan]), np.array([2.0, 4.0, 1.0])) == 2.0
    assert math.isnan(slope_through_origin(np.zeros(2), np.ones(2)))
