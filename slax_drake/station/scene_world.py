"""The shelf world in a MultibodyPlant: the shelf bay as a URDF model and a scene's objects as free bodies.

Frames: the shelf model's body ``shelf_body`` has the shelf frame S of the scene package (origin at the centre of
the support surface, x to the right seen from the camera, y into the shelf, z up). Its panels are exactly the
boxes of ``slax_drake.scene.raycast.shelf_boxes``, so the physics, the renderer and the scene model share one
geometry. Objects (and the target) are free bodies whose frame O is at the object's centre, z up.

Physics choices (documented numbers):
- mass: the object's recorded mass (scenario ``physics.mass_model: household``, drawn from household goods'
  published masses, slax_drake.scene.mass), else ``density`` (kg/m^3, the scenario's ``objects.density``, 400 in
  sim_shelf.yaml) times the volume; inertia of the solid box or cylinder of that mass;
- Coulomb friction (static = dynamic): the scenario's ``physics.object_friction`` (default 0.5) for objects, 0.4
  for the shelf (packaging on a laminated board; sources in slax_drake/config.py's PhysicsConfig);
- point contact: stiffness 2e5 N/m per contact point and Hunt-Crossley dissipation 5 s/m;
- Drake's point contact between two boxes returns one contact point, which lets a resting box rock; each box
  therefore carries eight 1 mm spheres inset at its corners (tangent to its faces), and each cylinder
  ``CYLINDER_RIM_SPHERES`` (6) spheres around each rim, so a resting object stands on four or more points like
  a real one. The object's own shape does not touch the support board (``support_by_corner_spheres_only``):
  with it, each resting object had one more, deepest-point contact that made it chatter at 1e-2 m/s. It does touch
  the board's front edge (``support_front_edge``, 1 mm below the surface), so an object overhanging the edge rests
  on it as on a real shelf's edge.
- Speed (the station's real-time factor, benchmarks/bench_station.py) is roughly proportional to the number of
  resting contacts: 6 rim spheres instead of 8 ran 1.2x faster with 10 objects (4 would give 1.4x). The price:
  a cylinder tips over a hexagon, whose narrowest half-width is cos(30 deg) = 0.87 of its radius (0.92 with 8).

Render labels (``label_image``): the shelf is 0, ``objects[i]`` is i + 1 and the target len(objects) + 1, the
same numbering as ``SceneRaycaster``; the robot has no perception role (it is not drawn in the camera images).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from slax_drake.scene.model import Scene, SceneObject, Shelf
from slax_drake.scene.raycast import shelf_boxes

OBJECT_FRICTION = 0.5
SHELF_FRICTION = 0.4
POINT_STIFFNESS = 2.0e5  # N/m
HUNT_CROSSLEY_DISSIPATION = 5.0  # s/m
CORNER_SPHERE_RADIUS = 0.001  # m
CYLINDER_RIM_SPHERES = 6  # contact spheres around each rim of a cylinder (see the module docstring)
SHELF_PANEL_NAMES = ("support", "left_wall", "right_wall", "top", "back")
# m: how far below the support surface the support board's collision box reaches (the panel, and its visual, is
# the shelf's wall_thickness). With point contact an object's corner sphere pressed more than half a 2 cm board deep
# meets the board's bottom face nearer than its top and is pushed out below it: in the Drake trial 8:5 of the Table II
# protocol a carried box pressed 1.2 cm into the board fell through it and hung beneath the bay (docs/research/physics.md)
SUPPORT_COLLISION_DEPTH = 0.10
# The support board's front edge as a second collision box that the objects' own shapes touch (the board itself carries
# them by their corner spheres only, ``support_by_corner_spheres_only``): FRONT_EDGE_LENGTH (m) of the board behind its
# front face, from FRONT_EDGE_DROP (m) below the support surface down to SUPPORT_COLLISION_DEPTH. An object resting on
# the board does not touch it (its shape's bottom is on the surface); one whose front hangs over the edge rests on it and
# tips only when its centre of mass is past the edge. Without it an object overhanging the edge by 1 cm, its centre of
# mass 3 cm behind it, pivoted about its back corner spheres with the edge cutting through its shape, and fell
# (tests/station/test_station.py).
FRONT_EDGE_LENGTH = 0.02
FRONT_EDGE_DROP = 0.001
FRONT_EDGE_NAME = "support_front_edge"
# the shelf's collision geometries that carry objects (the board and its front edge); the rest of the shelf obstructs
SUPPORT_GEOMETRY_NAMES = ("support", FRONT_EDGE_NAME)
SHELF_COLOR = (0.76, 0.60, 0.42, 1.0)
FLOOR_SIZE = 20.0  # m, the floor's width and length about the robot (add_floor)


@dataclasses.dataclass(frozen=True)
class SceneBodies:
    """Body indices of the scene's objects in the plant, in scene order, and the target's (or None)."""

    objects: tuple
    target: object | None
    names: tuple[str, ...]

    def all(self) -> tuple:
        return self.objects + ((self.target,) if self.target is not None else ())


def add_floor(plant) -> None:
    """The room's floor under the robot: a slab ``FLOOR_SIZE`` wide whose top is the world's z = 0 (W: the robot's base
    stands on it; a box, as Drake warns of every rigid half-space that deformable contact does not support it),
    collision geometry only (not drawn, not seen by the camera), with the shelf's friction and the objects' point
    contact. An object that falls off the shelf lands on it and rests there, as on a real floor; without it, it
    fell for the rest of the trial, spinning ever faster, until the plant's state was no longer finite (the Drake
    trial 10:7 of the physics benchmark, "simulation diverged" 78 s after a lifted box fell off the shelf). Collisions
    with the robot's base, welded to the world, are filtered by the plant. Call before ``plant.Finalize()``."""
    from pydrake.geometry import AddContactMaterial, Box, ProximityProperties
    from pydrake.math import RigidTransform
    from pydrake.multibody.plant import CoulombFriction

    props = ProximityProperties()
    AddContactMaterial(dissipation=HUNT_CROSSLEY_DISSIPATION, point_stiffness=POINT_STIFFNESS,
                       friction=CoulombFriction(SHELF_FRICTION, SHELF_FRICTION), properties=props)
    plant.RegisterCollisionGeometry(plant.world_body(), RigidTransform([0.0, 0.0, -0.5]),
                                    Box(FLOOR_SIZE, FLOOR_SIZE, 1.0), "floor", props)


def _collision_box_xml(name: str, lo: np.ndarray, hi: np.ndarray) -> str:
    """A URDF collision element: the box from corner ``lo`` to ``hi`` (shelf frame S, m), shelf contact properties."""
    c, s = (lo + hi) / 2.0, hi - lo
    return f"""    <collision name="{name}">
      <origin xyz="{c[0]:.6f} {c[1]:.6f} {c[2]:.6f}" rpy="0 0 0"/>
      <geometry><box size="{s[0]:.6f} {s[1]:.6f} {s[2]:.6f}"/></geometry>
      <drake:proximity_properties>
        <drake:mu_dynamic value="{SHELF_FRICTION}"/>
        <drake:mu_static value="{SHELF_FRICTION}"/>
        <drake:point_contact_stiffness value="{POINT_STIFFNESS:g}"/>
        <drake:hunt_crossley_dissipation value="{HUNT_CROSSLEY_DISSIPATION:g}"/>
      </drake:proximity_properties>
    </collision>"""


def shelf_urdf(shelf: Shelf) -> str:
    """URDF text of the shelf bay: one body ``shelf_body`` at the shelf frame S with five box panels, each a
    collision box with Drake's point-contact properties and a visual box (the support's collision box reaches
    ``SUPPORT_COLLISION_DEPTH`` below the support surface, so that nothing pressed into the board passes through it),
    and the support board's front edge (``FRONT_EDGE_NAME``, collision only). URDF rather than SDFormat: Drake parses an
    SDFormat file in about 65 ms whatever its content (a URDF this size in under 1 ms), and the planner builds a
    planning world, the shelf included, for every object state it plans in."""
    links = []
    for name, (lo, hi) in zip(SHELF_PANEL_NAMES, shelf_boxes(shelf)):
        c, s = (lo + hi) / 2.0, hi - lo
        if name == "support":  # the collision box reaches SUPPORT_COLLISION_DEPTH below the support surface
            bottom = np.array([lo[0], lo[1], hi[2] - SUPPORT_COLLISION_DEPTH])
            links.append(_collision_box_xml(name, bottom, hi))
            links.append(_collision_box_xml(FRONT_EDGE_NAME, bottom,
                                            np.array([hi[0], lo[1] + FRONT_EDGE_LENGTH, hi[2] - FRONT_EDGE_DROP])))
        else:
            links.append(_collision_box_xml(name, lo, hi))
        links.append(
            f"""    <visual name="{name}_visual">
      <origin xyz="{c[0]:.6f} {c[1]:.6f} {c[2]:.6f}" rpy="0 0 0"/>
      <geometry><box size="{s[0]:.6f} {s[1]:.6f} {s[2]:.6f}"/></geometry>
      <material name="shelf_board"><color rgba="{" ".join(f"{v:g}" for v in SHELF_COLOR)}"/></material>
    </visual>"""
        )
    panels = "\n".join(links)
    return f"""<?xml version="1.0"?>
<!-- Shelf bay {shelf.width:g} m wide x {shelf.height:g} m high x {shelf.depth:g} m deep, panels {shelf.wall_thickness:g} m thick,
     written by slax_drake.station.scene_world.shelf_urdf (regenerate with it; a test checks the shipped copy).
     Body frame = shelf frame S: origin at the centre of the support surface, x right seen from the camera,
     y into the shelf (the front at y = -depth/2 is open), z up. Weld shelf_body to place the shelf. -->
<robot name="shelf" xmlns:drake="http://drake.mit.edu">
  <link name="shelf_body">
{panels}
  </link>
</robot>
"""


def object_mass(obj: SceneObject, density: float) -> float:
    """Mass (kg): the object's recorded mass (a household-mass scene), else a solid box or cylinder of ``density``
    kg/m^3."""
    from slax_drake.scene.mass import object_mass as mass_of

    return mass_of(obj, density)


def _corner_points(obj: SceneObject, r: float) -> list[np.ndarray]:
    """Centres of the small contact spheres in the object frame, inset by r so they are tangent to the faces."""
    sx, sy, sz = (s / 2.0 - r for s in obj.size)
    if obj.shape == "box":
        return [np.array([i * sx, j * sy, k * sz]) for i in (-1, 1) for j in (-1, 1) for k in (-1, 1)]
    points = []
    for k in (-1, 1):
        for n in range(CYLINDER_RIM_SPHERES):
            a = 2.0 * math.pi * n / CYLINDER_RIM_SPHERES
            points.append(np.array([sx * math.cos(a), sx * math.sin(a), k * sz]))
    return points


def add_scene_objects(plant, scene: Scene, density: float, include_target: bool = True,
                      friction: float = OBJECT_FRICTION) -> SceneBodies:
    """Adds the scene's objects (and target) as free bodies, each in its own model instance named after it, with
    Coulomb ``friction`` (static = dynamic; the scenario's ``physics.object_friction``).

    Call before ``plant.Finalize()``; set their poses with ``set_default_object_poses`` (or
    ``plant.SetDefaultFloatingBaseBodyPose``) once the shelf's pose in the world is known.
    """
    from pydrake.geometry import Box, Cylinder, ProximityProperties, Sphere
    from pydrake.multibody.plant import CoulombFriction
    from pydrake.multibody.tree import SpatialInertia, UnitInertia
    from pydrake.geometry import AddContactMaterial
    from pydrake.math import RigidTransform

    items = list(scene.objects)
    if include_target and scene.target is not None:
        items.append(scene.target.as_object())
    indices = []
    for obj in items:
        instance = plant.AddModelInstance(f"object_{obj.name}")
        mass = object_mass(obj, density)
        sx, sy, sz = obj.size
        if obj.shape == "box":
            unit = UnitInertia.SolidBox(sx, sy, sz)
            shape = Box(sx, sy, sz)
        else:
            unit = UnitInertia.SolidCylinder(sx / 2.0, sz, [0.0, 0.0, 1.0])
            shape = Cylinder(sx / 2.0, sz)
        body = plant.AddRigidBody(obj.name, instance, SpatialInertia(mass, np.zeros(3), unit))
        props = ProximityProperties()
        AddContactMaterial(
            dissipation=HUNT_CROSSLEY_DISSIPATION,
            point_stiffness=POINT_STIFFNESS,
            friction=CoulombFriction(friction, friction),
            properties=props,
        )
        plant.RegisterCollisionGeometry(body, RigidTransform(), shape, f"{obj.name}_collision", props)
        for k, p in enumerate(_corner_points(obj, CORNER_SPHERE_RADIUS)):
            plant.RegisterCollisionGeometry(
                body, RigidTransform(p), Sphere(CORNER_SPHERE_RADIUS), f"{obj.name}_corner_{k}", props
            )
        color = (0.9, 0.2, 0.2, 1.0) if obj.name == "target" else (0.3, 0.6, 0.3, 1.0)
        plant.RegisterVisualGeometry(body, RigidTransform(), shape, f"{obj.name}_visual", np.array(color))
        indices.append(body.index())
    has_target = include_target and scene.target is not None
    return SceneBodies(
        objects=tuple(indices[: len(scene.objects)]),
        target=indices[-1] if has_target else None,
        names=tuple(o.name for o in items),
    )


def set_default_object_poses(plant, scene: Scene, bodies: SceneBodies, X_WS) -> None:
    """Places every object at its scene pose X_SO, expressed in the world as X_WS * X_SO."""
    from pydrake.math import RigidTransform

    items = list(scene.objects) + ([scene.target.as_object()] if bodies.target is not None else [])
    for obj, index in zip(items, bodies.all()):
        plant.SetDefaultFloatingBaseBodyPose(plant.get_body(index), X_WS @ RigidTransform(obj.X_SO))


def assign_render_labels(scene_graph, plant, shelf_instance, robot_instance, bodies: SceneBodies) -> None:
    """Sets the perception role: shelf label 0, objects i + 1, target last; the robot gets no perception role."""
    from pydrake.geometry import PerceptionProperties, RenderLabel, Role, RoleAssign

    inspector = scene_graph.model_inspector()
    source_id = plant.get_source_id()

    def relabel(body, label):
        for geometry_id in plant.GetVisualGeometriesForBody(body):
            props = PerceptionProperties()
            props.AddProperty("label", "id", RenderLabel(label))
            illustration = inspector.GetIllustrationProperties(geometry_id)
            if illustration is not None and illustration.HasProperty("phong", "diffuse"):
                props.AddProperty("phong", "diffuse", illustration.GetProperty("phong", "diffuse"))
            if inspector.GetPerceptionProperties(geometry_id) is not None:
                scene_graph.RemoveRole(source_id, geometry_id, Role.kPerception)
            scene_graph.AssignRole(source_id, geometry_id, props, RoleAssign.kNew)

    for body_index in plant.GetBodyIndices(shelf_instance):
        relabel(plant.get_body(body_index), 0)
    for label, body_index in enumerate(bodies.all(), start=1):
        relabel(plant.get_body(body_index), label)
    for body_index in plant.GetBodyIndices(robot_instance):
        for geometry_id in plant.GetVisualGeometriesForBody(plant.get_body(body_index)):
            if inspector.GetPerceptionProperties(geometry_id) is not None:
                scene_graph.RemoveRole(source_id, geometry_id, Role.kPerception)


def support_by_corner_spheres_only(scene_graph, plant, shelf_instance, bodies: SceneBodies) -> None:
    """Excludes contact between each object's own shape and the shelf's support panel (the board it stands on).

    The corner (rim) spheres carry the object on the board: an upright object rests on 4 (box) or
    ``CYLINDER_RIM_SPHERES`` (cylinder) points instead of those plus one more point from its shape, which saves
    one contact pair per object on every step. The object's shape still touches the walls, the top, the back,
    the other objects and the tool. Cost: a toppled cylinder lying on its side rests on its rim spheres only and
    sinks by at most r (1 - cos(pi / CYLINDER_RIM_SPHERES)) into the board (13 % of its radius at 6).
    """
    from pydrake.geometry import CollisionFilterDeclaration, GeometrySet

    inspector = scene_graph.model_inspector()
    support = [
        g
        for b in plant.GetBodyIndices(shelf_instance)
        for g in plant.GetCollisionGeometriesForBody(plant.get_body(b))
        if inspector.GetName(g).split("::")[-1] == "support"
    ]
    shapes = [
        g
        for index in bodies.all()
        for g in plant.GetCollisionGeometriesForBody(plant.get_body(index))
        if inspector.GetName(g).endswith("_collision")
    ]
    if support and shapes:
        scene_graph.collision_filter_manager().Apply(
            CollisionFilterDeclaration().ExcludeBetween(GeometrySet(shapes), GeometrySet(support))
        )
