"""The per-decision picture of a trial (``step_<k>.png``): what the planner saw and what it chose.

Three panels:
- the depth image (metres, with its colour bar) and the label image, both in image columns u and rows v of the
  tool camera. Labels have fixed colours (:func:`label_colors`): background white, shelf tan, object i the i-th
  colour of a fixed palette, the target red as in Meshcat, so a colour names the same object in every step;
- on both, the chosen action projected through the camera: an arrow for a push (the blade from its start ``q``
  along x by ``d``), a path for a suction (the cup from its contact ``q`` out of the bay, across by ``dx`` and back
  in until the object's centre is at y = ``dz``; a sketch of the planner's waypoints, which may pull out less far);
  and the outline of the target's visible pixels;
- the 1D target distribution P_t (filled) and its history minimum P'_t = min(P_t, P'_{t-1}) (line) over the same
  image columns u as the images (the coarse columns of the distribution scaled to the image's width), with the
  shelf's x in metres on the top axis, where a column's ray meets the support surface's centre line (y = 0, z = 0).
"""

from __future__ import annotations

import numpy as np

BACKGROUND_COLOR = (1.0, 1.0, 1.0)
SHELF_COLOR = (0.85, 0.74, 0.58)
TARGET_COLOR = (0.9, 0.2, 0.2)  # the target's colour in the Meshcat scene (slax_drake/station/scene_world.py)
ACTION_COLOR = (1.0, 0.0, 1.0)  # magenta: in neither the depth colour map nor the label palette
# Object colours by index (object i has label i + 1): qualitative, none of them red or magenta.
OBJECT_PALETTE = (
    (0.12, 0.47, 0.71), (1.00, 0.50, 0.05), (0.17, 0.63, 0.17), (0.58, 0.40, 0.74), (0.55, 0.34, 0.29),
    (0.09, 0.75, 0.81), (0.74, 0.74, 0.13), (0.50, 0.50, 0.50), (0.68, 0.78, 0.91), (0.60, 0.87, 0.54),
    (0.77, 0.69, 0.84), (0.10, 0.30, 0.30),
)


def label_colors(n_objects: int) -> np.ndarray:
    """RGB colours (n_objects + 3, 3) indexed by label + 1: background (-1), shelf (0), objects 1..n, target n+1.

    A function of the object count only, so a label has the same colour in every step of a trial."""
    objects = [OBJECT_PALETTE[i % len(OBJECT_PALETTE)] for i in range(n_objects)]
    return np.array([BACKGROUND_COLOR, SHELF_COLOR, *objects, TARGET_COLOR], dtype=float)


def label_image_rgb(labels: np.ndarray, n_objects: int) -> np.ndarray:
    """The label image (H, W) as RGB (H, W, 3) in the fixed colours of :func:`label_colors`; labels outside
    [-1, n_objects + 1] are drawn as background."""
    colors = label_colors(n_objects)
    index = np.asarray(labels, dtype=np.int64) + 1
    index = np.where((index >= 0) & (index < len(colors)), index, 0)
    return colors[index]


def action_polyline_shelf(action: dict, object_y: float | None, shelf) -> np.ndarray:
    """The drawn way of ``action`` (a trial.json action: type, q, d or dx/dz) as points (N, 3) in the shelf frame.

    Push: the blade from ``q`` to ``q + (d, 0, 0)``. Suction: the cup from its contact ``q`` out to the bay's open
    face, across by ``dx`` and in until the object's centre (now at ``object_y``) is at y = ``dz``."""
    q = np.asarray(action["q"], dtype=float)
    if action["type"] == "push":
        return np.array([q, q + [action["d"], 0.0, 0.0]])
    y_out = -shelf.depth / 2.0 - 0.02
    y_in = q[1] + (action["dz"] - (object_y if object_y is not None else q[1]))
    x2 = q[0] + action["dx"]
    return np.array([q, [q[0], y_out, q[2]], [x2, y_out, q[2]], [x2, y_in, q[2]]])


def columns_to_shelf_x(camera, shelf) -> tuple[float, float]:
    """(slope, offset) of u = slope * x + offset: the image column u of ``camera`` where the point x (m) of the
    support surface's centre line (y = 0, z = 0, shelf frame) is seen. Exact for a camera that is only pitched
    (points at one depth project linearly); fitted over the bay's width otherwise."""
    x = np.linspace(-shelf.width / 2.0, shelf.width / 2.0, 21)
    u = camera.project(np.stack([x, np.zeros_like(x), np.zeros_like(x)], axis=-1))[:, 0]
    slope, offset = np.polyfit(x, u, 1)
    return float(slope), float(offset)


def _draw_action(ax, points_uv: np.ndarray, kind: str) -> None:
    if kind == "push":
        (u0, v0), (u1, v1) = points_uv
        ax.annotate("", xy=(u1, v1), xytext=(u0, v0),
                    arrowprops=dict(arrowstyle="-|>", color=ACTION_COLOR, lw=3, mutation_scale=20))
    else:
        ax.plot(points_uv[:, 0], points_uv[:, 1], color=ACTION_COLOR, lw=2.5)
        ax.annotate("", xy=points_uv[-1], xytext=points_uv[-2],
                    arrowprops=dict(arrowstyle="-|>", color=ACTION_COLOR, lw=3, mutation_scale=20))
        ax.plot(*points_uv[0], "o", color=ACTION_COLOR, ms=6)


def step_png(step: int, depth: np.ndarray, labels: np.ndarray, history, p1d, scene, action: dict | None = None,
             object_y: float | None = None, visible_fraction: float | None = None, tracks: dict | None = None) -> bytes:
    """:func:`step_figure` as PNG bytes (80 dpi)."""
    from slax_drake.io import figure_png

    return figure_png(step_figure(step, depth, labels, history, p1d, scene, action, object_y, visible_fraction,
                                  tracks), 80)


def step_figure(step: int, depth: np.ndarray, labels: np.ndarray, history, p1d, scene, action: dict | None = None,
                object_y: float | None = None, visible_fraction: float | None = None, tracks: dict | None = None):
    """The matplotlib figure of decision ``step``: ``depth`` (H, W) m and ``labels`` (H, W) as the planner read
    them, the 1D distributions ``p1d`` (P_t; None at the final observation, where none is computed) and
    ``history`` (P'_t), ``scene`` (its camera, shelf and object names), the ``action`` chosen there (a trial.json
    action, or None) with ``object_y``, its object's centre y before the action (m, for a suction's path), and
    the target's ``visible_fraction`` for the title. ``tracks``: {true object name: the tracker's name for it at
    that decision}; the legend and the action then name each object as trial.json and the step lines do
    ("track_7 (= object_7)")."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Patch

    h, w = labels.shape
    camera = scene.camera.with_resolution(w, h)
    n = len(scene.objects)
    target_mask = np.asarray(labels) == n + 1

    fig, axes = plt.subplots(1, 3, figsize=(16, 4.6), layout="constrained", gridspec_kw={"width_ratios": [1.1, 1, 1]})
    d = np.where(np.isfinite(depth) & (depth > 0), depth, np.nan)
    im = axes[0].imshow(d, cmap="viridis")
    fig.colorbar(im, ax=axes[0], fraction=0.046, pad=0.03, label="depth (m)")
    axes[0].set_title(f"step {step}: depth")
    axes[1].imshow(label_image_rgb(labels, n), interpolation="nearest")
    visible = "" if visible_fraction is None else f", target {visible_fraction * 100:.0f}% visible"
    axes[1].set_title(f"labels{visible}")
    present = set(int(v) for v in np.unique(labels))
    colors = label_colors(n)
    tracks = tracks or {}
    true_of = {track: name for name, track in tracks.items()}

    def named(name: str) -> str:
        if name in tracks:
            return f"{tracks[name]} (= {name})"
        return f"{name} (= {true_of[name]})" if name in true_of else name

    handles = [Patch(color=colors[i + 2], label=named(o.name)) for i, o in enumerate(scene.objects) if i + 1 in present]
    if target_mask.any():
        handles.append(Patch(color=TARGET_COLOR, label="target"))
    for ax in axes[:2]:
        ax.set_xlabel("image column u (px)")
        ax.set_ylabel("image row v (px)")
        if target_mask.any():
            ax.contour(target_mask.astype(float), levels=[0.5], colors=[TARGET_COLOR if ax is axes[0] else "black"],
                       linewidths=1.5)
        if action is not None:
            points = camera.project(action_polyline_shelf(action, object_y, scene.shelf))
            _draw_action(ax, points, action["type"])
        ax.set_xlim(-0.5, w - 0.5)
        ax.set_ylim(h - 0.5, -0.5)
    if action is not None:
        what = (f"push {named(action['object'])} d={action['d']:+.3f} m" if action["type"] == "push"
                else f"suction {named(action['object'])} dx={action['dx']:+.3f} m, to y={action['dz']:+.3f} m")
        handles.append(plt.Line2D([], [], color=ACTION_COLOR, lw=2.5, label=what))
    if target_mask.any():
        handles.append(plt.Line2D([], [], color="black", lw=1.5, label="target outline"))
    # Below the bay's floor the camera sees only background: room for the legend inside the image.
    axes[1].legend(handles=handles, loc="lower center", ncol=2, fontsize=7, framealpha=0.9)

    ax = axes[2]
    if history is not None:
        history = np.asarray(history, dtype=float)
        u = (np.arange(len(history)) + 0.5) * w / len(history) - 0.5  # coarse column centres in image columns
        if p1d is not None:
            ax.fill_between(u, np.asarray(p1d, dtype=float), color="tab:blue", alpha=0.35, step="mid", label="P_t")
        ax.plot(u, history, color="black", lw=1.3, ls="--", drawstyle="steps-mid", label="P'_t = min(P_t, P'_{t-1})")
        if p1d is None:
            ax.plot([], [], " ", label="P_t: none at the final observation")
        ax.legend(fontsize=8, loc="best")
    ax.set_xlim(-0.5, w - 0.5)
    ax.set_xlabel("image column u (px)")
    ax.set_ylabel("probability per column")
    slope, offset = columns_to_shelf_x(camera, scene.shelf)
    top = ax.secondary_xaxis("top", functions=(lambda uu: (uu - offset) / slope, lambda xx: slope * xx + offset))
    top.set_xlabel("shelf x (m) on the support's centre line", fontsize=8)
    ax.set_title("1D target distribution", pad=28)
    return fig


def step_png_of_record(record, step: int, depth, labels, history, p1d) -> bytes:
    """:func:`step_png` for decision ``step`` of a trial ``record`` (a ``TrialRecord``): the action chosen at that
    step, its object's position and the target's visible share come from ``record.data["steps_log"]``."""
    entries = [e for e in record.data.get("steps_log", ()) if e.get("step") == step]
    chosen = next((e for e in entries if "action" in e), None)
    entry = chosen or (entries[-1] if entries else {})
    action = chosen["action"] if chosen else None
    object_y = None
    if action is not None:
        pose = entry.get("hypotheses", {}).get(action["object"]) or entry.get("poses_before", {}).get(action["object"])
        object_y = (pose or {}).get("y")
    segments = entry.get("segments", {})  # this frame's segment -> true object
    tracks = {segments[seg]: track for track, seg in entry.get("segment_of", {}).items() if seg in segments}
    return step_png(step, depth, labels, history, p1d, record.scene, action=action, object_y=object_y,
                    visible_fraction=entry.get("visible_fraction"), tracks=tracks)
