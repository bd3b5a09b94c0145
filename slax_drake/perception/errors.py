"""Errors of the perception stage; all are user errors (one line, exit code 2)."""

from slax_drake.errors import UserError


class WeightFileError(UserError):
    """A weight file is missing, truncated, not a slax-drake perception model, or of another version."""


class ImageSizeError(UserError):
    """A depth image does not have the shape the model was trained for."""


class PerceptionDataError(UserError):
    """A training or evaluation data set is missing, empty or lacks what the network needs."""


class ObservationError(UserError):
    """A camera frame (depth, segmentation, target mask, joint state) cannot be used as an observation: wrong
    shape for the camera, wrong data type, or too few valid depth returns."""
