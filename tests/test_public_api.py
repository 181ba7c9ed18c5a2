"""The public face: what ``dir(comgrasp_pin)`` shows, and that every listed name is there."""

import importlib

import comgrasp_pin as cg


def test_dir_lists_the_public_names_only():
    assert dir(cg) == sorted([*cg.__all__, "__version__"])
    for internal in ("errors", "file_checks", "validate", "geometry", "estimation", "robot"):
        assert internal not in dir(cg)


def test_every_exported_name_resolves():
    for module in ("comgrasp_pin", "comgrasp_pin.robot_io", "comgrasp_pin.estimation"):
        mod = importlib.import_module(module)
        assert len(mod.__all__) == len(set(mod.__all__)), module
        for name in mod.__all__:
            assert hasattr(mod, name), f"{module}.{name}"
    assert "estimate_payload_dynamic" in importlib.import_module("comgrasp_pin.robot_io").__all__


def test_one_name_for_the_std_of_a_torque_reading():
    """``torque_std`` is the std of one (averaged) reading wherever the estimator speaks of it:
    the argument, the estimate's field, the pose plan's; ``noise_std`` is gone from them."""
    import dataclasses
    import inspect

    from comgrasp_pin.robot_io.results import estimate_result as rio_parts

    assert "torque_std" in inspect.signature(cg.estimate_com).parameters
    for cls in (cg.ComEstimate, cg.PosePlan, cg.PayloadEstimate, rio_parts.JointTorques):
        names = {f.name for f in dataclasses.fields(cls)}
        assert "noise_std" not in names, cls
    assert "torque_std" in {f.name for f in dataclasses.fields(cg.ComEstimate)}
