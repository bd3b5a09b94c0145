"""Picture of a scene's occupancy: the depth image with p2d over it, p1d below, top-down hidden placements."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from slax_drake.occupancy.hidden import Occupancy
from slax_drake.scene.model import Scene
from slax_drake.scene.raycast import SceneRaycaster


def save_occupancy_png(scene: Scene, occ: Occupancy, path: str | Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from slax_drake.io import figure_png, write_bytes_atomic
    from slax_drake.scene.plot import draw_top_down

    camera = scene.camera.with_resolution(occ.p2d.shape[1], occ.p2d.shape[0])
    depth, _ = SceneRaycaster(scene).render(camera)
    fig = plt.figure(figsize=(12, 6))
    grid = fig.add_gridspec(2, 2, width_ratios=[1.25, 1], height_ratios=[3, 1])
    ax_img = fig.add_subplot(grid[0, 0])
    ax_1d = fig.add_subplot(grid[1, 0], sharex=ax_img)
    ax_top = fig.add_subplot(grid[:, 1])
    ax_img.imshow(np.where(depth > 0, depth, np.nan), cmap="gray")
    p = np.ma.masked_where(occ.p2d <= 0, occ.p2d)
    ax_img.imshow(p, cmap="magma", alpha=0.75)
    ax_img.set_title(f"depth with p(x, y): {occ.num_hidden} hidden placements")
    ax_img.set_axis_off()
    ax_1d.fill_between(np.arange(len(occ.p1d)), occ.p1d, step="mid", color="tab:purple")
    ax_1d.set_xlim(-0.5, len(occ.p1d) - 0.5)
    ax_1d.set_xlabel("image x (pixels)")
    ax_1d.set_ylabel("P(x)")
    draw_top_down(ax_top, scene)
    if occ.num_hidden:
        ax_top.plot(occ.hidden_xy[:, 0], occ.hidden_xy[:, 1], ".", ms=2, color="darkgreen",
                    label="hidden placements (centres)")
        ax_top.legend(loc="lower right", fontsize=7)
    ax_top.set_title(f"top down, grid {occ.grid_step} m")
    fig.tight_layout()
    write_bytes_atomic(Path(path), figure_png(fig, 100))
