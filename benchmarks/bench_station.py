"""Real-time factor of the station: 10 objects at rest on the sim shelf, the arm holding the observation pose,
no camera rendering (the RgbdSensor renders only when its port is evaluated; here it is left out).

Run on one core:  taskset -c 0 python benchmarks/bench_station.py [--objects 10] [--seconds 2] [--seed 0]
"""

import argparse
import time

import numpy as np


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--objects", type=int, default=10)
    parser.add_argument("--seconds", type=float, default=2.0)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--station", default="sim_configs/station_sim_shelf.yaml")
    parser.add_argument("--time-step", type=float, default=None, help="override plant_config.time_step (s)")
    args = parser.parse_args()

    from pydrake.systems.analysis import Simulator

    from slax_drake.config import load_scenario
    from slax_drake.scene.sampling import sample_scene
    from slax_drake.systems.station import MakeStation, load_station_scenario

    scenario = load_station_scenario(args.station)
    if args.time_step is not None:
        scenario.plant_config.time_step = args.time_step
    scene = sample_scene(load_scenario(scenario.scene_config), args.objects, args.seed)
    t0 = time.perf_counter()
    diagram = MakeStation(scenario, scene, camera=False)
    build = time.perf_counter() - t0
    simulator = Simulator(diagram)
    context = simulator.get_mutable_context()
    q = diagram.GetOutputPort("measured_state").Eval(context)[:9]
    diagram.GetInputPort("desired_state").FixValue(context, np.concatenate([q, np.zeros(9)]))
    diagram.GetInputPort("suction_command").FixValue(context, [0.0])
    simulator.Initialize()
    simulator.AdvanceTo(0.1)  # warm-up
    t0 = time.perf_counter()
    simulator.AdvanceTo(0.1 + args.seconds)
    wall = time.perf_counter() - t0
    print(f"station: {args.objects} objects + target, time_step {scenario.plant_config.time_step} s, "
          f"build {build:.2f} s")
    print(f"simulated {args.seconds:.2f} s in {wall:.2f} s wall: real-time factor {args.seconds / wall:.2f}x")


if __name__ == "__main__":
    main()
