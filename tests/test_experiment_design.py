"""The accuracy experiment's grasps: where they go relative to the true CoM."""

import numpy as np

from comgrasp_pin.config import EpisodeConfig
from comgrasp_pin.experiments.trials import (
    ACCURACY_COM_RANGE,
    ACCURACY_GRASP_OFFSET,
    ACCURACY_LEVER_RANGE,
    accuracy_grasp,
)
from comgrasp_pin.planning.holding import holding_lever
from comgrasp_pin.simulation.objects import OBJECTS


def test_holding_lever_is_the_pads_moment_over_the_weight():
    # 2 fingers x 15 N x (0.8 x 12 mm + 2 mm) = 0.348 N m; a 0.5 kg rod weighs 4.905 N.
    assert np.isclose(holding_lever(0.5, 15.0, (0.8, 0.002, 1e-4)), 0.348 / 4.905)
    assert np.isclose(holding_lever(1.0, 30.0, (0.8, 0.002)), 2 * 0.348 / 9.81)


def test_accuracy_grasps_lie_between_the_centre_and_the_com_within_the_lever_range():
    config = EpisodeConfig()
    for name, obj in OBJECTS.items():
        lever = holding_lever(obj.mass, config.motion.grip_force, config.world.pad_friction)
        limit = ACCURACY_GRASP_OFFSET * obj.length
        for seed in range(40):
            pos_real, offset = accuracy_grasp(name, seed, config)
            assert ACCURACY_COM_RANGE[0] * obj.length <= abs(pos_real)
            assert abs(pos_real) <= ACCURACY_COM_RANGE[1] * obj.length
            assert abs(offset) <= limit + 1e-12
            if abs(offset) < limit - 1e-9:  # not clipped to the handle
                distance = abs(offset - pos_real)
                assert ACCURACY_LEVER_RANGE[0] * lever - 1e-12 <= distance
                assert distance <= ACCURACY_LEVER_RANGE[1] * lever + 1e-12
                assert abs(offset) <= abs(pos_real) + distance  # towards the centre
        # The same seed gives the same grasp (baseline/regrasp comparisons, --resume).
        assert accuracy_grasp(name, 3, config) == accuracy_grasp(name, 3, config)
