"""Collision queries for the trajectory checker: the robot model's collision geometry, the shelf and a scene.

:class:`CollisionWorld` builds its own Drake plant (no planner code) with the station's plant builder
(``make_station_plant(..., PlantPurpose.CHECKING)``): the station's model directives (the robot welded to the
world, the shelf model) with the shelf welded at the station's X_WS, and each scene object as a free body with
its primitive box or cylinder, placed per motion from the objects' planar poses (shelf frame S; z = half the height, standing). Object-object and object-shelf contacts are
filtered out (they rest on each other); what is reported are penetrations deeper than ``tolerance``:

- robot vs shelf and robot vs objects. The action's own object may be touched by the tool (``tool_shaft_link``:
  tube, blade, cup) during that action's motion (it is pushed or sucked), never by the other links;
- robot vs robot (self-collision). Bodies joined by a joint are not checked (Drake's default); the model's
  primitive link boxes also overlap structurally at some joints, so pairs that already penetrate at the reference
  configuration (the first point of the trajectory: the observation pose) are not checked either; the pairs
  left out are listed in the report.

Objects that the trial reported toppled or dropped before a motion are left out of that motion's check (their
pose is not planar), and an object carried by suction is checked at its pose before the motion only.
"""

from __future__ import annotations

TOLERANCE = 0.001  # m of penetration depth before a contact counts as a collision


class CollisionWorld:
    """See the module docstring. ``station``: a StationScenario; ``scene``: the Scene whose shelf and objects
    (shapes, sizes, initial poses) are checked, or None for self-collision only."""

    def __init__(self, station, scene=None, q_reference=None, tolerance: float = TOLERANCE):
        from pydrake.geometry import CollisionFilterDeclaration, GeometrySet

        from slax_drake.hardware.fetch_limits import FETCH_JOINTS
        from slax_drake.station import robot as robot_model
        from slax_drake.station.plant import PlantPurpose, make_station_plant

        self.tolerance = tolerance
        station_plant = make_station_plant(station, scene, PlantPurpose.CHECKING)
        builder, plant, scene_graph = station_plant.builder, station_plant.plant, station_plant.scene_graph
        robot, shelf, self.X_WS = station_plant.robot, station_plant.shelf, station_plant.X_WS
        self.objects = {obj.name: (obj, station_plant.objects[obj.name]) for obj in (scene.objects if scene else ())}
        self.plant, self.scene_graph = plant, scene_graph
        self.diagram = builder.Build()
        self.context = self.diagram.CreateDefaultContext()
        self.plant_context = plant.GetMyMutableContextFromRoot(self.context)
        self.sg_context = scene_graph.GetMyContextFromRoot(self.context)
        self.scene = scene

        def geometries(bodies):
            return [g for b in bodies for g in plant.GetCollisionGeometriesForBody(b)]

        robot_bodies = [plant.get_body(b) for b in plant.GetBodyIndices(robot)]
        env = geometries([plant.get_body(b) for b in plant.GetBodyIndices(shelf)] + [b for _, b in self.objects.values()])
        scene_graph.collision_filter_manager(self.sg_context).Apply(
            CollisionFilterDeclaration().ExcludeWithin(GeometrySet(env)))
        self.robot_geometries = set(geometries(robot_bodies))
        self.tool_geometries = set(geometries([plant.GetBodyByName(robot_model.TOOL_BODY, robot)]))
        self.object_of_geometry = {g: name for name, (_, b) in self.objects.items() for g in plant.GetCollisionGeometriesForBody(b)}
        self.shelf_geometries = set(geometries([plant.get_body(b) for b in plant.GetBodyIndices(shelf)]))
        inspector = scene_graph.model_inspector()
        self.body_name = {g: plant.GetBodyFromFrameId(inspector.GetFrameId(g)).name() for g in self.object_of_geometry}
        self.body_name.update({g: plant.GetBodyFromFrameId(inspector.GetFrameId(g)).name() for g in self.robot_geometries})
        self.body_name.update({g: "shelf" for g in self.shelf_geometries})
        self.joint_positions = [plant.GetJointByName(n, robot).position_start() for n in FETCH_JOINTS]
        q0 = plant.GetPositions(self.plant_context).copy()
        for name, value in station.head_configuration.items():
            q0[plant.GetJointByName(name, robot).position_start()] = value
        plant.SetPositions(self.plant_context, q0)
        self.place_objects(None, [])
        # Structural self-overlaps: robot pairs already penetrating at the reference configuration.
        self.structural_pairs = []
        if q_reference is not None:
            self.set_robot(q_reference)
            for p in self._penetrations():
                if p[0] in self.robot_geometries and p[1] in self.robot_geometries:
                    self.structural_pairs.append(tuple(sorted((self.body_name[p[0]], self.body_name[p[1]]))))
            pairs = {}
            for p in self._penetrations():
                if p[0] in self.robot_geometries and p[1] in self.robot_geometries:
                    pairs.setdefault(tuple(sorted((self.body_name[p[0]], self.body_name[p[1]]))), []).append((p[0], p[1]))
            decl = CollisionFilterDeclaration()
            for gs in pairs.values():
                for a, b in gs:
                    decl.ExcludeBetween(GeometrySet(a), GeometrySet(b))
            scene_graph.collision_filter_manager(self.sg_context).Apply(decl)
        self.structural_pairs = sorted(set(self.structural_pairs))

    def place_objects(self, poses: dict | None, lost) -> None:
        """Objects at their planar poses {name: {x, y, yaw}} in S (missing names: the scene's pose); lost ones
        are moved far below the floor."""
        from pydrake.math import RigidTransform, RollPitchYaw

        for name, (obj, body) in self.objects.items():
            if name in lost:
                X = RigidTransform([0.0, 0.0, -100.0])
            else:
                p = (poses or {}).get(name)
                x, y, yaw = (p["x"], p["y"], p["yaw"]) if p else (obj.center[0], obj.center[1], obj.yaw)
                X = self.X_WS @ RigidTransform(RollPitchYaw(0.0, 0.0, yaw), [x, y, obj.size[2] / 2.0])
            self.plant.SetFreeBodyPose(self.plant_context, body, X)

    def set_robot(self, q) -> None:
        """Robot at planned-joint positions q (``FETCH_JOINTS`` order); the head stays at its configuration."""
        full = self.plant.GetPositions(self.plant_context).copy()
        full[self.joint_positions] = q
        self.plant.SetPositions(self.plant_context, full)

    def _penetrations(self):
        query = self.scene_graph.get_query_output_port().Eval(self.sg_context)
        return [(p.id_A, p.id_B, p.depth) for p in query.ComputePointPairPenetration() if p.depth > self.tolerance]

    def collisions(self, q, touching_allowed: str | None = None) -> list[tuple[str, str, float]]:
        """(body A, body B, depth m) of every penetration deeper than the tolerance at robot positions q (9)."""
        self.set_robot(q)
        found = []
        for a, b, depth in self._penetrations():
            if a not in self.robot_geometries:
                a, b = b, a
            if a not in self.robot_geometries:
                continue
            if touching_allowed is not None and self.object_of_geometry.get(b) == touching_allowed and a in self.tool_geometries:
                continue
            found.append((self.body_name[a], self.body_name.get(b, "?"), float(depth)))
        return found
