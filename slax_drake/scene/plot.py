"""Pictures of a scene: top-down footprints with the camera's view cone and the hidden target, beside the
camera's depth view (ray cast with Embree, the same geometry the visibility tests use)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from slax_drake.scene.footprint import Footprint
from slax_drake.scene.model import Scene
from slax_drake.scene.raycast import SceneRaycaster


def draw_top_down(ax, scene: Scene, highlight_target: bool = True) -> None:
    """Draws the shelf outline, the object footprints, the camera's view cone and the target on ``ax``."""
    from matplotlib.patches import Polygon as PolygonPatch, Rectangle

    shelf, camera = scene.shelf, scene.camera
    w, d = shelf.width / 2, shelf.depth / 2
    ax.add_patch(Rectangle((-w, -d), shelf.width, shelf.depth, fill=False, lw=2, ec="0.3"))
    for obj in scene.objects:
        fp = Footprint.of(obj)
        poly = np.asarray(fp.polygon().exterior.coords)
        ax.add_patch(PolygonPatch(poly, closed=True, fc="tab:blue" if obj.shape == "box" else "tab:orange",
                                  ec="k", alpha=0.6))
        ax.text(fp.x, fp.y, obj.name.split("_")[-1], ha="center", va="center", fontsize=7)
    if scene.target is not None and highlight_target:
        t = scene.target
        ax.add_patch(Rectangle((t.center[0] - t.size[0] / 2, t.center[1] - t.size[1] / 2), t.size[0], t.size[1],
                               fc="tab:green", ec="darkgreen", lw=1.5, label="hidden target"))
    eye = camera.position
    half = camera.horizontal_fov / 2
    reach = (d - eye[1]) * 1.05
    yaw_axis = np.arctan2(camera.X_SC[1, 2], camera.X_SC[0, 2])
    for a in (yaw_axis - half, yaw_axis + half):
        ax.plot([eye[0], eye[0] + reach * np.cos(a) / max(np.sin(a), 1e-3)],
                [eye[1], eye[1] + reach], color="tab:red", lw=1, ls="--")
    ax.plot(eye[0], eye[1], "v", color="tab:red", ms=9, label="camera")
    ax.set_aspect("equal")
    ax.set_xlim(-w - 0.15, w + 0.15)
    ax.set_ylim(eye[1] - 0.05, d + 0.05)
    ax.set_xlabel("x_S (m), right")
    ax.set_ylabel("y_S (m), into the shelf")
    ax.legend(loc="lower right", fontsize=7)


def save_scene_png(scene: Scene, path: str | Path, resolution: tuple[int, int] = (320, 240)) -> None:
    """Writes a PNG: left the top-down view, right the camera's depth view with the target's outline."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    camera = scene.camera.with_resolution(*resolution)
    depth, _ = SceneRaycaster(scene).render(camera)
    fig, (ax0, ax1) = plt.subplots(1, 2, figsize=(11, 4.6), gridspec_kw={"width_ratios": [1, 1.2]})
    draw_top_down(ax0, scene)
    ax0.set_title(f"top down: {len(scene.objects)} objects, seed {scene.seed}")
    shown = np.where(depth > 0, depth, np.nan)
    im = ax1.imshow(shown, cmap="viridis")
    fig.colorbar(im, ax=ax1, label="depth (m)", fraction=0.035)
    if scene.target is not None:
        from slax_drake.scene.surface import box_surface_points

        pts, _ = box_surface_points(tuple(scene.target.size), 0.01)
        uv = camera.project(pts + scene.target.center)
        ax1.plot(uv[:, 0], uv[:, 1], ".", ms=1.5, color="lime", label="hidden target (behind)")
        ax1.legend(loc="lower right", fontsize=7)
    ax1.set_title("camera view (depth)")
    ax1.set_axis_off()
    fig.tight_layout()
    from slax_drake.io import figure_png, write_bytes_atomic

    write_bytes_atomic(Path(path), figure_png(fig, 110))
