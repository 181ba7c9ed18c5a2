import os

os.environ.setdefault("MUJOCO_GL", "egl")
# One BLAS thread: the tests' matrices are small, and on 2 shared cores several BLAS threads
# per process fight over them (the motion fits ran 3x slower so); set before NumPy loads.
for _name in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_name, "1")

import pytest  # noqa: E402


@pytest.fixture(scope="session")
def ur5():
    import comgrasp_pin as cg

    return cg.RobotModel.ur5()


@pytest.fixture(scope="session")
def world_model():
    from comgrasp_pin.simulation import build_model

    return build_model()
