"""Choosing a station's robot placement (base relative to the shelf, torso height, observation pose) over reach maps.

    python -m slax_drake.planning.placement --station sim_configs/station_sim_shelf.yaml \\
        --report /tmp/placement.json [--out-map MAP.json --png MAP.png]

The station welds the robot's base at the world origin and places the shelf from the tool camera at the
observation configuration q_obs (X_WS = X_WC(q_obs) * inv(X_SC)), so moving the robot relative to the shelf is
moving the camera in the world W (the base frame, on the floor: x forward, y left, z up). A candidate is

- the camera's world position (``camera_x``: how far in front of the base, the base's distance from the bay;
  ``camera_y``: the lateral offset of the bay's centre line from the base), with the camera's height and
  orientation (level, pitched down, looking along +x) kept from the station: the shelf stands at the height
  the furniture gives, the base moves on the floor;
- the torso height at the observation pose (m). The torso is a planned joint, so the planner's IK picks its own
  height per tool pose; at q_obs it shapes the start of every motion and the planner's seed library.

For each candidate q_obs is solved by IK (:func:`solve_observation_pose`): the camera at the candidate's pose, the
torso at the candidate's height, the tool shaft as in the station, every robot-shelf and non-adjacent link
distance >= ``OBSERVATION_CLEARANCE``; from the station's q_obs, then from ``IK_RESTARTS`` seeded random
guesses. A candidate without a collision-free observation pose is dropped. The rest are scored by their reach
map (:mod:`slax_drake.planning.reach`: whether the planner finds a collision-free IK solution for the blade
inserted for a push toward +x and -x and the cup at a yaw-0 suction's seal, on the empty shelf, from q_obs),
coarse to fine: every candidate on the map's grid with every other node left out (``coarse_stride``), then the
``top`` best (and the station's own placement, for the "before") on the full grid, reusing the coarse nodes.
The score is the mean fraction of nodes reached over the three layers (the whole bay floor up to 5 cm from the
back wall); ties go to the larger worst layer, then to the candidate nearest the station's own placement.
A node costs 0.1-0.2 s where the arm reaches and about 0.5 s where it does not (one core).

The winner's q_obs is printed as the station YAML's ``observation_configuration`` block; ``--report`` writes
every candidate's pose, coverage and fate (JSON), ``--out-map`` / ``--png`` the winner's full reach map.
"""

from __future__ import annotations

import argparse
import dataclasses
import itertools
import json
import sys
import time
from pathlib import Path

import numpy as np

from slax_drake.errors import PlacementError
from slax_drake.shelf.reach import LAYERS, ReachMap

OBSERVATION_CLEARANCE = 0.02  # m, robot-shelf and link-link distance at the observation pose
POSITION_TOLERANCE = 1e-4  # m, the camera's position at q_obs
ANGLE_TOLERANCE = 1e-4  # rad, the camera's orientation at q_obs (the shelf must stand level within 1 mrad)
IK_RESTARTS = 4  # seeded random guesses after the station's q_obs
Q_DECIMALS = 6  # q_obs is rounded as the station YAML holds it, before its reach is measured
COARSE_STRIDE = 2
TOP = 2
TORSO_RANGE = (0.0, 0.38615)  # m, Fetch's torso_lift_joint


@dataclasses.dataclass(frozen=True)
class Candidate:
    """A placement: the camera's world position (m, W) at the observation pose and the torso height there (m)."""

    camera_x: float
    camera_y: float
    torso: float

    def label(self) -> str:
        return f"camera ({self.camera_x:.3f}, {self.camera_y:+.3f}) m, torso {self.torso:.3f} m"


@dataclasses.dataclass
class Evaluated:
    """A candidate's observation pose (None when IK found no collision-free one, ``why``), and the nodes of its
    reach map measured so far: {(layer, i, j): reached} on the full grid's indices."""

    candidate: Candidate
    q_obs: np.ndarray | None
    why: str = ""
    nodes: dict = dataclasses.field(default_factory=dict)
    is_station: bool = False

    def coverage(self, indices) -> dict:
        """{layer: (reached, measured)} over ``indices`` [(i, j)] of the full grid."""
        return {layer: (sum(self.nodes[(layer, i, j)] for i, j in indices), len(indices)) for layer in LAYERS}

    def score(self, indices) -> tuple:
        cov = self.coverage(indices)
        fractions = [r / n for r, n in cov.values()]
        return (float(np.mean(fractions)), float(min(fractions)))


def check_grid(camera_xs, camera_ys, torsos, coarse_stride: int, top: int, step: float | None = None) -> None:
    """PlacementError naming what is wrong with the candidate grid."""
    for name, values in (("--camera-x", camera_xs), ("--camera-y", camera_ys), ("--torso", torsos)):
        if len(values) == 0:
            raise PlacementError(f"{name}: give at least one value")
        if not all(np.isfinite(values)):
            raise PlacementError(f"{name}: every value must be a finite number of metres")
    bad = [t for t in torsos if not TORSO_RANGE[0] <= t <= TORSO_RANGE[1]]
    if bad:
        raise PlacementError(f"--torso {bad[0]}: outside the torso's travel {TORSO_RANGE[0]}-{TORSO_RANGE[1]} m")
    if coarse_stride < 1 or top < 1:
        raise PlacementError("--coarse-stride and --top must be at least 1")
    if step is not None and not (np.isfinite(step) and step > 0):
        raise PlacementError(f"--step {step}: the reach map's node spacing must be a positive number of metres")


def with_observation(station, q_obs: np.ndarray):
    """The station scenario with ``q_obs`` (planned joints) as its observation configuration."""
    from slax_drake.station import robot as robot_model

    config = {name: float(v) for name, v in zip(robot_model.PLANNED_JOINTS, q_obs)}
    return dataclasses.replace(station, observation_configuration=config)


def solve_observation_pose(world, X_S_camera, q_guess, torso: float, min_distance: float | None):
    """Planned joint values (9,) that put the tool camera at ``X_S_camera`` (RigidTransform, the shelf frame of
    ``world``, a :class:`~slax_drake.planning.world.PlanningWorld`), the torso at ``torso`` (m), the head and the
    tool shaft at ``q_guess``'s, every unfiltered distance >= ``min_distance`` (m, None: unchecked), inside the
    joint limits by the planner's margin; the cost stays near ``q_guess``. None when the solver fails."""
    from pydrake.math import RotationMatrix
    from pydrake.multibody.inverse_kinematics import InverseKinematics
    from pydrake.solvers import Solve

    from slax_drake.planning.ik import CONTINUOUS_JOINTS, LIMIT_MARGIN, margin_limits
    from slax_drake.station import robot as robot_model

    plant, context = world.plant, world.plant_context
    q0 = world.full_q(q_guess)
    torso_i = plant.GetJointByName("torso_lift_joint", world.robot).position_start()
    q0[torso_i] = torso
    plant.SetPositions(context, q0)
    ik = InverseKinematics(plant, context, with_joint_limits=True)
    q = ik.q()
    X_WC = world.X_WS @ X_S_camera
    camera = world.frames[robot_model.CAMERA_FRAME]
    p = X_WC.translation()
    ik.AddPositionConstraint(camera, np.zeros(3), plant.world_frame(), p - POSITION_TOLERANCE, p + POSITION_TOLERANCE)
    ik.AddOrientationConstraint(plant.world_frame(), X_WC.rotation(), camera, RotationMatrix(), ANGLE_TOLERANCE)
    if min_distance is not None:
        ik.AddMinimumDistanceLowerBoundConstraint(min_distance, min_distance + 0.03)
    prog = ik.get_mutable_prog()
    fixed = [torso_i] + [plant.GetJointByName(n, world.robot).position_start()
                         for n in robot_model.HEAD_JOINTS + ("tool_shaft_joint",)]
    prog.AddBoundingBoxConstraint(q0[fixed], q0[fixed], q[fixed])
    for name in CONTINUOUS_JOINTS:
        i = plant.GetJointByName(name, world.robot).position_start()
        prog.AddBoundingBoxConstraint(q0[i] - np.pi, q0[i] + np.pi, q[i])
    lower, upper = margin_limits(plant, world.robot, LIMIT_MARGIN)
    free = np.isfinite(lower) & np.isfinite(upper)
    free[fixed] = False
    prog.AddBoundingBoxConstraint(lower[free], upper[free], q[free])
    prog.AddQuadraticErrorCost(np.eye(len(q0)), q0, q)
    prog.SetInitialGuess(q, np.clip(q0, np.where(free, lower, -np.inf), np.where(free, upper, np.inf)))
    result = Solve(prog)
    return world.planned_q(result.GetSolution(q)) if result.is_success() else None


class PlacementSearch:
    """The search of the module docstring for one station; ``evaluate`` and ``measure`` are its two steps."""

    def __init__(self, station_path: str, seed: int = 0, step: float | None = None):
        from slax_drake.config import load_scenario
        from slax_drake.planning.reach import map_grid
        from slax_drake.planning.world import PlanningWorld
        from slax_drake.shelf.tool import tool_config
        from slax_drake.scene.camera import Camera
        from slax_drake.scene.model import Scene
        from slax_drake.scene.sampling import shelf_of
        from slax_drake.station.plant import camera_pose_at
        from slax_drake.station.scenario import load_station_scenario, observation_positions

        self.station_path = str(station_path)
        self.station = load_station_scenario(station_path)
        scenario = load_scenario(self.station.scene_config)
        self.shelf = shelf_of(scenario)
        self.camera = Camera.from_config(scenario.camera)
        self.scene = Scene(self.shelf, self.camera, (), None, 0)
        self.tool = tool_config(scenario, "station")
        self.q_station = observation_positions(self.station)
        self.X_WC_station = camera_pose_at(self.station, self.q_station)
        self.world = PlanningWorld(self.station, self.scene)  # the station's own world: IK without the shelf
        self.xs, self.ys = map_grid(self.shelf) if step is None else map_grid(self.shelf, step)
        self.rng = np.random.default_rng(seed)
        self.seed = seed

    # ----------------------------------------------------------------------------------------------------
    def station_candidate(self) -> Candidate:
        p = self.X_WC_station.translation()
        return Candidate(round(float(p[0]), 4), round(float(p[1]), 4), round(float(self.q_station[0]), 4))

    def guesses(self) -> list:
        """The station's q_obs, then ``IK_RESTARTS`` random configurations inside the limits (seeded per
        candidate in the search's order, so a search is deterministic)."""
        from slax_drake.station.plant import station_joint_limits

        limits = station_joint_limits(self.station)
        lo = np.where(np.isfinite(limits.position_lower), limits.position_lower, -np.pi)
        hi = np.where(np.isfinite(limits.position_upper), limits.position_upper, np.pi)
        out = [self.q_station.copy()]
        for _ in range(IK_RESTARTS):
            q = self.rng.uniform(lo, hi)
            q[-1] = self.q_station[-1]
            out.append(q)
        return out

    def evaluate(self, candidate: Candidate) -> Evaluated:
        """The candidate's collision-free observation pose (rounded as the YAML holds it), or why there is none."""
        from pydrake.math import RigidTransform

        from slax_drake.errors import ConfigError
        from slax_drake.planning.world import PlanningWorld
        from slax_drake.station.plant import camera_pose_at

        p_target = np.array([candidate.camera_x, candidate.camera_y, self.X_WC_station.translation()[2]])
        X_WC = RigidTransform(self.X_WC_station.rotation(), p_target)
        X_S_camera_now = self.world.X_WS.inverse() @ X_WC  # in the station's own world (no distance constraint)
        X_SC = RigidTransform(self.camera.X_SC)
        why = "no IK solution for the camera pose"
        for guess in self.guesses():
            q1 = solve_observation_pose(self.world, X_S_camera_now, guess, candidate.torso, None)
            if q1 is None:
                continue
            # the shelf placed from q1's camera: solved again there with the clearance to the shelf and itself
            world = PlanningWorld(with_observation(self.station, q1), self.scene)
            q2 = solve_observation_pose(world, X_SC, q1, candidate.torso, OBSERVATION_CLEARANCE)
            if q2 is None:
                why = f"no observation pose {OBSERVATION_CLEARANCE * 100:.0f} cm clear of the shelf and itself"
                continue
            q2 = np.round(q2, Q_DECIMALS)
            try:
                final = with_observation(self.station, q2)
                X = camera_pose_at(final, q2)
                check = PlanningWorld(final, self.scene)  # ConfigError when the shelf would tilt
            except ConfigError as e:
                why = str(e)
                continue
            if np.linalg.norm(X.translation() - p_target) > 1e-3 or not check.config_free(q2):
                why = "the rounded observation pose misses the camera pose or collides"
                continue
            return Evaluated(candidate, q2)
        return Evaluated(candidate, None, why)

    def measure(self, ev: Evaluated, indices, bar=None) -> None:
        """Reach of the nodes ``indices`` [(i, j)] not yet measured, for every layer."""
        from slax_drake.planning.planner import MotionPlanner
        from slax_drake.planning.reach import layer_waypoint

        todo = [(layer, i, j) for layer in LAYERS for i, j in indices if (layer, i, j) not in ev.nodes]
        if not todo:
            return
        planner = MotionPlanner(with_observation(self.station, ev.q_obs), self.tool)
        for layer, i, j in todo:
            wp = layer_waypoint(layer, float(self.xs[i]), float(self.ys[j]), self.scene, self.tool)
            ev.nodes[(layer, i, j)] = planner.reaches(self.scene, wp)
            if bar is not None:
                bar.update(1)

    def reach_map(self, ev: Evaluated) -> ReachMap:
        """The full-grid reach map of a measured candidate (its push and yaw-0 cup layers, the heights of those)."""
        from slax_drake.planning.reach import layer_heights

        reach = {layer: np.array([[ev.nodes[(layer, i, j)] for i in range(len(self.xs))] for j in range(len(self.ys))])
                 for layer in LAYERS}
        heights = {layer: h for layer, h in layer_heights(self.tool).items() if layer in reach}
        return ReachMap(self.station_path, self.xs, self.ys, reach, heights)


def subgrid(n_x: int, n_y: int, stride: int) -> list:
    """Node indices (i, j) of every ``stride``-th column and row (the last one always kept)."""
    def pick(n):
        idx = list(range(0, n, stride))
        return idx if idx[-1] == n - 1 else idx + [n - 1]

    return [(i, j) for j in pick(n_y) for i in pick(n_x)]


def rank(e: Evaluated, indices, reference: Candidate) -> tuple:
    """The sort key of a measured candidate: mean coverage over the layers, then the worst layer's, then nearness
    to ``reference`` (the station's own placement; m summed over camera x, y and torso)."""
    c = e.candidate
    near = abs(c.camera_x - reference.camera_x) + abs(c.camera_y - reference.camera_y) + abs(c.torso - reference.torso)
    return (*e.score(indices), -near)


def choose(evaluated, indices, reference: Candidate) -> Evaluated:
    """The best of ``evaluated`` (each measured on ``indices``) by :func:`rank`; the first of equals."""
    return max(evaluated, key=lambda e: rank(e, indices, reference))


def search(station_path: str, camera_xs, camera_ys, torsos, coarse_stride: int = COARSE_STRIDE, top: int = TOP,
           seed: int = 0, progress: bool = True, step: float | None = None):
    """(winner, every Evaluated in order, the station's own Evaluated, the PlacementSearch); module docstring."""
    from tqdm import tqdm

    check_grid(camera_xs, camera_ys, torsos, coarse_stride, top, step)
    ps = PlacementSearch(station_path, seed, step)
    own = Evaluated(ps.station_candidate(), ps.q_station.copy(), is_station=True)  # the baseline: q_obs as it is
    candidates = [Candidate(float(x), float(y), float(t)) for x, y, t in itertools.product(camera_xs, camera_ys, torsos)]
    evaluated = [ps.evaluate(c) for c in tqdm(candidates, desc="observation poses", disable=not progress)]
    feasible = [own] + [e for e in evaluated if e.q_obs is not None]
    coarse = subgrid(len(ps.xs), len(ps.ys), coarse_stride)
    with tqdm(total=len(feasible) * len(coarse) * len(LAYERS), desc="coarse reach", disable=not progress) as bar:
        for e in feasible:
            ps.measure(e, coarse, bar)

    reference = ps.station_candidate()
    order = sorted(feasible, key=lambda e: rank(e, coarse, reference), reverse=True)
    finalists = order[:top] + ([own] if own not in order[:top] else [])
    full = subgrid(len(ps.xs), len(ps.ys), 1)
    with tqdm(total=sum(len(full) * len(LAYERS) - len(e.nodes) for e in finalists), desc="full reach",
              disable=not progress) as bar:
        for e in finalists:
            ps.measure(e, full, bar)
    winner = choose(finalists, full, reference)
    return winner, [own] + evaluated, own, ps


def report(evaluated, ps: PlacementSearch, winner: Evaluated, seconds: float, coarse_stride: int = COARSE_STRIDE) -> dict:
    from slax_drake.station import robot as robot_model

    coarse = subgrid(len(ps.xs), len(ps.ys), coarse_stride)
    full = subgrid(len(ps.xs), len(ps.ys), 1)
    rows = []
    for e in evaluated:
        row = {"candidate": dataclasses.asdict(e.candidate), "station": e.is_station, "why": e.why,
               "q_obs": None if e.q_obs is None else dict(zip(robot_model.PLANNED_JOINTS, map(float, e.q_obs)))}
        for name, idx in (("coarse", coarse), ("full", full)):
            if e.q_obs is not None and all((layer, i, j) in e.nodes for layer in LAYERS for i, j in idx):
                row[name] = {k: list(v) for k, v in e.coverage(idx).items()}
        rows.append(row)
    return {"station": ps.station_path, "seed": ps.seed, "seconds": round(seconds, 1), "grid_step": float(ps.xs[1] - ps.xs[0]),
            "winner": dataclasses.asdict(winner.candidate), "winner_is_station": winner.is_station, "candidates": rows}


def yaml_block(q_obs) -> str:
    from slax_drake.station import robot as robot_model

    return "observation_configuration:\n" + "".join(f"  {n}: {float(v):.6f}\n" for n, v in zip(robot_model.PLANNED_JOINTS, q_obs))


def main(argv=None) -> int:
    from slax_drake.errors import UserError
    from slax_drake.io import write_bytes_atomic, write_text_atomic

    parser = argparse.ArgumentParser(description="choose a station's robot placement over reach maps")
    parser.add_argument("--station", required=True)
    parser.add_argument("--camera-x", type=float, nargs="+", default=[0.30, 0.375, 0.45],
                        help="camera positions in front of the base (m, world x)")
    parser.add_argument("--camera-y", type=float, nargs="+", default=[0.10, 0.20, 0.30],
                        help="camera lateral positions (m, world y, left of the base)")
    parser.add_argument("--torso", type=float, nargs="+", default=[0.05, 0.25], help="torso heights at q_obs (m)")
    parser.add_argument("--coarse-stride", type=int, default=COARSE_STRIDE)
    parser.add_argument("--top", type=int, default=TOP, help="candidates measured on the full grid")
    parser.add_argument("--step", type=float, default=None, help="reach map node spacing (m; default the map's 0.05)")
    parser.add_argument("--seed", type=int, default=0, help="seed of the IK restarts")
    parser.add_argument("--report", default=None, help="JSON of every candidate")
    parser.add_argument("--out-map", default=None, help="the winner's reach map JSON")
    parser.add_argument("--png", default=None, help="the winner's reach map picture")
    parser.add_argument("--no-progress", action="store_true")
    args = parser.parse_args(argv)
    t0 = time.perf_counter()
    try:
        winner, evaluated, own, ps = search(args.station, args.camera_x, args.camera_y, args.torso,
                                            args.coarse_stride, args.top, args.seed, not args.no_progress, args.step)
    except UserError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    full = subgrid(len(ps.xs), len(ps.ys), 1)
    for e in (own, winner):
        cov = ", ".join(f"{k} {r}/{n}" for k, (r, n) in e.coverage(full).items())
        print(f"{'station ' if e.is_station else 'chosen  '}{e.candidate.label()}: {cov}")
    print(yaml_block(winner.q_obs), end="")
    if args.report:
        write_text_atomic(Path(args.report), json.dumps(report(evaluated, ps, winner, time.perf_counter() - t0, args.coarse_stride), indent=1) + "\n")
    rmap = ps.reach_map(winner)
    if args.out_map:
        write_text_atomic(Path(args.out_map), json.dumps(rmap.to_dict()) + "\n")
    if args.png:
        from slax_drake.planning.reach import reach_png

        write_bytes_atomic(Path(args.png), reach_png(rmap, ps.shelf))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
