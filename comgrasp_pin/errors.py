"""The package's errors: one base, ``ComGraspError``, and a built-in base that says the kind.

Every exception the package raises is a ``ComGraspError``, so a caller may catch them all
with one clause (and the command line prints any of them as one line, exit status 2). Each
one is also the built-in exception of its kind, so a caller that knows nothing of this
package catches it where it belongs:

- bad input and estimates that cannot be made: ``ValueError`` (``InvalidInputError``,
  ``UnobservableError``, ``EmptyGripperError``, ``NotIdentifiedError``, ``SolverError``,
  the ``PerceptionError``, ``LogError`` and ``IKError`` families, ``CollisionError``);
- the physical outcomes of a grasp, which are neither bad input nor a broken harness: a
  ``ComGraspError`` only (``RodDroppedError``, ``RodSlippedError``);
- run and harness failures: ``UnstablePhysicsError``, ``WorkerDiedError``,
  ``BackendError`` and ``InternalTrialError`` are ``RuntimeError``; ``TrialTimeoutError``
  a ``TimeoutError``; ``OutputError`` and ``ResumeError`` (the results folder's files refuse
  the run, as ``FileExistsError`` would) an ``OSError``; ``MissingAssetError`` a
  ``FileNotFoundError``; ``MissingExtraError`` an ``ImportError``.

Inheritance says what a failure is, not what to do about it: which outcomes of a trial
grasp are grasped again is ``planning.retry.ON_FAILED_GRASP``, a table.
"""

from __future__ import annotations


class ComGraspError(Exception):
    """Base class of every error raised by comgrasp_pin (see the module docstring for the
    built-in base each kind adds)."""


# --- bad input, and estimates the data cannot give: ValueError ---------------------------


class InvalidInputError(ComGraspError, ValueError):
    """An argument has the wrong shape, type or value (NaN, inf, unknown option)."""


class UnobservableError(ComGraspError, ValueError):
    """The data cannot determine the requested quantity (e.g. the mass, or x_CoM^O for a rod
    axis parallel to gravity)."""


class EmptyGripperError(ComGraspError, ValueError):
    """The estimated payload mass is not measurably above zero: nothing is held."""


class NotIdentifiedError(ComGraspError, ValueError):
    """A payload file was asked for an estimate whose verdict is not ``identified``
    (``estimation.trust``): the message gives the verdict and its reasons."""


class SolverError(ComGraspError, ValueError):
    """A numerical solver failed on the data it was given. ``return_status`` is the solver's
    own status string (IPOPT's ``return_status``), ``iterations`` its iteration count."""

    def __init__(self, message: str, return_status: str, iterations: int | None = None):
        super().__init__(f"{message} (solver status: {return_status})")
        self.return_status = return_status
        self.iterations = iterations


class PerceptionError(ComGraspError, ValueError):
    """The cameras' images do not give what was asked (base of the perception errors)."""


class ObjectNotFoundError(PerceptionError):
    """No object is in view where one is expected."""


class ObjectCutByBorderError(PerceptionError):
    """The object touches the image border: part of it is out of view, so its extent (and
    centre) cannot be measured.

    ``seen``: when a rod runs out of view at one end only, the top view's measure of the
    part it sees (a ``RodDetection`` whose ``cut_end`` says which end), else None. Who
    knows the rod's length may complete it (``perception.top_view.top_down.with_known_length``).
    """

    def __init__(self, message: str, seen=None):
        super().__init__(message)
        self.seen = seen


class AmbiguousObjectError(PerceptionError):
    """What the camera sees is not one rod: two objects, or two rods side by side seen as
    one blob. Measuring it would give a pose that belongs to neither."""


class ClutterError(AmbiguousObjectError):
    """Three objects or more (or piles of them) lie where one rod should lie alone."""


class UntrustedImageError(PerceptionError):
    """The object is in view, but this image cannot measure it to the accuracy asked (a
    real camera's holes and noise where the method needs a clean surface): refused rather
    than measured with a known bias."""


class ColourDepthMismatchError(UntrustedImageError):
    """The colour image and the depth image do not line up (not registered): the object's
    outline sits at other pixels in each, so the colour cannot say which pixels are the
    object's. The depth alone may still measure it."""


class InvalidDepthError(PerceptionError):
    """The depth image is missing, of the wrong shape, or has no valid values where needed."""


class HeldRodUnmeasuredError(PerceptionError):
    """The side camera could not measure the held rod (every frame refused as untrusted:
    noise and holes where the handle's surface is fitted), so it was laid back where it was
    grasped. A camera's failure, not the grasp's: the rod did not necessarily slip.
    ``heavy_side_world`` tells where its CoM lies, if the watch saw it turn
    (``planning.retry.ON_FAILED_GRASP`` grasps it again)."""

    template = "the side camera cannot measure the held rod, so it was laid back: {}"

    def __init__(self, message: str, heavy_side_world=None):
        super().__init__(self.template.format(message))
        self.heavy_side_world = heavy_side_world


class CameraFileError(InvalidInputError):
    """A camera's image, camera-info or pose file cannot be read as asked: unreadable, of
    the wrong kind or bit depth, missing a field, or sizes that disagree."""


class IKError(ComGraspError, ValueError):
    """No joint configuration reaches the target within tolerance and joint limits."""


class CollisionError(ComGraspError, ValueError):
    """The robot's collision model cannot be built, or no collision-free pose is found."""


class LogError(ComGraspError, ValueError):
    """A robot log (ROS 2 bag or CSV) cannot give what is asked: the file is unreadable, a
    topic, joint or effort is missing, or a time window is outside the log."""


class MotionLogError(LogError):
    """A motion's log cannot identify a payload's inertia: too short, no motion, a joint at
    its limit, too jerky for the filter, or sampled with gaps."""


class NotStaticError(LogError):
    """A time window of a log is not static: the arm moved faster than the threshold."""


# --- what the world did to a grasp: its own kind ------------------------------------------


class RodDroppedError(ComGraspError):
    """The rod fell out of the jaws during a trial grasp (a physical outcome, not an empty
    gripper's estimate: that one is ``EmptyGripperError``, which the trial grasp turns into
    this when the rod was held before).

    ``heavy_side_world``: (3,) unit horizontal direction (world) of the end that went down
    first, from the side camera's tilt samples or the estimate, or None if nothing told.
    """

    template = "the rod was dropped in the trial grasp: {}"

    def __init__(self, message: str, heavy_side_world=None):
        super().__init__(self.template.format(message))
        self.heavy_side_world = heavy_side_world


class RodSlippedError(RodDroppedError):
    """The rod turned in the jaws as a careful trial grasp began to lift it, and was put
    back down; ``heavy_side_world`` tells where its CoM lies."""

    template = "the rod slipped as it was lifted: {}"


# --- run and harness failures: RuntimeError, TimeoutError, OSError, ImportError -----------


class UnstablePhysicsError(ComGraspError, RuntimeError):
    """The simulation went unstable (NaN or inf state, MuJoCo's bad-acceleration warning):
    the trial's physics, not the robot's method, failed."""


class WorkerDiedError(ComGraspError, RuntimeError):
    """A worker process running a trial died (killed, crashed, out of memory)."""


class TrialTimeoutError(ComGraspError, TimeoutError):
    """A trial ran past its time limit (``--trial-timeout``): its worker was stopped and the
    run went on; ``--resume --retry-failed`` runs it again."""


class BackendError(ComGraspError, RuntimeError):
    """The requested backend cannot run trials here (``--backend ray`` without Ray installed,
    or a Ray cluster that cannot be reached)."""


class InternalTrialError(ComGraspError, RuntimeError):
    """Trials raised an exception that is not a ``ComGraspError`` (a bug: a ``TypeError``,
    a ``KeyError``, ...), not the world's failure. Raised when the command's runs have ended
    (``internal_errors.fail_on_internal_errors``): their rows are in the CSVs, marked ``internal
    error`` and left out of every rate and mean; ``--resume`` runs them again. The command
    line exits with status 1.

    ``trials``: the names of those trials; ``traceback_paths``: the files holding their
    tracebacks."""

    def __init__(self, message: str, trials=(), traceback_paths=()):
        super().__init__(message)
        self.trials = list(trials)
        self.traceback_paths = list(traceback_paths)


class MissingExtraError(ComGraspError, ImportError):
    """An optional dependency the command needs is not installed (``--rerun`` without
    rerun-sdk); the message says how to install it."""


class MissingAssetError(ComGraspError, FileNotFoundError):
    """A file the package ships or depends on (urdf/, sim/, example-robot-data) is missing:
    the installation is broken."""


class RobotError(ComGraspError, RuntimeError):
    """A connected robot refused, reported an error or a contact, or its connection was lost
    (``comgrasp live``); what was recorded up to then is kept."""


class OutputError(ComGraspError, OSError):
    """A result file (video, figure, CSV) cannot be written where it was asked for."""


class ResumeError(OutputError):
    """A run's results folder cannot be continued: other settings, another header, damaged
    rows, results there without ``--resume`` or ``--overwrite``, another run writing it. The
    files on disk refuse the run (an ``OSError``, as ``FileExistsError`` would be), not an
    argument: the message names what differs and what to do."""
