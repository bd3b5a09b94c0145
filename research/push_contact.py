"""Blade pushes measured in Drake: where along the box's side the blade meets it, and how far the box turns.

    python research/push_contact.py [--sizes 0.08x0.16,...] [--yaws 0,15] [--masses 0.3,1.0] [--d 0.10,-0.10] \
        [--contacts front,centre] [--heights 0.05,0.12]

One box stands alone on the sim shelf at x = 0, y = ``--y`` (S), of each size of ``--sizes`` (width along x by
depth along y, m; ``--heights`` tall, 0.12 m by default) and mass. The action model (station profile, the station YAML's cup limits) gives
the push of ``d``; the motion planner plans it and the Drake station executes it open loop (as
research/drag_hold.py does for drags), and the quasi-static model (slax_drake.shelf.pushing, the push_turn rule)
predicts it too. ``--contacts`` picks where the blade's tip goes: "front", the action
model's (``ActionModel.blade_depth``: the blade spans the box's side from 3.5 cm in front of it to
``push_contact_depth`` past its front), or "centre", the blade's middle level with the box's centre, so that
the push's line of action passes through the box's centre of friction on the floor (the first-order model
translates the box without turning it). A case is "as predicted" when the box ends within 2 cm and 10 deg of
each prediction (the first-order translation's, the quasi-static model's), the physics benchmark's test. One line
per case, a count per contact and prediction at the end.
"""

import argparse
import dataclasses
import math
import time

from slax_drake.config import load_scenario
from slax_drake.planning.planner import MotionPlanner
from slax_drake.planning.waypoints import BLADE_HALF_LENGTH
from slax_drake.shelf.actions import ActionModel, Push, apply_action
from slax_drake.shelf.pushing import push_pose
from slax_drake.shelf.tool import tool_config
from slax_drake.scene.footprint import Footprint
from slax_drake.scene.camera import Camera
from slax_drake.scene.model import Scene, SceneObject, planar_pose
from slax_drake.scene.sampling import shelf_of
from slax_drake.station.scenario import load_station_scenario
from slax_drake.systems.motion_run import run_motion
from slax_drake.systems.trial import station_tool_rules

def push_case(scenario, station, tool, size_xy, mass: float, y: float, d: float, contact: str,
              yaw_deg: float = 0.0, height: float = 0.12) -> dict:
    """Plans and executes one push of a lone box ``height`` (m) tall; returns the case's row (``outcome``: "as
    predicted", "off", "toppled", "no motion" or the action model's refusal; the end's offset (cm), its part
    along the push (cm, positive: farther than d) and its turn (deg))."""
    size = (size_xy[0], size_xy[1], height)
    box = SceneObject("object_0", "box", size, planar_pose(0.0, y, height / 2, math.radians(yaw_deg)), mass=mass)
    scene = Scene(shelf_of(scenario), Camera.from_config(scenario.camera), (box,), None, 0)
    model = ActionModel(scene.shelf, scene.camera.position, tool)
    found = model.enumerate((box,), suctions=False)
    action = next((a for a in found.feasible if abs(a.d - d) < 1e-9), None)
    row = dict(size=size_xy, mass=mass, d=d, contact=contact, yaw=yaw_deg)
    if action is None:
        return dict(row, outcome="no such push")
    if contact == "centre":
        action = dataclasses.replace(action, q=(action.q[0], y + BLADE_HALF_LENGTH, action.q[2]))
    row["tip_y"] = action.q[1]
    motion = MotionPlanner(station, tool).plan(action, scene)
    if not motion.feasible:
        return dict(row, outcome=f"no motion: {motion.reason[:70]}")
    end = run_motion(station, scene, motion, box.name, times=[])["end"]
    (moved,) = apply_action((box,), dataclasses.replace(action, turns=False))  # the first-order translation
    off = math.hypot(end["x"] - float(moved.center[0]), end["y"] - float(moved.center[1]))
    turn = abs(math.degrees(math.remainder(end["yaw"] - math.radians(yaw_deg), 2 * math.pi)))
    outcome = ("toppled" if end["tilt_deg"] > 20.0 else
               "as predicted" if off <= 0.02 and turn <= 10.0 else "off")
    # the quasi-static model's prediction (slax_drake.shelf.pushing) of the same push
    sign = 1.0 if d > 0 else -1.0
    qx, qy, qyaw = push_pose(Footprint.of(box), sign, abs(d), action.q[1] - 2 * BLADE_HALF_LENGTH, action.q[1])
    q_off = math.hypot(end["x"] - qx, end["y"] - qy)
    q_turn = abs(math.degrees(math.remainder(end["yaw"] - qyaw, 2 * math.pi)))
    q_outcome = "as predicted" if end["tilt_deg"] <= 20.0 and q_off <= 0.02 and q_turn <= 10.0 else "off"
    return dict(row, outcome=outcome, off_cm=100 * off, dy_cm=100 * (end["y"] - y),
                along_cm=100 * sign * (end["x"] - float(moved.center[0])), turn_deg=turn,
                q_outcome=q_outcome, q_off_cm=100 * q_off, q_turn_deg=q_turn)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", default="0.08x0.16,0.16x0.16,0.18x0.10,0.10x0.10",
                        help="box footprints, width along x by depth along y (m)")
    parser.add_argument("--masses", default="0.3,1.0", help="box masses (kg)")
    parser.add_argument("--d", default="0.10,-0.10", help="push distances along x (m)")
    parser.add_argument("--yaws", default="0", help="the boxes' yaws about the shelf's z (deg)")
    parser.add_argument("--y", type=float, default=-0.05, help="the box centre's y in the shelf frame (m)")
    parser.add_argument("--contacts", default="front,centre", help="front (the action model's), centre")
    parser.add_argument("--heights", default="0.12", help="box heights (m)")
    args = parser.parse_args(argv)
    try:
        sizes = [tuple(float(v) for v in size.split("x")) for size in args.sizes.split(",")]
        masses, ds, yaws, heights = ([float(v) for v in text.split(",")]
                                     for text in (args.masses, args.d, args.yaws, args.heights))
    except ValueError as e:
        parser.error(f"--sizes, --masses, --d, --yaws and --heights take comma-separated numbers (sizes "
                     f"WIDTHxDEPTH): {e}")
    contacts = args.contacts.split(",")
    if any(len(size) != 2 or min(size) <= 0 for size in sizes) or set(contacts) - {"front", "centre"}:
        parser.error("each size is WIDTHxDEPTH in metres, both positive; --contacts takes front and centre")
    if min(heights) <= 0:
        parser.error("--heights must be positive (m)")
    scenario = load_scenario("sim_configs/sim_shelf.yaml")
    station = load_station_scenario("sim_configs/station_sim_shelf.yaml")
    rules = station_tool_rules(station)
    rules.pop("reach_map", None)  # the planner decides what the arm reaches
    tool = tool_config(scenario, "station", **rules)
    print("| box (m) | yaw (deg) | mass (kg) | d (m) | contact | blade tip y (m) | first-order: outcome | offset (cm) | "
          "farther (cm) | deeper (cm) | turn (deg) | quasi-static: outcome | offset (cm), yaw off (deg) |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    t0 = time.perf_counter()
    counts = {}
    for size_xy, height in ((s, h) for s in sizes for h in heights):
        size = f"{size_xy[0]:.2f}x{size_xy[1]:.2f}x{height:.3f}"
        for m in masses:
            for d in ds:
                for yaw in yaws:
                    for contact in contacts:
                        r = push_case(scenario, station, tool, size_xy, m, args.y, d, contact, yaw, height)
                        for model, outcome in (("first-order", r["outcome"]), ("quasi-static", r.get("q_outcome"))):
                            if outcome is not None:
                                counts[(contact, model, outcome)] = counts.get((contact, model, outcome), 0) + 1
                        end = (f"{r['off_cm']:.1f} | {r['along_cm']:+.1f} | {r['dy_cm']:+.1f} | {r['turn_deg']:.1f} | {r['q_outcome']} | "
                               f"{r['q_off_cm']:.1f}, {r['q_turn_deg']:.1f}" if "off_cm" in r else " | | | | | ")
                        tip = f"{r['tip_y']:+.3f}" if "tip_y" in r else ""
                        print(f"| {size} | {yaw:+.0f} | {m:.2f} | {d:+.2f} | {contact} | {tip} | {r['outcome']} | "
                              f"{end} |", flush=True)
    print("\n| contact | prediction | outcome | cases |\n|---|---|---|---|")
    for (contact, model, outcome), n in sorted(counts.items()):
        print(f"| {contact} | {model} | {outcome} | {n} |")
    print(f"\n{time.perf_counter() - t0:.0f} s")


if __name__ == "__main__":
    main()  # exits 2 with one line on bad arguments (argparse)
