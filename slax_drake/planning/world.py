"""The planning world: the robot, the shelf and a scene's objects frozen where they stand, for IK and checks.

``PlanningWorld(station_scenario, scene)`` builds a Drake RobotDiagram with the station's plant builder
(``make_station_plant(..., PlantPurpose.PLANNING)``: the robot and the shelf of the station's directives, the
shelf welded at the station's X_WS, every object of the scene (and, optionally, the target) welded at
X_WS * X_SO with its primitive box or cylinder as the collision shape). The plant's positions are the robot's
alone (planned joints and the head).

Collision semantics (the same for IK and for the checker):
- robot vs environment (shelf panels and objects) is checked with ``padding`` metres of margin;
- robot vs robot (self-collision) is checked with ``self_padding`` metres of margin, except between links joined
  by a joint (the plant's adjacency filter; the primitive link boxes overlap at the joints) and the pairs of
  ``NESTED_PAIRS`` (the telescoping torso). The station itself does not simulate self-contact: the planner
  is what keeps the arm out of the torso and out of itself;
- during an action's contact phases, the tool link (tube, blade, cup) is allowed to touch the manipulated
  object: :meth:`PlanningWorld.allow_tool_contact` toggles that single pair in the checker;
- while the suction cup carries an object clear of the support (pull out, translate, push in),
  :meth:`PlanningWorld.carry` attaches the object's box or cylinder to the tool link in the checker (an added
  collision shape, group ``CARRIED_GROUP``), shrunk by ``padding - CARRIED_MARGIN`` on every side so that it is
  checked with ``CARRIED_MARGIN`` against the shelf, the other objects and the robot; its welded copy where it
  stood is ignored by the tool link during contact phases, so only the carried copy counts. An object that rests
  closer than ``CARRIED_MARGIN`` to a wall or a neighbour (physics leaves objects touching) has its footprint
  shrunk by the difference plus ``REST_CONTACT_ALLOWANCE``, so that it may slide out along what it touches; where
  the estimates of two touching objects overlap, the difference is the overlap's depth (:func:`rest_gap`).
"""

from __future__ import annotations

import functools

import numpy as np

from slax_drake.scene.footprint import MAX_TOUCH_OVERLAP, TOUCH_ALLOWANCE
from slax_drake.scene.model import Scene
from slax_drake.station import robot as robot_model
from slax_drake.station.plant import PlantPurpose, make_station_plant
from slax_drake.station.scenario import StationScenario

PADDING = 0.002  # m, robot-environment margin of the collision checker
SELF_PADDING = 0.003  # m, margin between non-adjacent robot links
# Robot link pairs that overlap by design and are never checked against each other: the torso lift link slides
# over the fixed torso column (they are siblings on base_link, so the plant's adjacency filter misses them).
NESTED_PAIRS = (("torso_fixed_link", "torso_lift_link"),)
# Robot bodies whose pose a tool waypoint fixes (rigid with the tool frame while the shaft is locked): when one of
# them meets the environment at an IK solution of a waypoint, no other solution of that waypoint avoids it.
TOOL_RIGID_BODIES = ("wrist_roll_link", "bluction_mount_link", "camera_link", "tool_shaft_link")
EDGE_STEP = 0.005  # rad (weighted joint distance) between checked configurations along a segment
CARRIED_GROUP = "carried_object"
PLACED_GROUP = "placed_object"  # the moved object where the action leaves it (PlanningWorld.place)
# An object resting closer than CARRIED_MARGIN to a wall or neighbour may press this far into it while it slides
# out along it (m; the carry's lift reckons touching neighbours with the same allowance).
REST_CONTACT_ALLOWANCE = TOUCH_ALLOWANCE
CARRIED_MARGIN = 0.001  # m, the carried object's margin to everything else (the action model places objects
# 2 mm clear of neighbours, so the environment padding of 2 mm would reject exact placements)


class PlanningWorld:
    """A frozen world for planning (see the module docstring). Frames: world W = the station's world."""

    def __init__(self, scenario: StationScenario, scene: Scene, include_target: bool = False,
                 padding: float = PADDING, edge_step: float = EDGE_STEP, self_padding: float = SELF_PADDING):
        from pydrake.common import Parallelism
        from pydrake.geometry import CollisionFilterDeclaration, GeometrySet
        from pydrake.planning import SceneGraphCollisionChecker

        self.scenario = scenario
        self.scene = scene
        station_plant = make_station_plant(scenario, scene, PlantPurpose.PLANNING, include_target=include_target)
        self.X_WS = station_plant.X_WS
        self.object_bodies = station_plant.objects
        builder, plant, robot = station_plant.builder, station_plant.plant, station_plant.robot
        scene_graph = builder.scene_graph()
        # Self-collision: the plant already filters bodies joined by a joint (adjacent links) and bodies welded
        # together; the pairs that nest by design (the telescoping torso) are filtered here.
        decl = CollisionFilterDeclaration()
        for a, b in NESTED_PAIRS:
            decl.ExcludeBetween(GeometrySet(plant.GetCollisionGeometriesForBody(plant.GetBodyByName(a, robot))),
                                GeometrySet(plant.GetCollisionGeometriesForBody(plant.GetBodyByName(b, robot))))
        scene_graph.collision_filter_manager().Apply(decl)
        self.robot = robot
        self.planned_indices = robot_model.planned_joint_indices(plant, robot)
        self.head_indices = np.array([plant.GetJointByName(n, robot).position_start() for n in robot_model.HEAD_JOINTS])
        self.q_head = np.array([scenario.head_configuration.get(n, 0.0) for n in robot_model.HEAD_JOINTS])
        diagram = builder.Build()
        self.checker = SceneGraphCollisionChecker(
            model=diagram, robot_model_instances=[robot], edge_step_size=edge_step,
            env_collision_padding=padding, self_collision_padding=self_padding,
            implicit_context_parallelism=Parallelism(False),  # every query here is serial: one context is enough
        )
        self.self_padding = self_padding
        self.padding = padding
        self.diagram = self.checker.model()
        self.plant = self.checker.plant()
        self.tool_body = self.plant.GetBodyByName(robot_model.TOOL_BODY, robot)
        # A context of our own for IK and forward kinematics.
        self.diagram_context = self.diagram.CreateDefaultContext()
        self.plant_context = self.plant.GetMyMutableContextFromRoot(self.diagram_context)
        self.scene_graph = self.checker.model().scene_graph()
        self.scene_graph_context = self.scene_graph.GetMyMutableContextFromRoot(self.diagram_context)
        self._ik_filter = None
        self.carried = None
        self.carried_trim = 0.0
        # Dense edge checks already made, by the checker's state (tool contact allowed with which objects, what
        # is carried and how): a motion re-checks its free-space moves, which the free-path search has checked.
        self._allowed: set[str] = set()
        self._carried_key = None
        self.placed = None  # the object place() moved, or None
        self._placed_key = None
        self._robot_bodies = [self.plant.get_body(b) for b in self.plant.GetBodyIndices(robot)]
        self._edge_memo: dict = {}
        self._tool_rigid_index = {n: int(self.plant.GetBodyByName(n, robot).index()) for n in TOOL_RIGID_BODIES
                                  if self.plant.HasBodyNamed(n, robot)}
        self.frames = {name: self.plant.GetFrameByName(name, robot) for name in
                       (robot_model.BLADE_FACE_FRAME, robot_model.CUP_TIP_FRAME, robot_model.CAMERA_FRAME)}

    # configurations -------------------------------------------------------------------------------------
    def full_q(self, q_planned) -> np.ndarray:
        """The plant's positions for planned joint values (head at the scenario's head configuration)."""
        q = np.zeros(self.plant.num_positions())
        q[self.planned_indices] = q_planned
        q[self.head_indices] = self.q_head
        return q

    def planned_q(self, q_full) -> np.ndarray:
        return np.asarray(q_full)[self.planned_indices].copy()

    def tool_pose_S(self, q_planned, frame: str):
        """X_SF of a robot frame at the planned joint values (RigidTransform, shelf frame)."""
        self.plant.SetPositions(self.plant_context, self.full_q(q_planned))
        return self.X_WS.inverse() @ self.frames[frame].CalcPoseInWorld(self.plant_context)

    # checks -----------------------------------------------------------------------------------------------
    def allow_tool_contact(self, name: str | None, allowed: bool) -> None:
        """Lets the tool link touch object ``name`` (or stops letting it; an object :meth:`place` moved stays
        ignored where it stood)."""
        if name is None or name not in self.object_bodies:
            return
        self.checker.SetCollisionFilteredBetween(self.tool_body, self.object_bodies[name],
                                                 allowed or name == self.placed)
        (self._allowed.add if allowed else self._allowed.discard)(name)

    def place(self, obj, X_SO) -> None:
        """Moves ``obj`` (a SceneObject of the scene) to X_SO (4x4, shelf frame) for the checks that follow, until
        :meth:`unplace`: the robot ignores its welded copy where it stood and meets its box or cylinder at X_SO
        (an added shape on the world body, group ``PLACED_GROUP``). Where an action leaves the object it moved:
        the way back to the observation pose must clear it there."""
        from pydrake.geometry import Box, Cylinder
        from pydrake.math import RigidTransform

        self.unplace()
        body = self.object_bodies[obj.name]
        for b in self._robot_bodies:
            self.checker.SetCollisionFilteredBetween(b, body, True)
        sx, sy, sz = (float(v) for v in obj.size)
        shape = Box(sx, sy, sz) if obj.shape == "box" else Cylinder(sx / 2.0, sz)
        if not self.checker.AddCollisionShapeToBody(PLACED_GROUP, self.plant.world_body(), shape,
                                                    self.X_WS @ RigidTransform(np.asarray(X_SO, float))):
            raise RuntimeError("the collision checker refused the placed object's shape")
        self.placed = obj.name
        self._placed_key = (obj.name, np.asarray(X_SO, float).tobytes())

    def unplace(self) -> None:
        """Puts back the object :meth:`place` moved (no-op when none)."""
        if self.placed is None:
            return
        body = self.object_bodies[self.placed]
        self.checker.RemoveAllAddedCollisionShapes(PLACED_GROUP)
        for b in self._robot_bodies:
            self.checker.SetCollisionFilteredBetween(b, body, b is self.tool_body and self.placed in self._allowed)
        self.placed = None
        self._placed_key = None

    @property
    def placed_key(self):
        """What :meth:`place` moved and where (None: nothing), for memos of checks."""
        return self._placed_key

    def ik_tool_contact(self, name: str | None, allowed: bool) -> None:
        """The same as :meth:`allow_tool_contact` for IK's distance constraint (a transient collision filter in
        this world's own SceneGraph context, which IK queries)."""
        from pydrake.geometry import CollisionFilterDeclaration, GeometrySet

        manager = self.scene_graph.collision_filter_manager(self.scene_graph_context)
        if self._ik_filter is not None:
            manager.RemoveDeclaration(self._ik_filter)
            self._ik_filter = None
        if allowed and name in self.object_bodies:
            tool = self.plant.GetCollisionGeometriesForBody(self.tool_body)
            obj = self.plant.GetCollisionGeometriesForBody(self.object_bodies[name])
            self._ik_filter = manager.ApplyTransient(
                CollisionFilterDeclaration().ExcludeBetween(GeometrySet(tool), GeometrySet(obj)))

    def carry(self, obj, q_planned, trim_bottom: float = 0.0) -> None:
        """Attaches ``obj`` (a SceneObject, pose X_SO as it stands, i.e. where the cup seals on it at the
        configuration ``q_planned``) to the tool link for the checks that follow, until :meth:`drop`; less its
        bottom ``trim_bottom`` metres (for segments that start or end with it on its support)."""
        from pydrake.geometry import Box, Cylinder
        from pydrake.math import RigidTransform

        self.drop()
        shrink = max(0.0, self.padding - CARRIED_MARGIN)
        # An object resting against a wall or a neighbour (physics leaves them touching) slides along it: its
        # footprint is shrunk further by what it lacks of CARRIED_MARGIN there.
        gap = rest_gap(obj, self.scene)
        shrink_xy = shrink + (CARRIED_MARGIN - gap + REST_CONTACT_ALLOWANCE if gap < CARRIED_MARGIN else 0.0)
        sx, sy = (max(1e-4, v - 2.0 * shrink_xy) for v in obj.size[:2])
        sz = max(1e-4, obj.size[2] - 2.0 * shrink - trim_bottom)
        shape = Box(sx, sy, sz) if obj.shape == "box" else Cylinder(sx / 2.0, sz)
        self.plant.SetPositions(self.plant_context, self.full_q(q_planned))
        X_WT = self.tool_body.EvalPoseInWorld(self.plant_context)
        X_TO = X_WT.inverse() @ self.X_WS @ RigidTransform(obj.X_SO)
        if not self.checker.AddCollisionShapeToBody(CARRIED_GROUP, self.tool_body, shape,
                                                    X_TO @ RigidTransform([0.0, 0.0, trim_bottom / 2.0])):
            raise RuntimeError("the collision checker refused the carried object's shape")
        self.carried = obj
        self.carried_trim = trim_bottom
        self._X_TO = X_TO
        self._carried_key = (obj.name, obj.X_SO.tobytes(), trim_bottom, X_TO.GetAsMatrix4().tobytes())

    def drop(self) -> None:
        """Detaches the carried object (no-op when none)."""
        if self.carried is not None:
            self.checker.RemoveAllAddedCollisionShapes(CARRIED_GROUP)
            self.carried = None
            self._carried_key = None

    def carried_pose_S(self, q_planned) -> np.ndarray:
        """X_SO (4x4) of the carried object at the planned joint values."""
        if self.carried is None:
            raise ValueError("no object is carried")
        self.plant.SetPositions(self.plant_context, self.full_q(q_planned))
        X_WT = self.tool_body.EvalPoseInWorld(self.plant_context)
        return (self.X_WS.inverse() @ X_WT @ self._X_TO).GetAsMatrix4()

    def edge_free_uncarried(self, q0, q1) -> bool:
        """:meth:`edge_free` with the carried object detached for this one check (the robot alone)."""
        if self.carried is None:
            return self.edge_free(q0, q1)
        shapes = self.checker.GetAllAddedCollisionShapes()[CARRIED_GROUP]
        self.checker.RemoveAllAddedCollisionShapes(CARRIED_GROUP)
        try:
            return bool(self.checker.CheckEdgeCollisionFree(self.full_q(q0), self.full_q(q1)))
        finally:
            for d in shapes:
                self.checker.AddCollisionShapeToBody(CARRIED_GROUP, self.tool_body, d.shape(), d.pose_in_body())

    def config_free(self, q_planned) -> bool:
        return bool(self.checker.CheckConfigCollisionFree(self.full_q(q_planned)))

    def edge_free(self, q0, q1) -> bool:
        """The dense check of the joint-space segment q0 -> q1 (``edge_step`` apart) in the checker's present
        state; a segment already checked in the same state is answered from memory."""
        key = (np.asarray(q0, float).tobytes(), np.asarray(q1, float).tobytes(), frozenset(self._allowed),
               self._carried_key, self._placed_key)
        free = self._edge_memo.get(key)
        if free is None:
            free = bool(self.checker.CheckEdgeCollisionFree(self.full_q(q0), self.full_q(q1)))
            self._edge_memo[key] = free
        return free

    def edge_free_coarse(self, q0, q1, step: float) -> bool:
        """Configurations ``step`` apart (largest joint change) along the segment, both ends included, are free:
        a quick screen for searches; :meth:`edge_free` is the dense check. They are checked far end first, then
        by halving the intervals (:func:`_coarse_order`), and the check stops at the first collision: a search's
        blocked extension is mostly blocked at its new end (the same answer, fewer configurations checked)."""
        q0, q1 = np.asarray(q0, float), np.asarray(q1, float)
        n = max(1, int(np.ceil(float(np.max(np.abs(q1 - q0))) / step)))
        check = self.checker.CheckConfigCollisionFree
        return all(check(self.full_q(q0 + (k / n) * (q1 - q0))) for k in _coarse_order(n))

    def tool_environment_hits(self, q_planned) -> list[str]:
        """The bodies of ``TOOL_RIGID_BODIES`` that meet the environment (within the padding) at q."""
        from pydrake.planning import RobotCollisionType

        types = self.checker.ClassifyBodyCollisions(self.full_q(q_planned))
        env = (RobotCollisionType.kEnvironmentCollision, RobotCollisionType.kEnvironmentAndSelfCollision)
        return [n for n in TOOL_RIGID_BODIES if n in self._tool_rigid_index and types[self._tool_rigid_index[n]] in env]

    def colliding_bodies(self, q_planned) -> list[str]:
        """Names of the robot bodies in collision (within the paddings) at q, each with what it touches
        ("environment", "itself" or both)."""
        from pydrake.planning import RobotCollisionType

        types = self.checker.ClassifyBodyCollisions(self.full_q(q_planned))
        what = {RobotCollisionType.kEnvironmentCollision: "environment",
                RobotCollisionType.kSelfCollision: "itself",
                RobotCollisionType.kEnvironmentAndSelfCollision: "environment and itself"}
        return [f"{self.plant.get_body(_body_index(i)).name()} ({what[t]})" for i, t in enumerate(types) if t in what]

    def collision_pairs(self, q_planned) -> list[tuple[str, str]]:
        """What collides at q within the paddings: (robot body, what it meets) per pair, what it meets being a
        scene object's name, "the shelf" or a robot link (a shape added to the tool, a carried object, counts as
        the tool's body); empty when q is free. :func:`pairs_text` words them."""
        clearance = self.checker.CalcRobotClearance(self.full_q(q_planned),
                                                    influence_distance=max(self.padding, self.self_padding))
        objects = {int(body.index()): name for name, body in self.object_bodies.items()}
        pairs = []
        for r, o, d in zip(clearance.robot_indices(), clearance.other_indices(), clearance.distances()):
            if d >= 0.0:
                continue
            other = self.plant.get_body(_body_index(int(o)))
            if int(o) in objects:
                what = objects[int(o)]
            elif other.model_instance() == self.robot:
                what = other.name()
            else:
                what = "the shelf"
            pair = (self.plant.get_body(_body_index(int(r))).name(), what)
            if pair not in pairs:
                pairs.append(pair)
        return pairs

    def first_collision_on(self, q0, q1) -> list[tuple[str, str]]:
        """:meth:`collision_pairs` at the first configuration of the segment q0 -> q1 (``edge_step`` apart in
        the largest joint change) that collides; empty when none of those does."""
        q0, q1 = np.asarray(q0, float), np.asarray(q1, float)
        step = self.checker.edge_step_size()
        n = max(1, int(np.ceil(float(np.max(np.abs(q1 - q0))) / step)))
        for s in np.linspace(0.0, 1.0, n + 1):
            q = q0 + s * (q1 - q0)
            if not self.config_free(q):
                return self.collision_pairs(q)
        return []


def pairs_text(pairs) -> str:
    """``[(robot body, other), ...]`` of :meth:`PlanningWorld.collision_pairs` as "A with B, C with D"."""
    return ", ".join(f"{a} with {b}" for a, b in pairs)


def rest_gap(obj, scene: Scene) -> float:
    """The smallest horizontal gap (m; negative when overlapping) between ``obj``'s footprint and the side and
    back walls or another object's footprint, as they stand. An overlap with another footprint (two estimates of
    objects that physics left touching) counts as minus how far ``obj``'s footprint must shrink on every side to
    clear it (:func:`~slax_drake.scene.footprint.touch_overlap`: to 0.1 mm, at most ``MAX_REST_OVERLAP``; a
    deeper overlap counts as that)."""
    from slax_drake.scene.footprint import Footprint, touch_overlap

    poly = Footprint.of(obj).polygon()
    shelf = scene.shelf
    minx, miny, maxx, maxy = poly.bounds
    gaps = [minx + shelf.width / 2, shelf.width / 2 - maxx, shelf.depth / 2 - maxy]
    for other in scene.objects:
        if other.name == obj.name:
            continue
        depth = touch_overlap(obj, other)
        gaps.append(-depth if depth > 0.0 else poly.distance(Footprint.of(other).polygon()))
    return float(min(gaps))


MAX_REST_OVERLAP = MAX_TOUCH_OVERLAP  # m: rest_gap's deepest overlap of two footprints; deeper estimates are not trusted


def _body_index(i: int):
    from pydrake.multibody.tree import BodyIndex

    return BodyIndex(i)


@functools.lru_cache(maxsize=256)
def _coarse_order(n: int) -> tuple[int, ...]:
    """The sample indices 0..n of a segment cut into n intervals, in the order :meth:`PlanningWorld.edge_free_coarse`
    checks them: the far end n, the midpoints of ever shorter intervals, and the near end 0 last (a search's near
    end is a node of its tree, free already); each index once (a midpoint lies strictly inside its interval, and
    the intervals of one round do not overlap)."""
    order, intervals = [n], [(0, n)]
    while intervals:
        halves = []
        for a, b in intervals:
            if b - a >= 2:
                m = (a + b) // 2
                order.append(m)
                halves += [(a, m), (m, b)]
        intervals = halves
    return tuple(order + [0])
