"""Computing a station's reach map (:class:`slax_drake.shelf.reach.ReachMap`) with the motion planner.

    python -m slax_drake.planning.reach --station sim_configs/station_sim_shelf.yaml \\
        --out models/reach/station_sim_shelf.json --png models/reach/station_sim_shelf.png

For every grid node (x, y) of the bay floor (``step`` apart, from a tool-width inside the side walls to 5 cm from
the back), the empty shelf, and each layer: the tool waypoint the action model's action with parameter (x, y) puts
the tool at (the blade inserted for a push toward +x / -x: ``action_waypoints``'s "insert"; the cup at the seal of
a yaw-0 suction at height ``CUP_HEIGHT``: "seal"), and whether :meth:`MotionPlanner.reaches` finds a
collision-free IK solution from the observation pose with its seed library. One node takes about a second where
the arm does not reach (every seed is tried), less where it does.

The optional release layers (``--add-release``; :data:`slax_drake.shelf.reach.RELEASE_LAYERS`) are of a yaw-0
suction whose cup releases the object with its contact at (x, y), ``CUP_HEIGHT`` high: "back off" (the cup backed
off along the tube from there) and "retract" (the tool drawn back out in front of the opening, at either approach
margin: reached when either is).

The optional hold layers (``--add-hold``; :func:`slax_drake.shelf.reach.hold_layers`) are of the cup tip itself
while it holds an object (suction on, the blade up, the tool turned each of ``HOLD_YAWS_DEG`` about S z), at each
of ``HOLD_HEIGHTS``, on their own grid of y (:func:`hold_grid`: from ``HOLD_FRONT`` in front of the opening to the
map's deepest row, ``HOLD_STEP`` apart) and the map's x: the poses of a carry's pull-out, translation and push-in
and of the lowered placement. The map file is written after each layer, so a stopped run keeps what it computed
and a run again adds the layers still missing.

The optional pre-approach layers (``--add-approach``) are of a suction's first waypoint: the cup tip at the
planner's approach margins in front of the opening (``approach_ys``: one row per margin), suction off, the tool
turned; their x reaches ``APPROACH_HALF_WIDTH`` to either side (a turned tool's pre-approach lies far to the side
of a deep contact).
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import time

import numpy as np

from slax_drake.shelf.reach import (LAYERS, RELEASE_LAYERS, ReachMap, grid, hold_layers, hold_params, turned_cup_layers,
                                    turned_cup_params)

CUP_HEIGHT = 0.10  # m, the cup layer's contact height (contacts sit 1.5-18.5 cm high)
STEP = 0.05  # m
WALL_INSET = 0.035  # m: the first blade lane's centre from a side wall
BACK_INSET = 0.05  # m: the deepest node from the back wall
HOLD_FRONT = 0.27  # m: the hold layers' first row this far in front of the opening (a deep object pulled all the way out)
HOLD_STEP = 0.06  # m between the hold layers' rows
APPROACH_HALF_WIDTH = 0.6  # m: the pre-approach layers' x from -this to +this


def layer_waypoint(layer: str, x: float, y: float, scene, tool):
    """The tool waypoint of ``layer`` at the action parameter (x, y) (S, m)."""
    from slax_drake.planning.waypoints import action_waypoints
    from slax_drake.shelf.actions import Push
    from slax_drake.scene.model import SceneObject, planar_pose

    # action_waypoints reads the moved object's footprint (for a suction's carry); a small box behind the
    # contact, which the planning world does not hold
    dummy = SceneObject("reach_probe", "box", (0.06, 0.06, 0.06), planar_pose(x, y + 0.03, 0.03, 0.0))
    if layer in ("push+x", "push-x"):
        d = 0.05 if layer == "push+x" else -0.05
        wps = action_waypoints(Push(dummy.name, (x, y, tool.geometry.blade_height / 2), d), (dummy,), scene.shelf, tool)
        return next(w for w in wps if w.label == "insert")
    if layer == "cup":
        return cup_waypoint(x, y, 0.0, scene, tool)
    if layer in RELEASE_LAYERS:
        return release_waypoint(layer, x, y, scene, tool)
    yaw, height = turned_cup_params(layer)  # "cup@+20/6cm": turned 20 deg, the contact 6 cm high
    return cup_waypoint(x, y, yaw, scene, tool, height)


def release_waypoint(layer: str, x: float, y: float, scene, tool, approach_margin: float | None = None):
    """The "back off" or "retract" waypoint (``layer``) of a yaw-0 suction that releases its object with the cup's
    contact at (x, y, ``CUP_HEIGHT``) (S, m); ``approach_margin``: the retract's (default the planner's first)."""
    from slax_drake.planning.waypoints import APPROACH_MARGIN, action_waypoints
    from slax_drake.shelf.actions import Suction
    from slax_drake.scene.model import SceneObject, planar_pose

    dummy = SceneObject("reach_probe", "box", (0.06, 0.06, 0.06), planar_pose(x, y + 0.03, 0.03, 0.0))
    # no move: released where it was sealed (the back-off and retract read only where the cup releases)
    action = Suction(dummy.name, (x, y, CUP_HEIGHT), 0.0, y + 0.03, 0.0)
    margin = APPROACH_MARGIN if approach_margin is None else approach_margin
    wps = action_waypoints(action, (dummy,), scene.shelf, tool, approach_margin=margin)
    return next(w for w in wps if w.label == layer)


def cup_waypoint(x: float, y: float, yaw: float, scene, tool, height: float = CUP_HEIGHT):
    """The cup at the seal of a suction whose contact is (x, y, ``height``) (S, m) with the tool turned ``yaw``
    (rad) about S z."""
    from slax_drake.planning.waypoints import action_waypoints
    from slax_drake.shelf.actions import Suction
    from slax_drake.scene.model import SceneObject, planar_pose

    dummy = SceneObject("reach_probe", "box", (0.06, 0.06, 0.06), planar_pose(x, y + 0.03, 0.03, 0.0))
    wps = action_waypoints(Suction(dummy.name, (x, y, height), 0.0, y + 0.03, yaw), (dummy,), scene.shelf, tool)
    return next(w for w in wps if w.label == "seal")


def hold_waypoint(x: float, y: float, z: float, yaw: float, suction: bool = True):
    """The cup tip at (x, y, z) (S, m) holding an object, the tool turned ``yaw`` (rad) about S z: the pose of a
    lifted suction's "translate" waypoint (and of its pull-out, push-in and lowering) with the blade up, suction on;
    with ``suction`` False the pose of its "pre-approach"."""
    from slax_drake.planning.waypoints import ToolWaypoint, suction_rotation
    from slax_drake.station import robot as robot_model

    X = np.eye(4)
    X[:3, :3] = suction_rotation(yaw)
    X[:3, 3] = (x, y, z)
    if not suction:
        return ToolWaypoint("pre-approach", robot_model.CUP_TIP_FRAME, X, robot_model.SHAFT_BLADE_UP)
    return ToolWaypoint("translate", robot_model.CUP_TIP_FRAME, X, robot_model.SHAFT_BLADE_UP, contact=True,
                        suction=True, carried="clear")


def hold_grid(shelf, ys: np.ndarray, step: float = HOLD_STEP) -> np.ndarray:
    """The hold layers' y (S, m): from ``HOLD_FRONT`` in front of the opening to the map's deepest row ``ys[-1]``."""
    return grid(-shelf.depth / 2 - HOLD_FRONT, float(ys[-1]), step)


def add_hold_layers(station_path: str, base: ReachMap, out, layers=None, progress: bool = True,
                    family: str = "hold") -> ReachMap:
    """``base`` with the hold layers it lacks (``layers``: default every one of :func:`hold_layers`), on its x
    grid and :func:`hold_grid`; with ``family`` "approach" the pre-approach layers, on their grid (x within
    ``APPROACH_HALF_WIDTH``, the map's step; y at each approach margin); the map is written to ``out`` after each
    layer."""
    import dataclasses
    import json
    from pathlib import Path

    from slax_drake.config import load_scenario
    from slax_drake.io import write_text_atomic
    from slax_drake.planning.planner import MotionPlanner
    from slax_drake.shelf.tool import tool_config
    from slax_drake.scene.camera import Camera
    from slax_drake.scene.model import Scene
    from slax_drake.scene.sampling import shelf_of
    from slax_drake.station.scenario import load_station_scenario

    station = load_station_scenario(station_path)
    scenario = load_scenario(station.scene_config)
    shelf = shelf_of(scenario)
    scene = Scene(shelf, Camera.from_config(scenario.camera), (), None, 0)
    planner = MotionPlanner(station, tool_config(scenario, "station"))
    from slax_drake.shelf.actions import APPROACH_MARGINS

    if family == "hold":
        xs, ys = base.xs, (base.hold_ys if base.hold else hold_grid(shelf, base.ys))
        hold = dict(base.hold)
    else:
        step = float(base.xs[1] - base.xs[0])
        xs = base.approach_xs if base.approach else grid(-APPROACH_HALF_WIDTH, APPROACH_HALF_WIDTH, step)
        ys = base.approach_ys if base.approach else np.array(sorted(-shelf.depth / 2 - m for m in APPROACH_MARGINS))
        hold = dict(base.approach)
    rmap = base
    t0 = time.perf_counter()
    for layer in (hold_layers(family) if layers is None else layers):
        if layer in hold:
            continue
        yaw, z = hold_params(layer)
        ok = np.zeros((len(ys), len(xs)), bool)
        for j, y in enumerate(ys):
            for i, x in enumerate(xs):
                ok[j, i] = planner.reaches(scene, hold_waypoint(float(x), float(y), z, yaw, suction=family == "hold"))
        hold[layer] = ok
        if family == "hold":
            rmap = dataclasses.replace(rmap, hold_ys=np.asarray(ys, float), hold=dict(hold))
        else:
            rmap = dataclasses.replace(rmap, approach_xs=np.asarray(xs, float), approach_ys=np.asarray(ys, float),
                                       approach=dict(hold))
        write_text_atomic(Path(out), json.dumps(rmap.to_dict()) + "\n")
        if progress:
            print(f"{layer}: {int(ok.sum())} of {ok.size} nodes reached ({time.perf_counter() - t0:.0f} s)", flush=True)
    return rmap


def map_grid(shelf, step: float = STEP) -> tuple[np.ndarray, np.ndarray]:
    """(xs, ys) of a reach map's nodes on ``shelf`` (S, m): a tool-width inside the side walls, from 3 cm behind
    the opening to ``BACK_INSET`` from the back wall, ``step`` apart."""
    xs = grid(-shelf.width / 2 + WALL_INSET, shelf.width / 2 - WALL_INSET, step)
    ys = grid(-shelf.depth / 2 + 0.03, shelf.depth / 2 - BACK_INSET, step)
    return xs, ys


def compute_reach_map(station_path: str, step: float = STEP, progress: bool = True, layers=LAYERS,
                      base: ReachMap | None = None) -> ReachMap:
    """The reach map of ``layers`` on the station's empty shelf; with ``base``, its grid and layers (its hold and
    pre-approach layers included) are kept and ``layers`` computed on that grid and added (e.g. the turned-cup
    layers)."""
    from slax_drake.config import load_scenario
    from slax_drake.planning.planner import MotionPlanner
    from slax_drake.shelf.tool import tool_config
    from slax_drake.scene.camera import Camera
    from slax_drake.scene.model import Scene
    from slax_drake.scene.sampling import shelf_of
    from slax_drake.station.scenario import load_station_scenario

    station = load_station_scenario(station_path)
    scenario = load_scenario(station.scene_config)
    shelf = shelf_of(scenario)
    scene = Scene(shelf, Camera.from_config(scenario.camera), (), None, 0)
    tool = tool_config(scenario, "station")
    planner = MotionPlanner(station, tool)
    xs, ys = map_grid(shelf, step) if base is None else (base.xs, base.ys)
    reach = {} if base is None else dict(base.reach)
    t0 = time.perf_counter()
    from slax_drake.planning.waypoints import APPROACH_MARGINS

    for layer in layers:
        ok = np.zeros((len(ys), len(xs)), bool)
        if layer == "retract":  # in front of the opening: the same for every y; reached at either margin
            for i, x in enumerate(xs):
                ok[:, i] = any(planner.reaches(scene, release_waypoint(layer, float(x), float(ys[0]), scene, tool, m))
                               for m in APPROACH_MARGINS)
            reach[layer] = ok
            if progress:
                print(f"{layer}: {int(ok.sum())} of {ok.size} nodes reached ({time.perf_counter() - t0:.0f} s)",
                      flush=True)
            continue
        for j, y in enumerate(ys):
            for i, x in enumerate(xs):
                ok[j, i] = planner.reaches(scene, layer_waypoint(layer, float(x), float(y), scene, tool))
        reach[layer] = ok
        if progress:
            print(f"{layer}: {int(ok.sum())} of {ok.size} nodes reached ({time.perf_counter() - t0:.0f} s)", flush=True)
    heights = {layer: layer_heights(tool)[layer] for layer in reach}
    if base is None:
        return ReachMap(str(station_path), xs, ys, reach, heights)
    # the base's own-grid layers (hold, pre-approach) stay as they were
    return dataclasses.replace(base, reach=reach, heights=heights, _tables={})


def layer_heights(tool) -> dict:
    """The tool's height (m above the support) per layer of a map."""
    cups = {layer: turned_cup_params(layer)[1] for layer in turned_cup_layers()}
    return {"push+x": tool.geometry.blade_height / 2, "push-x": tool.geometry.blade_height / 2, "cup": CUP_HEIGHT, **cups,
            **{layer: CUP_HEIGHT for layer in RELEASE_LAYERS}}


def reach_png(rmap: ReachMap, shelf) -> bytes:
    """One panel per layer: reached nodes green, unreached red, over the bay's outline (S, top-down)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Rectangle

    from slax_drake.io import figure_png

    layers = list(rmap.reach)  # LAYERS, then any turned-cup layers
    cols = min(len(layers), 5)
    rows = -(-len(layers) // cols)
    fig, axes = plt.subplots(rows, cols, figsize=(4.2 * cols, 4.6 * rows), squeeze=False)
    for ax in axes.flat[len(layers):]:
        ax.set_visible(False)
    axes = axes.flat
    X, Y = np.meshgrid(rmap.xs, rmap.ys)
    for ax, layer in zip(axes, layers):
        ok = rmap.reach[layer]
        ax.add_patch(Rectangle((-shelf.width / 2, -shelf.depth / 2), shelf.width, shelf.depth, fill=False))
        ax.scatter(X[ok], Y[ok], c="#2ca02c", s=18, label="reached")
        ax.scatter(X[~ok], Y[~ok], c="#d62728", s=18, marker="x", label="not reached")
        ax.set_aspect("equal")
        ax.set_title(f"{layer} (z = {rmap.heights[layer]:.3f} m): {int(ok.sum())}/{ok.size}", fontsize=9)
        ax.set_xlabel("x (m)")
    axes[0].set_ylabel("y (m), into the shelf")
    axes[0].legend(fontsize=7, loc="lower left")
    fig.suptitle(f"reach map of {rmap.station} (the action's q; empty shelf, from the observation pose)", fontsize=9)
    fig.tight_layout()
    return figure_png(fig, 100)


def main(argv=None) -> int:
    from slax_drake.errors import UserError

    parser = argparse.ArgumentParser(description="compute a station's reach map")
    parser.add_argument("--station", required=True)
    parser.add_argument("--out", required=True, help="reach map JSON")
    parser.add_argument("--png", default=None)
    parser.add_argument("--step", type=float, default=STEP)
    parser.add_argument("--add-turned-cup", action="store_true",
                        help="read the map at --out and add the turned-cup layers it lacks, on its grid")
    parser.add_argument("--add-release", action="store_true",
                        help="read the map at --out and add the release layers (back off, retract) it lacks")
    parser.add_argument("--add-hold", action="store_true",
                        help="read the map at --out and add the hold layers (the carry's and the lowered placement's "
                             "cup poses) it lacks, writing it after each layer")
    parser.add_argument("--add-approach", action="store_true",
                        help="read the map at --out and add the pre-approach layers (a turned suction's first "
                             "waypoint) it lacks, writing it after each layer")
    args = parser.parse_args(argv)
    try:
        return _run(args)
    except UserError as e:  # a malformed or missing map or station file: one line, exit 2
        print(f"error: {e}", file=sys.stderr)
        return 2


def _run(args) -> int:
    """Computes the map (or its missing layers) that ``args`` asks for and writes it, and its picture."""
    from slax_drake.config import load_scenario
    from slax_drake.io import write_bytes_atomic, write_text_atomic
    from slax_drake.scene.sampling import shelf_of
    from slax_drake.shelf.reach import load_reach_map
    from slax_drake.station.scenario import load_station_scenario
    import json
    from pathlib import Path

    if args.add_hold or args.add_approach:
        rmap = load_reach_map(args.out)
        for family in ("hold",) * args.add_hold + ("approach",) * args.add_approach:
            rmap = add_hold_layers(args.station, rmap, args.out, family=family)
    elif args.add_release:
        base = load_reach_map(args.out)
        layers = tuple(layer for layer in RELEASE_LAYERS if layer not in base.reach)
        rmap = compute_reach_map(args.station, layers=layers, base=base)
    elif args.add_turned_cup:
        base = load_reach_map(args.out)
        layers = tuple(layer for layer in turned_cup_layers() if layer not in base.reach)
        rmap = compute_reach_map(args.station, layers=layers, base=base)
    else:
        rmap = compute_reach_map(args.station, args.step)
    write_text_atomic(Path(args.out), json.dumps(rmap.to_dict()) + "\n")
    if args.png:
        shelf = shelf_of(load_scenario(load_station_scenario(args.station).scene_config))
        write_bytes_atomic(Path(args.png), reach_png(rmap, shelf))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
