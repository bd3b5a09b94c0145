"""Real-time factor of the station: 10 objects at rest on the sim shelf, the arm holding the observation pose,
no camera rendering (the RgbdSensor renders only when its port is evaluated; here it is left out).

Run on one core:  taskset -c 0 python benchmarks/bench_station.py [--objects 10] [--seconds 3] [--seed 0]
                  [--time-step 0.005] [--approximation lagged] [--sleep]

It prints the real-time factor from wall-clock time and from the process's CPU time (``time.process_time``), each
the best of ``--repeats`` consecutive segments: on a shared machine the CPU-time figure is the steadier one, but
neither is immune to other processes on the same core.

What made the station faster (measured with this script, 10 objects + target, seed 0, one core of a loaded
2-core machine; CPU-time real-time factor):

- 0.75x at 2 ms before any change (83 resting contacts).
- The gravity-compensation plant of the robot alone had been added to the diagram as a subsystem: a continuous
  plant, whose 22 states the simulator integrated with RK3 every step for nothing (17 % of the profile). It is now
  held outside the diagram: 0.75x -> 1.27x at 2 ms. No accuracy cost.
- Each object's own shape no longer touches the support board (its corner/rim spheres carry it): one contact
  fewer per object, and the resting objects stopped chattering (max |v| 1e-2 -> 1e-8 m/s), so the contact solver
  converges at once: 1.27x -> 1.8x at 2 ms. Cost: a toppled cylinder lying on its side rests on rim spheres.
- 6 instead of 8 contact spheres per cylinder rim (72 -> 58 contacts in this scene): about 1.2x. Cost: a cylinder
  tips over a hexagon (narrowest half-width 0.87 r instead of 0.92 r; a real one: r).
- Plant step 5 ms instead of 2 ms (same 'lagged' SAP approximation): about 2.5-3x. Cost: objects settle 0.2 mm
  from their JSON pose instead of 0.02 mm (test limit 1 mm); the blade push moves a box 0.2 mm less; the
  suction fixture holds its 0.5 kg box within 0.3 mm either way. At 10 ms it is about 2x faster again, but the
  settling error reaches 0.67 mm, too close to the 1 mm limit to be the default.
- Measured and not kept: SAP instead of lagged (no faster at 5 ms); filtering the robot's base, torso and head
  against the world (about 5 %, within noise, and only true for some shelf placements).
- ``--sleep``: resting objects far from the robot and from moving objects are locked out of the step
  (slax_drake.systems.sleep.ObjectSleep, a Simulator monitor). Interleaved in one process (same load): 8.6x
  against 6.0x CPU. Cost: a sleeping object is fixed until the wake test (every 20 ms, 5 cm plus a speed bound)
  frees it; the push test gives the same box displacement with and without sleep (to 1e-5 mm).

Result (one core, a machine shared with other jobs at a load average of about 8 on 2 cores, so wall time is
inflated; 10 objects + target, 5 ms): without sleep 4.6-6.2x CPU-time (3.1-4.3x wall); with --sleep 7.0-9.3x
CPU-time (4.6-7.2x wall). Of the remaining awake-step cost, building the contact problem is about 60 % (in
proportion to the number of resting contacts) and the geometry query about 20 %.
"""

import argparse
import time

import numpy as np


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--objects", type=int, default=10)
    parser.add_argument("--seconds", type=float, default=3.0, help="simulated seconds, split into --repeats segments")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--station", default="sim_configs/station_sim_shelf.yaml")
    parser.add_argument("--time-step", type=float, default=None, help="override plant_config.time_step (s)")
    parser.add_argument("--approximation", default=None, help="override plant_config.discrete_contact_approximation")
    parser.add_argument("--sleep", action="store_true", help="let resting objects sleep (slax_drake.systems.sleep)")
    args = parser.parse_args()

    from pydrake.systems.analysis import Simulator

    from slax_drake.config import load_scenario
    from slax_drake.scene.sampling import sample_scene
    from slax_drake.station.scenario import load_station_scenario
    from slax_drake.systems.station import MakeStation

    scenario = load_station_scenario(args.station)
    if args.time_step is not None:
        scenario.plant_config.time_step = args.time_step
    if args.approximation is not None:
        scenario.plant_config.discrete_contact_approximation = args.approximation
    scene = sample_scene(load_scenario(scenario.scene_config), args.objects, args.seed)
    t0 = time.perf_counter()
    diagram = MakeStation(scenario, scene, camera=False)
    build = time.perf_counter() - t0
    simulator = Simulator(diagram)
    context = simulator.get_mutable_context()
    sleep = None
    if args.sleep:
        from slax_drake.systems.sleep import ObjectSleep

        sleep = ObjectSleep(diagram)
        sleep.install(simulator)
    q = diagram.GetOutputPort("measured_state").Eval(context)[:9]
    diagram.GetInputPort("desired_state").FixValue(context, np.concatenate([q, np.zeros(9)]))
    diagram.GetInputPort("suction_command").FixValue(context, [0.0])
    simulator.Initialize()
    simulator.AdvanceTo(0.1)  # warm-up
    segment = args.seconds / args.repeats
    walls, cpus = [], []
    for k in range(args.repeats):
        w0, c0 = time.perf_counter(), time.process_time()
        simulator.AdvanceTo(0.1 + (k + 1) * segment)
        walls.append(time.perf_counter() - w0)
        cpus.append(time.process_time() - c0)
    plant = diagram.GetSubsystemByName("plant")
    contacts = plant.get_contact_results_output_port().Eval(plant.GetMyContextFromRoot(context)).num_point_pair_contacts()
    asleep = f", {sum(sleep.sleeping(context))} of {len(sleep.names())} objects asleep" if sleep else ""
    print(
        f"station: {args.objects} objects + target (seed {args.seed}), time_step {scenario.plant_config.time_step} s, "
        f"{scenario.plant_config.discrete_contact_approximation}, {contacts} contacts at rest{asleep}, build {build:.2f} s"
    )
    print(
        f"simulated {args.seconds:.2f} s in {sum(walls):.2f} s wall ({sum(cpus):.2f} s CPU); best of {args.repeats} "
        f"segments of {segment:.2f} s: real-time factor {segment / min(walls):.2f}x wall, {segment / min(cpus):.2f}x CPU"
    )


if __name__ == "__main__":
    main()
