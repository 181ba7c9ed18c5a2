import numpy as np

from comgrasp_pin.experiments.paper import paper_accuracy_at
from comgrasp_pin.experiments.stats import binned_mean, wilson_interval


def test_wilson_interval_known_values():
    # Reference values computed by hand from the Wilson formula: 8/10 -> (0.4902, 0.9433).
    lo, hi = wilson_interval(8, 10)
    assert abs(lo - 0.4902) < 1e-3 and abs(hi - 0.9433) < 1e-3
    assert wilson_interval(0, 20)[0] == 0.0 and wilson_interval(20, 20)[1] == 1.0


def test_binned_mean():
    rows = binned_mean(np.array([1, 2, 6, 31]), np.array([1.0, 3.0, 5.0, 7.0]), (0, 5, 10, 40))
    assert rows[0] == (0, 5, 2.0, 2) and rows[1] == (5, 10, 5.0, 1) and rows[2] == (10, 40, 7.0, 1)


def test_paper_values_interpolate():
    assert paper_accuracy_at("obj1", 0.1) == 98.7
    assert abs(paper_accuracy_at("obj6", 30.8) - 59.1) < 1e-12
    assert paper_accuracy_at("obj3", 5.0) is None
