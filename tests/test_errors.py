"""The error tree says what kind of failure each error is, and the retries are a table."""

import inspect
from types import SimpleNamespace

import numpy as np
import pytest

import comgrasp_pin as cg
from comgrasp_pin import errors
from comgrasp_pin.errors import (
    AmbiguousObjectError,
    BackendError,
    CameraFileError,
    ClutterError,
    CollisionError,
    ColourDepthMismatchError,
    ComGraspError,
    EmptyGripperError,
    HeldRodUnmeasuredError,
    IKError,
    InternalTrialError,
    InvalidDepthError,
    InvalidInputError,
    LogError,
    MissingAssetError,
    MissingExtraError,
    MotionLogError,
    NotIdentifiedError,
    NotStaticError,
    ObjectCutByBorderError,
    ObjectNotFoundError,
    OutputError,
    PerceptionError,
    ResumeError,
    RobotError,
    RodDroppedError,
    RodSlippedError,
    SolverError,
    TrialTimeoutError,
    UnobservableError,
    UnstablePhysicsError,
    UntrustedImageError,
    WorkerDiedError,
)
from comgrasp_pin.planning import retry

INPUT = [InvalidInputError, UnobservableError, EmptyGripperError, SolverError, PerceptionError,
         ObjectNotFoundError, ObjectCutByBorderError, AmbiguousObjectError, ClutterError,
         UntrustedImageError, ColourDepthMismatchError, InvalidDepthError,
         HeldRodUnmeasuredError, CameraFileError, IKError, CollisionError,
         LogError, MotionLogError, NotStaticError, NotIdentifiedError]  # fmt: skip
HARNESS = {
    UnstablePhysicsError: RuntimeError,
    WorkerDiedError: RuntimeError,
    BackendError: RuntimeError,
    InternalTrialError: RuntimeError,
    TrialTimeoutError: TimeoutError,
    OutputError: OSError,
    ResumeError: OSError,
    MissingAssetError: FileNotFoundError,
    MissingExtraError: ImportError,
    RobotError: RuntimeError,
}
PHYSICAL = [RodDroppedError, RodSlippedError]


def _classes():
    return [c for _, c in inspect.getmembers(errors, inspect.isclass) if issubclass(c, Exception)]


def test_every_error_is_listed_here_and_is_a_comgrasp_error():
    assert set(_classes()) == {ComGraspError, *INPUT, *HARNESS, *PHYSICAL}
    assert all(issubclass(c, ComGraspError) for c in _classes())
    assert ComGraspError.__bases__ == (Exception,)


@pytest.mark.parametrize("cls", INPUT, ids=lambda c: c.__name__)
def test_input_and_estimate_errors_are_value_errors(cls):
    assert issubclass(cls, ValueError)
    assert not issubclass(cls, (RuntimeError, OSError, ImportError))


@pytest.mark.parametrize("cls", list(HARNESS), ids=lambda c: c.__name__)
def test_run_and_harness_failures_are_not_value_errors(cls):
    assert issubclass(cls, HARNESS[cls])
    assert not issubclass(cls, ValueError)


@pytest.mark.parametrize("cls", PHYSICAL, ids=lambda c: c.__name__)
def test_a_grasp_that_failed_in_the_world_is_neither_input_nor_harness(cls):
    assert not issubclass(cls, (ValueError, RuntimeError, OSError, ImportError))


def test_the_grasp_outcomes_are_their_own_kinds():
    assert not issubclass(RodDroppedError, EmptyGripperError)
    assert issubclass(HeldRodUnmeasuredError, PerceptionError)
    assert not issubclass(HeldRodUnmeasuredError, RodDroppedError)  # a camera's failure
    assert not issubclass(HeldRodUnmeasuredError, RodSlippedError)


def test_the_errors_keep_their_data_and_messages():
    heavy = np.array([1.0, 0.0, 0.0])
    e = HeldRodUnmeasuredError("no cylinder fits", heavy)
    assert str(e).startswith("the side camera cannot measure the held rod, so it was laid back")
    assert e.heavy_side_world is heavy
    assert str(RodSlippedError("by 20 deg")).startswith("the rod slipped as it was lifted")
    assert RodDroppedError("x").heavy_side_world is None
    assert str(OutputError("cannot write x")) == "cannot write x"
    assert str(TrialTimeoutError("late")) == "late"
    s = SolverError("no fit", "Infeasible_Problem_Detected", 12)
    assert s.return_status == "Infeasible_Problem_Detected" and s.iterations == 12


def test_the_top_level_exports_what_callers_catch():
    for name in ("ComGraspError", "InvalidInputError", "UnobservableError", "EmptyGripperError",
                 "SolverError", "PerceptionError", "LogError", "NotStaticError", "IKError",
                 "OutputError"):  # fmt: skip
        assert name in cg.__all__ and getattr(cg, name) is getattr(errors, name)


@pytest.mark.parametrize("cls", [TrialTimeoutError, ResumeError, MissingExtraError,
                                 BackendError, RodDroppedError, InvalidInputError])  # fmt: skip
def test_the_command_line_prints_any_comgrasp_error_as_one_line_with_status_2(
    cls, monkeypatch, capsys
):
    from comgrasp_pin import cli
    from comgrasp_pin.cli import world

    def boom(args):
        raise cls("what went wrong")

    monkeypatch.setattr(world, "_cmd_check", boom)
    assert cli.main(["check"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("comgrasp check: error: ") and err.endswith("what went wrong\n")
    assert err.count("\n") == 1  # one line, no traceback


# --- the retry table -----------------------------------------------------------------------


def test_the_retry_table_names_each_outcome_grasped_again():
    assert retry.on_failed_grasp(RodDroppedError("fell")) == retry.OnFailedGrasp(True, False)
    assert retry.on_failed_grasp(RodSlippedError("turned")) == retry.OnFailedGrasp(True, True)
    assert retry.on_failed_grasp(HeldRodUnmeasuredError("refused")) == retry.OnFailedGrasp(
        True, True
    )
    assert set(retry.GRASPED_AGAIN) == {RodDroppedError, RodSlippedError, HeldRodUnmeasuredError}


@pytest.mark.parametrize(
    "exc",
    [PerceptionError("no rod"), UntrustedImageError("noisy"), IKError("far"),
     EmptyGripperError("nothing"), UnstablePhysicsError("nan"), TypeError("bug")],
    ids=lambda e: type(e).__name__,
)  # fmt: skip
def test_other_failures_are_not_grasped_again(exc):
    assert retry.on_failed_grasp(exc) is None


def test_a_subclass_is_not_retried_because_its_parent_is():
    class NewKindOfDrop(RodDroppedError):
        pass

    assert isinstance(NewKindOfDrop("x"), retry.GRASPED_AGAIN)  # caught...
    assert retry.on_failed_grasp(NewKindOfDrop("x")) is None  # ...but not grasped again


# --- the table in the pick-and-place procedure (a fake cell, no simulator) -----------------


MEASURED = SimpleNamespace(dropped_at_roll=False)  # a trial grasp that measured


class _Cell:
    """Records what the procedure tells the robot to do."""

    def __init__(self):
        self.log = []

    def look_from_above(self):
        return SimpleNamespace(length=0.4, grasp=SimpleNamespace(yaw=0.0))

    def announce(self, text):
        self.log.append(("announce", text.split(":")[0]))

    def open_gripper(self, t):
        self.log.append(("open",))

    def move_to(self, q, **kw):
        self.log.append(("park",))

    def hold(self, t):
        pass


def _trial_with_retry(monkeypatch, failures):
    """``trial_with_retry`` on a fake cell whose trial grasps raise ``failures`` in turn,
    then succeed: the cell's log and the offsets the grasps were made at."""
    from comgrasp_pin.config import EpisodeConfig
    from comgrasp_pin.procedures import pick_and_place

    outcomes, offsets = list(failures), []

    def trial_grasp(cell, config, offset, careful, detection):
        offsets.append((offset, careful))
        if outcomes:
            raise outcomes.pop(0)
        return MEASURED

    monkeypatch.setattr(pick_and_place, "trial_grasp", trial_grasp)
    monkeypatch.setattr(pick_and_place, "nearest_on_handle", lambda rod, s: s)
    monkeypatch.setattr(
        pick_and_place, "look_again", lambda cell, length, config: cell.look_from_above()
    )
    cell, config = _Cell(), EpisodeConfig()
    return pick_and_place.trial_with_retry(cell, config), cell.log, offsets, config


def test_pick_and_place_grasps_again_as_the_table_says(monkeypatch):
    east = np.array([1.0, 0.0, 0.0])
    failures = [RodDroppedError("fell", east), RodSlippedError("turned", -east),
                HeldRodUnmeasuredError("refused", None)]  # fmt: skip
    result, log, offsets, config = _trial_with_retry(monkeypatch, failures)
    assert result is MEASURED and len(offsets) == 4
    # only the rod that fell is announced as put back: the others the trial laid back itself
    assert [e for e in log if e[0] == "announce"] == [("announce", "put back")]
    assert log.count(("open",)) == 3 and log.count(("park",)) == 3
    step = config.regrasp.retry_shift * 0.4  # towards the heavy end, then bisected
    assert [o for o, _ in offsets] == pytest.approx([0.0, step, step / 2, step / 2])
    assert config.regrasp.attempts == 4 and [c for _, c in offsets] == [True, True, True, False]


@pytest.mark.parametrize(
    "exc",
    [UntrustedImageError("noisy"), IKError("far"), UnstablePhysicsError("nan")],
    ids=lambda e: type(e).__name__,
)
def test_pick_and_place_does_not_grasp_again_what_the_table_leaves_out(monkeypatch, exc):
    with pytest.raises(type(exc)):
        _trial_with_retry(monkeypatch, [exc])
