"""The cup's holding limit confirmed in Drake (issue 17 item 2): which held moments the sealed cup carries.

    python research/cup_hold.py [--masses 0.2,0.3,0.35,0.4,0.45,0.5,0.6,0.7,0.8]

The cup's model (slax_drake.station.scenario.SuctionParameters): 60 kPa on a 15 mm-radius cup pulls
F = 42.4 N; acting at the rim it resists F x r = 0.64 N m before the lip peels; the station plans with at most
0.4 N m. Here one long box (0.08 m wide, 0.20 m deep, 0.10 m tall: its centre 0.10 m behind the face the cup
seals) stands alone at the front of the sim shelf with a given mass (SceneObject.mass), so the held moment is
m g 0.10 m. Its suction (moved 0.10 m across, put back at the same depth) is planned without the moment limit
and executed open loop in the Drake station; a case is held when the box ends within 2 cm / 10 deg of the model's
placement, upright.
"""

import argparse
import math
import time

from slax_drake.config import load_scenario
from slax_drake.evaluation.physics import action_matches
from slax_drake.planning.planner import MotionPlanner
from slax_drake.shelf.actions import GRAVITY, ActionModel, apply_action
from slax_drake.shelf.tool import tool_config
from slax_drake.scene.camera import Camera
from slax_drake.scene.model import Scene, SceneObject, planar_pose
from slax_drake.scene.sampling import shelf_of
from slax_drake.station.scenario import load_station_scenario
from slax_drake.systems.motion_run import run_motion

SIZE = (0.08, 0.20, 0.10)
X, Y, DX = -0.10, -0.15, 0.10


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--masses", default="0.2,0.3,0.35,0.4,0.45,0.5,0.6,0.7,0.8", help="box masses (kg)")
    args = parser.parse_args()
    scenario = load_scenario("sim_configs/sim_shelf.yaml")
    station = load_station_scenario("sim_configs/station_sim_shelf.yaml")
    cup = station.suction
    tool = tool_config(scenario, "station", max_seal_angle_deg=10.0)  # no moment limit: every mass is planned
    print(f"cup: pull {cup.max_force:.1f} N, lip moment {cup.lip_moment:.2f} N m, planning limit "
          f"{cup.max_held_moment} N m\n")
    print("| mass (kg) | held moment (N m) | sealed | held and placed | final offset (cm), tilt (deg) |")
    print("|---|---|---|---|---|")
    t0 = time.perf_counter()
    for m in (float(v) for v in args.masses.split(",")):
        box = SceneObject("object_0", "box", SIZE, planar_pose(X, Y, SIZE[2] / 2, 0.0), mass=m)
        scene = Scene(shelf_of(scenario), Camera.from_config(scenario.camera), (box,), None, 0)
        model = ActionModel(scene.shelf, scene.camera.position[:2], tool)
        action = next(a for a in model.enumerate((box,), pushes=False).feasible
                      if abs(a.dx - DX) < 1e-9 and abs(a.dz - Y) < 1e-9)
        moment = m * GRAVITY * math.hypot(X - action.q[0], Y - action.q[1])
        motion = MotionPlanner(station, tool).plan(action, scene)
        if not motion.feasible:
            print(f"| {m:.2f} | {moment:.2f} | no motion: {motion.reason[:60]} | | |")
            continue
        carried = next(t for label, t in motion.waypoint_times if label == "translate")
        poses = run_motion(station, scene, motion, box.name, times=[carried])
        (moved,) = apply_action((box,), action)
        end = poses["end"]
        expected = {"x": float(moved.center[0]), "y": float(moved.center[1]), "yaw": float(moved.yaw)}
        placed = bool(action_matches(expected, end)) and end["tilt_deg"] < 20.0
        off = 100 * math.hypot(end["x"] - expected["x"], end["y"] - expected["y"])
        print(f"| {m:.2f} | {moment:.2f} | {'yes' if poses[carried]['z'] > SIZE[2] / 2 + 0.005 else 'no'} | "
              f"{'yes' if placed else 'no'} | {off:.1f}, {end['tilt_deg']:.0f} |")
    print(f"\n{time.perf_counter() - t0:.0f} s")


if __name__ == "__main__":
    main()
