"""Laying back a rod the side camera cannot measure: how high the jaws let go."""

import numpy as np
import pytest

from comgrasp_pin.procedures.put_back import release_height_above_grasp


def test_the_lower_end_clears_the_table_by_the_margin():
    # a 0.4 m rod held 5 cm from its centre, hanging 30 deg: its far end reaches
    # (0.2 + 0.05) sin 30 deg = 0.125 m below the jaws
    assert release_height_above_grasp(0.4, 0.05, np.radians(30), 0.01) == pytest.approx(0.135)
    assert release_height_above_grasp(0.4, -0.05, -np.radians(30), 0.01) == pytest.approx(0.135)
    assert release_height_above_grasp(0.4, 0.0, 0.0, 0.01) == pytest.approx(0.01)  # level
    # hanging straight down: the whole far part of the rod below the jaws
    assert release_height_above_grasp(0.3, 0.02, np.pi / 2, 0.0) == pytest.approx(0.17)
