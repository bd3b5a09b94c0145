"""Which box-face angles the cup seals and holds in Drake, with the tool turned toward the face (issue 17 item 1)
and, for comparison, with the tube kept along the shelf's y.

    python research/yawed_suction.py [--angles 3,7,13,17,23,27,33,37,41,44] [--out results/yaw.json]

One box (0.08 x 0.10 x 0.12 m, 0.38 kg at 400 kg/m^3) alone on the sim shelf, turned by each angle, at two spots
(front left turned +angle, front right turned -angle). For each, the action model (``station`` profile with the
station cup's 10 deg seal limit) lists its suctions; the one that moves it 0.10 m toward the middle at the same
depth is planned (slax_drake.planning.planner) and executed open loop in the Drake station
(slax_drake.systems.motion_run). Counted per 10 deg band of the face's angle from the shelf's y: offered by the
model, planned, sealed (the box lifted > 5 mm when carried across), placed (its final pose within 2 cm / 10 deg of
the model's). Mode "turned": the station profile (``max_tool_yaw_deg`` 30). Mode "along y": the tube along y
(``max_tool_yaw_deg=0``) with the seal limit lifted (``max_seal_angle_deg=90``), i.e. what the cup does on a face
it meets at an angle.
"""

import argparse
import json
import math
import time
from pathlib import Path

from slax_drake.config import load_scenario
from slax_drake.evaluation.physics import action_matches
from slax_drake.planning.planner import MotionPlanner
from slax_drake.shelf.actions import ActionModel, apply_action
from slax_drake.shelf.tool import tool_config
from slax_drake.scene.camera import Camera
from slax_drake.scene.model import Scene, SceneObject, planar_pose
from slax_drake.scene.sampling import shelf_of
from slax_drake.station.scenario import load_station_scenario
from slax_drake.systems.motion_run import run_motion

SIZE = (0.08, 0.10, 0.12)
SPOTS = ((-0.12, -0.15, +1.0, +0.10), (0.12, -0.15, -1.0, -0.10))  # x, y, yaw sign, dx
MODES = {"turned": dict(max_seal_angle_deg=10.0, max_suction_moment=0.4),
         "along y": dict(max_seal_angle_deg=90.0, max_suction_moment=0.4, max_tool_yaw_deg=0.0)}
BANDS = ((0, 10), (10, 20), (20, 30), (30, 40), (40, 45))


def one_case(scenario, station, rules, angle, spot):
    x, y, sign, dx = spot
    box = SceneObject("object_0", "box", SIZE, planar_pose(x, y, SIZE[2] / 2, math.radians(sign * angle)))
    scene = Scene(shelf_of(scenario), Camera.from_config(scenario.camera), (box,), None, 0)
    tool = tool_config(scenario, "station", **rules)
    model = ActionModel(scene.shelf, scene.camera.position[:2], tool)
    offered = [a for a in model.enumerate((box,), pushes=False).feasible
               if abs(a.dx - dx) < 1e-9 and abs(a.dz - y) < 1e-9]
    row = {"angle": angle, "spot": [x, y], "offered": bool(offered), "planned": False, "sealed": False,
           "placed": False}
    if not offered:
        return row
    action = offered[0]
    row["tool_yaw_deg"] = round(math.degrees(action.yaw), 2)
    motion = MotionPlanner(station, tool).plan(action, scene)
    if not motion.feasible:
        row["reason"] = motion.reason
        return row
    row["planned"] = True
    carried = next(t for label, t in motion.waypoint_times if label == "translate")
    poses = run_motion(station, scene, motion, box.name, times=[carried])
    row["sealed"] = poses[carried]["z"] > SIZE[2] / 2 + 0.005
    (moved,) = apply_action((box,), action)
    expected = {"x": float(moved.center[0]), "y": float(moved.center[1]), "yaw": float(moved.yaw)}
    row["placed"] = bool(action_matches(expected, poses["end"])) and poses["end"]["tilt_deg"] < 20.0
    row["end"] = {k: round(v, 4) for k, v in poses["end"].items()}
    return row


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--angles", default="3,7,13,17,23,27,33,37,41,44", help="face angles (deg)")
    parser.add_argument("--out", default=None, help="write every case as JSON here")
    args = parser.parse_args()
    angles = [float(a) for a in args.angles.split(",")]
    scenario = load_scenario("sim_configs/sim_shelf.yaml")
    station = load_station_scenario("sim_configs/station_sim_shelf.yaml")
    rows = {}
    t0 = time.perf_counter()
    for mode, rules in MODES.items():
        rows[mode] = [dict(one_case(scenario, station, rules, a, spot), mode=mode) for a in angles for spot in SPOTS]
    print(f"{sum(len(r) for r in rows.values())} cases in {time.perf_counter() - t0:.0f} s\n")
    print("| face angle | mode | cases | offered by the model | planned | sealed | placed (2 cm / 10 deg) |")
    print("|---|---|---|---|---|---|---|")
    for lo, hi in BANDS:
        for mode in MODES:
            sel = [r for r in rows[mode] if lo <= r["angle"] < hi or (hi == 45 and r["angle"] == 45)]
            if sel:
                print(f"| {lo}-{hi} deg | {mode} | {len(sel)} | " + " | ".join(
                    str(sum(r[k] for r in sel)) for k in ("offered", "planned", "sealed", "placed")) + " |")
    if args.out:
        Path(args.out).parent.mkdir(parents=True, exist_ok=True)
        Path(args.out).write_text(json.dumps(rows, indent=1))


if __name__ == "__main__":
    main()
