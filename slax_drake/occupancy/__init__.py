"""Ground-truth target occupancy: hidden placements and their 2D / 1D image-space distributions."""

from slax_drake.occupancy.hidden import (
    Occupancy,
    collision_free,
    compute_occupancies,
    compute_occupancy,
    grid_placements,
    placements_hidden,
    project_placements,
)

__all__ = [
    "Occupancy", "collision_free", "compute_occupancies", "compute_occupancy", "grid_placements", "placements_hidden",
    "project_placements",
]
