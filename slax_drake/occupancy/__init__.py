"""Ground-truth target occupancy: hidden placements and their 2D / 1D image-space distributions.

The names below are imported from their submodule on first use (:mod:`slax_drake.lazy_exports`)."""

from slax_drake.lazy_exports import lazy_exports

_EXPORTS = {name: "hidden" for name in (
    "Occupancy", "collision_free", "compute_occupancies", "compute_occupancy", "grid_placements", "placements_hidden",
    "project_placements",
)}
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
