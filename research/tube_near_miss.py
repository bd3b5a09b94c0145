"""How close a tall neighbour may stand to the tube's way in before the planner refuses a push.

A box ``a`` (8 x 8 x 10 cm) stands 12 cm deep in the bay at x = -0.10, 0 or +0.10 m; a tall box ``c`` (4 x 4 x
15 cm) stands in front, beside the lane where the planner inserts the tube to push ``a`` toward +x or -x, its near
face ``gap`` metres from the tube's surface at the exact insert pose (0 to 6 mm). Each push the action model offers
(station profile with the tube and hidden-space checks off, so that every gap gets a push) is planned by the Drake
planner of the default station; the script prints, per direction and position, the smallest gap that plans and,
with ``--list``, every verdict. The collision checker's padding is 2 mm, so a planner that decides at the exact
pose plans from a gap a little over 2 mm.

    python research/tube_near_miss.py [--list]
"""

from __future__ import annotations

import argparse
import dataclasses
import sys

import numpy as np

GAPS = np.round(np.arange(0.0, 0.0061, 0.0005), 4)  # m
POSITIONS = (-0.10, 0.0, 0.10)  # m, a's x


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--list", action="store_true", help="print every verdict")
    args = parser.parse_args(argv)
    from slax_drake.config import load_scenario
    from slax_drake.planning.planner import MotionPlanner
    from slax_drake.scene.model import SceneObject, planar_pose
    from slax_drake.scene.sampling import sample_scene
    from slax_drake.shelf.actions import ActionModel
    from slax_drake.shelf.tool import tool_config
    from slax_drake.station.scenario import load_station_scenario

    scenario = load_scenario("sim_configs/sim_shelf.yaml")
    tool = tool_config(scenario, "station", push_tube_check=False, push_hidden_check=False)
    planner = MotionPlanner(load_station_scenario(), tool)
    base = sample_scene(scenario, 4, seed=0)  # its shelf and camera

    def box(name, x, y, sx, sy, sz):
        return SceneObject(name, "box", (sx, sy, sz), planar_pose(x, y, sz / 2, 0.0))

    print("| push | a's x (m) | smallest gap that plans (mm) |")
    print("|---|---|---|")
    for sign in (+1, -1):
        for xa in POSITIONS:
            a = box("a", xa, 0.12, 0.08, 0.08, 0.10)
            tube_x = xa - sign * (0.04 + 0.015 + 0.004)  # a's face, a tube radius and the standoff
            plans = []
            for gap in GAPS:
                c = box("c", tube_x - sign * (0.015 + gap + 0.02), -0.15, 0.04, 0.04, 0.15)
                scene = dataclasses.replace(base.with_objects((a, c)), target=None)
                model = ActionModel(scene.shelf, scene.camera.position[:2], tool)
                push = next((p for p in model.enumerate(scene.objects, suctions=False).feasible
                             if p.name == "a" and np.sign(p.d) == sign), None)
                if push is None:
                    verdict = "not offered"
                else:
                    result = planner.plan(push, scene)
                    verdict = "plans" if result.feasible else result.reason.split(" [")[0]
                if verdict == "plans":
                    plans.append(gap)
                if args.list:
                    print(f"    {'+x' if sign > 0 else '-x'} a at {xa:+.2f} gap {gap * 1000:.1f} mm: {verdict}",
                          file=sys.stderr)
            first = f"{min(plans) * 1000:.1f}" if plans else "none up to 6 mm"
            print(f"| {'+x' if sign > 0 else '-x'} | {xa:+.2f} | {first} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
