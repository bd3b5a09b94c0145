"""Datasets: rendered depth and label images with ground-truth occupancy distributions, in HDF5 shards."""

from slax_drake.dataset.generate import DatasetSpec, generate
from slax_drake.errors import DatasetError
from slax_drake.dataset.shards import TARGET_SIZES, DatasetReader

__all__ = ["DatasetError", "DatasetReader", "DatasetSpec", "TARGET_SIZES", "generate"]
