"""Errors of the perception stage; all are user errors (one line, exit code 2)."""

from slax_drake.errors import UserError


class WeightFileError(UserError):
    """A weight file is missing, truncated, not a slax-drake perception model, or of another version."""


class ImageSizeError(UserError):
    """A depth image does not have the shape the model was trained for."""


class PerceptionDataError(UserError):
    """A training or evaluation data set is missing, empty or lacks what the network needs."""
