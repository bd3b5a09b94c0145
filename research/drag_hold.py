"""The drag grasp measured in Drake: heavy boxes the cup may not lift, dragged on the shelf floor.

    python research/drag_hold.py [--masses 0.5,1,2] [--heights 0.10,0.16] [--dx 0.10]

One box (``--depth`` deep along y, 0.12 m wide, of each height) stands alone on the sim shelf at x = -0.05 m,
y = --y, with a given mass (SceneObject.mass). The action model (station profile, the station YAML's cup: 0.4 N m
lift limit, 42.4 N pull, 0.64 N m twist) chooses lift or drag; the drag that moves it ``--dx`` across and back to
its depth (or, where a sideways drag would twist it off the cup, straight out and in to 5 cm nearer the
opening) is
planned by the motion planner and executed open loop in the Drake station (research/cup_hold.py measured the
lift the same way). A case is "as predicted" when the box ends within 1 cm and 5 deg of the model's placement,
upright (tilt under 5 deg); "toppled" when its tilt exceeds 20 deg. ``--yaw`` turns the box (the tool turns
toward its face, up to 30 deg). One line per case, a count per band of held
moment at the end.
"""

import argparse
import math
import time

from slax_drake.config import load_scenario
from slax_drake.planning.planner import MotionPlanner
from slax_drake.shelf.actions import GRAVITY, ActionModel, apply_action
from slax_drake.shelf.tool import tool_config
from slax_drake.scene.camera import Camera
from slax_drake.scene.model import Scene, SceneObject, planar_pose
from slax_drake.scene.sampling import shelf_of
from slax_drake.station.scenario import load_station_scenario
from slax_drake.systems.motion_run import run_motion
from slax_drake.systems.trial import station_tool_rules

X = -0.05
WIDTH = 0.12


def drag_case(scenario, station, tool, mass: float, height: float, depth: float, y: float, dx: float,
              yaw_deg: float = 0.0, shape: str = "box") -> dict:
    """Plans and executes one drag; returns what happened (``grip``, ``outcome``: "as predicted", "off",
    "toppled", "no motion" or the action model's refusal; the end offset in m and yaw/tilt in deg). ``shape``
    "cylinder": a cylinder ``depth`` in diameter instead of the box."""
    size = (WIDTH, depth, height) if shape == "box" else (depth, depth, height)
    box = SceneObject("object_0", shape, size, planar_pose(X, y, height / 2, math.radians(yaw_deg)), mass=mass)
    scene = Scene(shelf_of(scenario), Camera.from_config(scenario.camera), (box,), None, 0)
    model = ActionModel(scene.shelf, scene.camera.position, tool)
    found = model.enumerate((box,), pushes=False)
    action = next((a for a in found.feasible if abs(a.dx - dx) < 1e-9 and abs(a.dz - y) < 1e-9), None)
    if action is None:  # a drag that would twist the box off the cup goes straight out and back in
        action = next((a for a in found.feasible if abs(a.dx) < 1e-9 and abs(a.dz - (y - 0.05)) < 1e-9), None)
    row = dict(mass=mass, height=height, depth=depth, moment=mass * GRAVITY * depth / 2,
               dx=action.dx if action is not None else None,
               twist=tool.rules.drag_safety_factor * tool.rules.drag_friction * mass * GRAVITY * depth / 2)
    if action is None:
        return dict(row, grip="-", outcome=(found.rejected[0].reason if found.rejected else "no such placement"))
    row.update(grip=action.grip, seal_z=action.q[2], tool_yaw_deg=math.degrees(action.yaw))
    motion = MotionPlanner(station, tool).plan(action, scene)
    if not motion.feasible:
        return dict(row, outcome=f"no motion: {motion.reason[:70]}")
    poses = run_motion(station, scene, motion, box.name, times=[])
    (moved,) = apply_action((box,), action)
    end = poses["end"]
    off = math.hypot(end["x"] - float(moved.center[0]), end["y"] - float(moved.center[1]))
    dyaw = abs(math.degrees((end["yaw"] - float(moved.yaw) + math.pi / 2) % math.pi - math.pi / 2))
    if end["tilt_deg"] > 20.0:
        outcome = "toppled"
    elif off <= 0.01 and dyaw <= 5.0 and end["tilt_deg"] < 5.0:
        outcome = "as predicted"
    else:
        outcome = "off"
    return dict(row, outcome=outcome, off_cm=100 * off, dyaw_deg=dyaw, tilt_deg=end["tilt_deg"])


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--masses", default="0.5,1.0,2.0", help="box masses (kg)")
    parser.add_argument("--heights", default="0.10,0.16", help="box heights (m)")
    parser.add_argument("--depth", type=float, default=0.16, help="box depth along y (m)")
    parser.add_argument("--y", type=float, default=-0.10, help="box centre's y in the shelf frame (m)")
    parser.add_argument("--dx", type=float, default=0.10, help="the drag's translation along x (m)")
    parser.add_argument("--seal-friction", type=float, default=None,
                        help="plan with this drag_friction (a variant: a low value seals high, to show tipping)")
    parser.add_argument("--yaw", type=float, default=0.0, help="the box's yaw about the shelf's z (deg)")
    parser.add_argument("--shape", choices=("box", "cylinder"), default="box",
                        help="cylinder: one --depth in diameter (its curved face to the cup)")
    parser.add_argument("--twist-limit", type=float, default=None,
                        help="plan with this max_drag_twist (N m; a large value slides every drag across, to "
                             "measure where the seal slips)")
    args = parser.parse_args()
    scenario = load_scenario("sim_configs/sim_shelf.yaml")
    station = load_station_scenario("sim_configs/station_sim_shelf.yaml")
    rules = station_tool_rules(station)
    rules.pop("reach_map", None)  # the planner decides what the arm reaches
    if args.seal_friction is not None:
        rules["drag_friction"] = args.seal_friction
    if args.twist_limit is not None:
        rules["max_drag_twist"] = args.twist_limit
    tool = tool_config(scenario, "station", **rules)
    print(f"rules: {rules}\n")
    print("| mass (kg) | height (m) | held moment (N m) | twist asked (N m) | grip | dx (m) | seal z (cm) | outcome | "
          "offset (cm), yaw, tilt (deg) |")
    print("|---|---|---|---|---|---|---|---|---|")
    t0 = time.perf_counter()
    counts = {}
    for h in (float(v) for v in args.heights.split(",")):
        for m in (float(v) for v in args.masses.split(",")):
            r = drag_case(scenario, station, tool, m, h, args.depth, args.y, args.dx, args.yaw, args.shape)
            band = "<= 0.4 N m" if r["moment"] <= 0.4 else "> 0.4 N m"
            counts.setdefault((band, r["grip"], r["outcome"]), 0)
            counts[(band, r["grip"], r["outcome"])] += 1
            end = (f"{r['off_cm']:.1f}, {r['dyaw_deg']:.1f}, {r['tilt_deg']:.1f}" if "off_cm" in r else "")
            seal = f"{100 * r['seal_z']:.1f}" if "seal_z" in r else ""
            moved = f"{r['dx']:+.2f}" if r["dx"] is not None else ""
            print(f"| {m:.2f} | {h:.2f} | {r['moment']:.2f} | {r['twist']:.2f} | {r['grip']} | {moved} | {seal} | {r['outcome']} | {end} |",
                  flush=True)
    print("\n| band | grip | outcome | cases |\n|---|---|---|---|")
    for (band, grip, outcome), n in sorted(counts.items()):
        print(f"| {band} | {grip} | {outcome} | {n} |")
    print(f"\n{time.perf_counter() - t0:.0f} s")


if __name__ == "__main__":
    main()
