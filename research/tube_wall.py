"""How much room a turned suction's tube needs at the side walls' front edges for the planner to plan it.

    python research/tube_wall.py [--clearances 0,0.006,0.01,0.015] [--angles 33,37]

A box (0.10 x 0.08 x 0.10 m) stands alone on the sim shelf near a side wall, turned so that its camera-facing side
looks toward that wall; at 33-37 deg the action model (``station`` profile, the station cup's 10 deg seal limit)
turns the tool as far as the wall lets the tube pass its front edge, ``TUBE_CLEARANCE`` to spare
(:meth:`slax_drake.shelf.actions.ActionModel.tool_yaw`). For each clearance, the suction that moves the box 5 cm
toward the middle is planned by the motion planner; a row per case where the wall limits the turn (the tool turned
less than the face and than ``max_tool_yaw_deg``), and a count per clearance of the cases planned and of those
refused for the tube meeting the shelf. Boxes at three spots along each wall and three depths.
"""

import argparse
import itertools
import math
import sys

from slax_drake.config import load_scenario
from slax_drake.planning.planner import MotionPlanner
from slax_drake.shelf import actions
from slax_drake.shelf.tool import tool_config
from slax_drake.scene.camera import Camera
from slax_drake.scene.model import Scene, SceneObject, planar_pose
from slax_drake.scene.sampling import shelf_of
from slax_drake.station.scenario import load_station_scenario

SIZE = (0.10, 0.08, 0.10)
XS, YS = (0.10, 0.14, 0.18), (-0.12, -0.02, 0.08)  # |x| from the middle, y (m, S)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--clearances", default="0,0.006,0.01,0.015", help="TUBE_CLEARANCE values (m)")
    parser.add_argument("--angles", default="33,37", help="the boxes' turns toward the wall (deg)")
    args = parser.parse_args(argv)
    try:
        clearances = [float(v) for v in args.clearances.split(",")]
        angles = [float(v) for v in args.angles.split(",")]
    except ValueError as e:
        parser.error(f"--clearances and --angles take comma-separated numbers: {e}")
    if min(clearances) < 0:
        parser.error("--clearances must not be negative (m)")
    scenario = load_scenario("sim_configs/sim_shelf.yaml")
    station = load_station_scenario("sim_configs/station_sim_shelf.yaml")
    tool = tool_config(scenario, "station", max_seal_angle_deg=10.0, max_suction_moment=0.4)
    shelf, camera = shelf_of(scenario), Camera.from_config(scenario.camera)
    planner = MotionPlanner(station, tool)
    default = actions.TUBE_CLEARANCE
    print("| clearance (m) | box x, y (m) | face turn (deg) | tool turn (deg) | planned | why not |")
    print("|---|---|---|---|---|---|")
    counts = {}
    try:
        for clearance in clearances:
            actions.TUBE_CLEARANCE = clearance
            model = actions.ActionModel(shelf, camera.position[:2], tool)
            for x, y, angle, side in itertools.product(XS, YS, angles, (1, -1)):
                box = SceneObject("object_0", "box", SIZE, planar_pose(side * x, y, SIZE[2] / 2,
                                                                       math.radians(side * angle)))
                contact = model.suction_contact(box)
                if contact is None:
                    continue
                tool_yaw, face_yaw = model.tool_yaw(box, contact[:2]), model.face_yaw(box)
                if abs(tool_yaw) >= min(abs(face_yaw), math.radians(tool.rules.max_tool_yaw_deg)) - 1e-6:
                    continue  # the wall does not limit this turn
                offered = [a for a in model.enumerate((box,), pushes=False).feasible
                           if not a.drag and abs(a.dx + side * 0.05) < 1e-9]
                if not offered:
                    continue  # the seal angle left after the clamp is over the cup's limit
                scene = Scene(shelf, camera, (box,), None, 0)
                motion = planner.plan(offered[0], scene)
                reason = "" if motion.feasible else motion.reason.split(" [")[0]
                n, planned, shelf_hits = counts.get(clearance, (0, 0, 0))
                meets_shelf = not motion.feasible and "the shelf" in motion.failure.hits
                counts[clearance] = (n + 1, planned + motion.feasible, shelf_hits + meets_shelf)
                print(f"| {clearance:.3f} | {side * x:+.2f}, {y:+.2f} | {math.degrees(face_yaw):+.1f} | "
                      f"{math.degrees(tool_yaw):+.1f} | {'yes' if motion.feasible else 'no'} | {reason} |", flush=True)
    finally:
        actions.TUBE_CLEARANCE = default
    print("\n| clearance (m) | cases the wall limits | planned | refused: the tube meets the shelf |")
    print("|---|---|---|---|")
    for clearance, (n, planned, shelf_hits) in counts.items():
        print(f"| {clearance:.3f} | {n} | {planned} | {shelf_hits} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
