"""Value types for the command line's arguments, shared by every command.

Each is an ``argparse`` ``type=``: a value out of range is refused while the arguments are parsed, before any
file or folder is made, with argparse's usage line and one error line naming the argument, exit code 2::

    slax-drake scene: error: argument --seed: must be an integer in [0, 2^63 - 1], got '-1'

Only the standard library is imported here, so that parsing stays fast.
"""

from __future__ import annotations

import argparse
import math

SEED_MAX = 2**63 - 1  # torch.manual_seed and numpy's SeedSequence both take any seed in [0, SEED_MAX]


def seed(text: str) -> int:
    """A random seed: an integer in [0, 2^63 - 1]."""
    value = _integer(text)
    if not 0 <= value <= SEED_MAX:
        raise argparse.ArgumentTypeError(f"must be an integer in [0, 2^63 - 1], got {text!r}")
    return value


def non_negative_int(text: str) -> int:
    """An integer >= 0."""
    value = _integer(text)
    if value < 0:
        raise argparse.ArgumentTypeError(f"must be an integer >= 0, got {text!r}")
    return value


def positive_int(text: str) -> int:
    """An integer >= 1."""
    value = _integer(text)
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be a positive integer, got {text!r}")
    return value


def positive_float(text: str) -> float:
    """A finite number > 0."""
    value = _finite(text)
    if value <= 0:
        raise argparse.ArgumentTypeError(f"must be a positive number, got {text!r}")
    return value


def non_negative_float(text: str) -> float:
    """A finite number >= 0."""
    value = _finite(text)
    if value < 0:
        raise argparse.ArgumentTypeError(f"must be a number >= 0, got {text!r}")
    return value


def _integer(text: str) -> int:
    try:
        return int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be an integer, got {text!r}") from None


def _finite(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be a number, got {text!r}") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"must be a finite number, got {text!r}")
    return value
