"""Every exception of slax_drake, under two bases:

- :class:`UserError`: what a user gave us (a config, a scene file, a request that cannot be met). The command line
  prints it as one line on stderr and exits with code 2.
- :class:`InternalError`: a fault of the package itself (a motion that Ruckig cannot time, a depth image of the
  wrong shape handed between stages). It is not the user's to fix, so it keeps its traceback (exit code 1).

Anything else raised is a bug as well and keeps its traceback too.
"""


class UserError(Exception):
    """A problem with the user's input; printed as one line, exit code 2."""


class InternalError(Exception):
    """A fault inside the package (not the user's input); printed with its traceback, exit code 1."""


# Scenarios and scenes


class ConfigError(UserError):
    """A scenario YAML file is malformed or holds an impossible value."""


class SceneFileError(UserError):
    """A scene JSON file is malformed, has the wrong schema version or out-of-range values."""


class SceneGenerationError(UserError):
    """A scene could not be completed within the retry budget."""


# Memory budget


class MemoryBudgetError(UserError):
    """A request whose estimated memory exceeds what this machine has available."""


# Backends (local processes, Ray)


class BackendError(UserError):
    """A backend that cannot be used: unknown, Ray missing, or a Ray cluster that cannot be reached."""


# Occupancy


class DepthOccupancyError(InternalError):
    """A depth image or setting the depth-based occupancy cannot use."""


# Station


class SceneMismatchError(UserError):
    """A scene does not belong to the station's shelf (different bay)."""


# Datasets


class DatasetError(UserError):
    """A dataset folder or shard is missing, corrupt, or was made with other arguments."""


# Perception


class ImageSizeError(UserError):
    """A depth image does not have the shape the model was trained for."""


class ObservationError(UserError):
    """A camera frame (depth, segmentation, target mask, joint state) cannot be used as an observation: wrong
    shape for the camera, wrong data type, or too few valid depth returns."""


class PerceptionDataError(UserError):
    """A training or evaluation data set is missing, empty or lacks what the network needs."""


class WeightFileError(UserError):
    """A weight file is missing, truncated, not a slax-drake perception model, or of another version."""


# Policies


class UnknownPolicyError(UserError):
    """A policy name that does not exist."""


# Planning


class TimingError(InternalError):
    """Ruckig could not time a segment."""


# Drake systems and trials


class GraphvizMissingError(UserError):
    """Graphviz's ``dot`` is not installed, so the SVG cannot be drawn."""


class StationNotFoundError(UserError):
    """No station file fits a scene scenario or a scene's shelf (pass ``--station``)."""


class TrialError(UserError):
    """A trial cannot be set up (bad config, no station for the shelf, unsupported option)."""


# Evaluation


class BenchmarkError(UserError):
    """A benchmark request that cannot be run, or a corrupt trial file."""


class PhysicsBenchmarkError(UserError):
    """A physics benchmark request that cannot be run, or a corrupt per-scene result file."""


class SettingsMismatchError(UserError):
    """A resumed benchmark whose settings differ from those its folder was made with."""


# Hardware: trajectory files, export, plan-step


class PlanStepError(UserError):
    """An input of plan-step that cannot be used (exit code 2)."""


class PlacementError(UserError):
    """A placement search that cannot be run as asked (an empty or out-of-range candidate grid; exit code 2)."""


class ActionSpecError(UserError):
    """A check-action request that cannot be used: a malformed --action, an unknown object, no station for the
    scene's shelf."""


class TrajectoryFileError(UserError):
    """An exported trajectory file cannot be read (missing, malformed, truncated, wrong joints, bad times)."""


class TrialFileError(TrajectoryFileError):
    """A trial.json cannot be exported (missing, malformed, or without the executed trajectory)."""
