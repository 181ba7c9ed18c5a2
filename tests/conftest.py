import os

os.environ.setdefault("MUJOCO_GL", "egl")

import pytest  # noqa: E402


@pytest.fixture(scope="session")
def ur5():
    import comgrasp_pin as cg

    return cg.RobotModel.ur5()


@pytest.fixture(scope="session")
def world_model():
    from comgrasp_pin.simulation import build_model

    return build_model()
