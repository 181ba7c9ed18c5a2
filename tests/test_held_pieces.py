"""The side view's gap check (``held_pieces.check_no_gap``) on arrays built here."""

import numpy as np
import pytest

from comgrasp_pin.camera import PinholeCamera
from comgrasp_pin.errors import UntrustedImageError


def test_a_held_rod_fit_with_no_point_near_its_axis_is_refused_not_a_crash():
    """The side view's gap check given a fit with no pixel within the rod's radius of its
    axis (a paper-size run met it on a 1 cm stick: an IndexError, counted as an internal
    error): a refusal of the frame, which the trial grasp takes again."""
    from comgrasp_pin.perception.side_view.held_pieces import check_no_gap

    mask = np.zeros((20, 30), bool)
    mask[8:12, 5:25] = True
    along = np.linspace(-0.05, 0.05, int(mask.sum()))
    camera = PinholeCamera(fx=300.0, fy=300.0, cx=14.5, cy=9.5, width=30, height=20)
    axis = (np.array([1.0, 0.0, 0.0]), np.zeros(3))
    with pytest.raises(UntrustedImageError, match="no point of the held rod"):
        check_no_gap(mask, along, np.zeros(len(along), bool), axis, np.ones((20, 30)), camera,
                     np.eye(4), lambda p: np.zeros(len(p), bool))  # fmt: skip
