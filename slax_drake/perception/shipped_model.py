"""Where the shipped occupancy network's weight file lives, relative to the repository root.

A module of its own, free of torch, so that the command line can name it in ``--help`` at once."""

DEFAULT_MODEL = "models/perception/unet128/model.pt"
