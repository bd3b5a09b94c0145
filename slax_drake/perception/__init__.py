"""Perception: depth image -> target occupancy distributions (one network head per target ratio), training,
inference, and instance segmentation of the occluders from depth alone."""
