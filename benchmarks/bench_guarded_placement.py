"""Guarded placements in the Drake station, with and without an object the robot cannot see in the way.

    python benchmarks/bench_guarded_placement.py                       # every case below, one line each
    python benchmarks/bench_guarded_placement.py --masses 0.2 --dz 0.25 --hidden none,wall
    python benchmarks/bench_guarded_placement.py --station my_station.yaml   # another guarded_stop_force

The believed scene: a wide box at the front left (0.30 x 0.06 x 0.30 m, at x = -0.12, y = -0.15) and the carried
box (0.08 x 0.08 x 0.10 m at x = +0.20, y = -0.10, of each mass in ``--masses``), suctioned straight back to y =
d_z (``--dz``; the station profile with the sim station's cup limits and suction_hidden_rule=guarded marks it
guarded: the space behind the box is hidden). The true scene adds, in the carried box's lane (x = +0.20):

- ``none``: nothing;
- ``wall``: a 0.5 kg box 0.08 x 0.08 x 0.10 m against the back wall (y = +0.255);
- ``free``: a 0.3 kg box 0.08 x 0.08 x 0.10 m standing free, its front 0.08 m before the placement's back;
- ``tall``: a 0.2 kg box 0.06 x 0.06 x 0.20 m standing free there (tips more easily than it slides).

Per case: stopped or completed, how far short of d_z the carried box rests (m), the peak resisting force the guard
saw (N), how far the hidden box moved (m) and the largest tilt of the two (deg; toppled: > 20 deg).
"""

import argparse
import math


def _box(name, x, y, size, mass):
    from slax_drake.scene.model import SceneObject, planar_pose

    return SceneObject(name, "box", size, planar_pose(x, y, size[2] / 2, 0.0), mass=mass)


def main():
    from slax_drake.config import load_scenario
    from slax_drake.planning.planner import MotionPlanner
    from slax_drake.scene.camera import Camera
    from slax_drake.scene.model import Scene
    from slax_drake.scene.sampling import shelf_of
    from slax_drake.shelf.actions import ActionModel
    from slax_drake.shelf.tool import tool_config
    from slax_drake.station.scenario import load_station_scenario
    from slax_drake.systems.motion_run import run_guarded_motion
    from slax_drake.systems.trial import station_tool_rules

    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--masses", default="0.2,0.6,1.0", help="kg of the carried box")
    parser.add_argument("--dz", default="0.25,0.15", help="placement depths d_z (m, S y of the box's centre)")
    parser.add_argument("--hidden", default="none,wall,free,tall")
    parser.add_argument("--station", default="sim_configs/station_sim_shelf.yaml",
                        help="the station file (a copy with another guarded_stop_force, say)")
    args = parser.parse_args()
    scenario = load_scenario("sim_configs/sim_shelf.yaml")
    station = load_station_scenario(args.station)
    rules = {k: v for k, v in station_tool_rules(station).items() if k != "reach_map"}
    tool = tool_config(scenario, "station", **{**rules, "suction_hidden_rule": "guarded"})
    shelf, camera = shelf_of(scenario), Camera.from_config(scenario.camera)
    counts = {"stopped": 0, "completed": 0, "toppled": 0, "runs": 0}
    for mass in (float(m) for m in args.masses.split(",")):
        wall = _box("object_0", -0.12, -0.15, (0.30, 0.06, 0.30), 0.3)
        carried = _box("object_1", 0.20, -0.10, (0.08, 0.08, 0.10), mass)
        believed = Scene(shelf, camera, (wall, carried), None, 0)
        model = ActionModel(shelf, camera.position, tool)
        planner = MotionPlanner(station, tool)
        for dz in (float(d) for d in args.dz.split(",")):
            action = next((a for a in model.enumerate(believed.objects, pushes=False, only=("object_1",)).feasible
                           if a.guarded and abs(a.dx) < 1e-9 and abs(a.dz - dz) < 1e-9), None)
            if action is None:
                print(f"mass {mass} kg, d_z {dz}: no guarded candidate")
                continue
            motion = planner.plan(action, believed)
            if not motion.feasible:
                print(f"mass {mass} kg, d_z {dz}: no motion ({motion.reason})")
                continue
            for case in args.hidden.split(","):
                front = dz + 0.04 + 0.0  # the placement's back (m)
                hidden = {"none": None,
                          "wall": _box("object_2", 0.20, 0.255, (0.08, 0.08, 0.10), 0.5),
                          "free": _box("object_2", 0.20, front - 0.08 + 0.04, (0.08, 0.08, 0.10), 0.3),
                          "tall": _box("object_2", 0.20, front - 0.08 + 0.03, (0.06, 0.06, 0.20), 0.2)}[case]
                if hidden is not None and hidden.center[1] + hidden.size[1] / 2 > shelf.depth / 2 - 0.004:
                    hidden = _box("object_2", 0.20, shelf.depth / 2 - 0.005 - hidden.size[1] / 2, hidden.size,
                                  hidden.mass)
                objects = believed.objects + ((hidden,) if hidden is not None else ())
                names = ["object_1"] + (["object_2"] if hidden is not None else [])
                poses, record = run_guarded_motion(station, Scene(shelf, camera, objects, None, 0), believed, motion,
                                                   planner, names)
                tilt = max(p["tilt_deg"] for p in poses.values())
                moved = (math.hypot(poses["object_2"]["x"] - hidden.center[0], poses["object_2"]["y"] - hidden.center[1])
                         if hidden is not None else 0.0)
                counts["runs"] += 1
                counts["stopped" if record["stopped"] else "completed"] += 1
                counts["toppled"] += tilt > 20.0
                print(f"mass {mass:.1f} kg, d_z {dz:+.2f} m, hidden {case:5s}: "
                      f"{'stopped ' if record['stopped'] else 'completed'} short {dz - poses['object_1']['y']:+.3f} m, "
                      f"peak {record['peak_force_n']:.1f} N, hidden moved {moved:.3f} m, max tilt {tilt:.1f} deg",
                      flush=True)
    print(f"{counts['runs']} runs: {counts['stopped']} stopped, {counts['completed']} completed, "
          f"{counts['toppled']} with an object tilted > 20 deg")


if __name__ == "__main__":
    main()
