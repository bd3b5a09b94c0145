"""Collision queries for the trajectory checker: the robot model's collision geometry, the shelf and a scene.

:class:`CollisionWorld` builds its own Drake plant (no planner code) with the station's plant builder
(``make_station_plant(..., PlantPurpose.CHECKING)``): the station's model directives (the robot welded to the
world, the shelf model) with the shelf welded at the station's X_WS, and each scene object as a free body with
its primitive box or cylinder, standing on the shelf (shelf frame S; z = half the height). Object-object and
object-shelf contacts are filtered out (they rest on each other); what is reported are penetrations deeper than
``tolerance`` of the robot into the shelf, the objects and itself.

The world is the scene the checker is given, never the file's claims: the first motion is checked with the
objects at the scene's poses (whatever the file's ``objects_before`` says), and the objects move only as the
checker's own model of each motion moves them (:meth:`CollisionWorld.check_motions`). Before each later motion
the file's ``objects_before`` (where the simulator or the robot saw the objects) must agree with that world within
``WORLD_TOL`` for every object: then they are adopted (the checker's rigid push and carry model drifts from
real contact by a few millimetres per motion; adopting confirmed poses keeps the drift from adding up); otherwise
the motion gets a ``world`` violation (it was planned for a world the checker cannot confirm) and is checked in
the checker's own world. ``lost`` never removes an object: an object the file calls lost (toppled or dropped) is
still checked, at its pose in the world.

The object an action may touch (``touched`` below) rests on geometry:

- which object: the action's recorded estimate (``action.estimate``: the hypothesis the planner acted on, x, y,
  yaw, shape and size in S) is matched to the scene object whose footprint holds the estimate's centre, or whose
  centre lies in the estimate's footprint, each grown by ``ASSOCIATION_TOL``, the nearest centre first. When the
  file also names the scene object (``action.scene_object``), the two must agree. No estimate or no match: no
  object may be touched, every contact is a collision;
- a push (``type`` push, ``d`` m along S's x): the tool (``tool_shaft_link``: blade, tube and cup, which move as
  one body; the tube, 30 mm wide, rides ahead of the 4 mm blade's face and meets a tall object first) may touch
  the object only while the tool moves along the commanded direction sign(d) x_S: the object is then moved along
  that direction, by no more than the tool advanced since the previous checked configuration plus
  ``PUSH_STEP_SLACK``, to the smallest shift that clears the tool (it is pushed), and stays there. It may move at
  most |d| + ``PUSH_SLACK`` in all. A contact while the tool does not advance along the direction (inserting,
  lowering, backing off) or that such a shift cannot clear is a collision;
- a suction (``type`` suction): before the suction comes on and after it goes off only the cup (its body and rim)
  may touch the object, by at most ``CUP_PRESS``; once the suction is on and the cup is within ``CUP_REACH`` of
  the object (the suction comes on before the cup arrives), the object is carried rigidly with the tool, and the
  robot's other links, the shelf's walls and top and the other objects must stay clear of it (it may slide on the
  support surface); when the suction goes off, the object stands on the shelf at the released x, y and yaw.
  A pushed object's own contacts with the shelf and the other objects are not checked (pushing it against them
  is the action model's business);
- a guarded suction a trial's guard stopped (``action.guarded_push_in`` with ``stopped_at_s``: the motion ends
  at the stop): while it is carried, up to the push-in window's end, the carried object may push the objects it
  meets ahead of it along S's y, each by no more than the carried object advanced since the previous checked
  configuration plus ``PUSH_STEP_SLACK``, to the smallest shift that clears it (a guard stops only once the push
  meets more than its stop force, so a light object slides ahead first; and a guard's stop leaves the objects
  touching, which the cup's seal presses against each other again when the same object is taken next); the
  objects it met are reported (``guarded_met``). A
  plan-step file's guarded push-in has no stop: its first contact is where the guard stops it
  (:func:`slax_drake.hardware.check._guarded_stop`). A trial's push-in stopped at the board's front edge is followed
  by the push-in again higher (``action.edge_retry_motion``): that motion goes on holding the object where the one
  before stopped (no release between them);
- the seal's press: the carry starts ``CUP_REACH`` before the cup meets the object, and the cup then presses on to
  seal. An object the carried one stands within ``CUP_PRESS`` of when the cup takes it (a neighbour a guarded
  placement left it touching, or one a moment's press reaches) may be pressed by it, by at most ``CUP_PRESS``, until
  the two stand more than ``CUP_PRESS`` apart: there the cup's bellows give way, not the objects (the press is
  reported, ``seal_pressed``). A deeper contact, a contact with any other object, or the same pair meeting again
  after they parted is a collision.

Self-collision: bodies joined by a joint are not checked (Drake's default); the model's primitive link shapes also
overlap structurally at some joints: pairs that penetrate at the station's observation configuration (never a
configuration from the file) are left out and each is listed with the reason (the joint that joins them and
whether they overlap across that joint's whole range).
"""

from __future__ import annotations

import math

import numpy as np

TOLERANCE = 0.001  # m of penetration depth before a contact counts as a collision
ASSOCIATION_TOL = 0.02  # m: footprint growth when matching an action's estimate to a scene object
PUSH_SLACK = 0.02  # m: how much further than |d| a pushed object may be moved by the blade
CUP_PRESS = 0.005  # m: how deep the cup may press into the object it sucks
CUP_REACH = 0.002  # m: the suction holds the object once the cup is this close to it (and the suction is on)
PUSH_STEP_SLACK = 0.0005  # m: how much further than the tool's own advance one checked step may push the object
PUSH_BISECTIONS = 10
WORLD_TOL = 0.02  # m: how far the file's objects_before may lie from the checker's own world and be adopted
SAMPLES_ACROSS_RANGE = 5  # joint positions tried across a joint's range for a structural pair


def _footprint_holds(shape: str, size, x: float, y: float, yaw: float, px: float, py: float, grow: float) -> bool:
    dx, dy = px - x, py - y
    if shape == "cylinder":
        return math.hypot(dx, dy) <= size[0] / 2.0 + grow
    c, s = math.cos(yaw), math.sin(yaw)
    u, v = c * dx + s * dy, -s * dx + c * dy
    return abs(u) <= size[0] / 2.0 + grow and abs(v) <= size[1] / 2.0 + grow


class CollisionWorld:
    """See the module docstring. ``station``: a StationScenario; ``scene``: the Scene whose shelf and objects
    (shapes, sizes, initial poses) are checked, or None for self-collision only."""

    def __init__(self, station, scene=None, tolerance: float = TOLERANCE):
        from pydrake.geometry import CollisionFilterDeclaration, GeometrySet

        from slax_drake.hardware.fetch_limits import FETCH_JOINTS
        from slax_drake.station import robot as robot_model
        from slax_drake.station.plant import PlantPurpose, make_station_plant
        from slax_drake.station.scenario import observation_positions
        from slax_drake.station.scene_world import SUPPORT_GEOMETRY_NAMES

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
        self.report = {}

        def geometries(bodies):
            return [g for b in bodies for g in plant.GetCollisionGeometriesForBody(b)]

        robot_bodies = [plant.get_body(b) for b in plant.GetBodyIndices(robot)]
        env = geometries([plant.get_body(b) for b in plant.GetBodyIndices(shelf)] + [b for _, b in self.objects.values()])
        scene_graph.collision_filter_manager(self.sg_context).Apply(
            CollisionFilterDeclaration().ExcludeWithin(GeometrySet(env)))
        inspector = scene_graph.model_inspector()
        self.robot_geometries = set(geometries(robot_bodies))
        self.tool_body = plant.GetBodyByName(robot_model.TOOL_BODY, robot)
        self.tool_geometries = set(geometries([self.tool_body]))
        local = {g: inspector.GetName(g).split("::")[-1] for g in self.tool_geometries}
        self.blade_geometries = {g for g, n in local.items() if n == "blade"}
        self.cup_geometries = {g for g, n in local.items() if n.startswith("cup")}
        self.object_of_geometry = {g: name for name, (_, b) in self.objects.items() for g in plant.GetCollisionGeometriesForBody(b)}
        self.shelf_geometries = set(geometries([plant.get_body(b) for b in plant.GetBodyIndices(shelf)]))
        self.shelf_obstacles = {g for g in self.shelf_geometries
                                if inspector.GetName(g).split("::")[-1] not in SUPPORT_GEOMETRY_NAMES}
        self.body_name = {g: plant.GetBodyFromFrameId(inspector.GetFrameId(g)).name() for g in self.object_of_geometry}
        self.body_name.update({g: plant.GetBodyFromFrameId(inspector.GetFrameId(g)).name() for g in self.robot_geometries})
        self.body_name.update({g: "shelf" for g in self.shelf_geometries})
        self.joint_positions = [plant.GetJointByName(n, robot).position_start() for n in FETCH_JOINTS]
        q0 = plant.GetPositions(self.plant_context).copy()
        for name, value in station.head_configuration.items():
            q0[plant.GetJointByName(name, robot).position_start()] = value
        plant.SetPositions(self.plant_context, q0)
        self.poses = {}
        self.place_objects(None)
        self._structural(observation_positions(station), robot)

    # -- structure ------------------------------------------------------------------------------------------
    def _robot_pairs(self) -> dict:
        pairs = {}
        for a, b, _, _ in self._penetrations():
            if a in self.robot_geometries and b in self.robot_geometries:
                pairs.setdefault(tuple(sorted((self.body_name[a], self.body_name[b]))), []).append((a, b))
        return pairs

    def _structural(self, q_obs, robot) -> None:
        """Robot pairs penetrating at the observation configuration are left out, each with its reason."""
        from pydrake.geometry import CollisionFilterDeclaration, GeometrySet

        from slax_drake.hardware.fetch_limits import FETCH_JOINTS, FetchLimits

        self.set_robot(q_obs)
        pairs = self._robot_pairs()
        self.structural_pairs = sorted(pairs)
        self.structural_reasons = {}
        lim = FetchLimits.real_fetch()
        plant = self.plant
        moving = [plant.get_joint(j) for j in plant.GetJointIndices(robot)]
        moving = [J for J in moving if J.name() in FETCH_JOINTS]
        for a_name, b_name in self.structural_pairs:
            reason = f"{a_name} and {b_name} overlap at the station's observation configuration"
            for J in moving:
                child, parent = J.child_body().name(), J.parent_body().name()
                if child not in (a_name, b_name):
                    continue
                other = b_name if child == a_name else a_name
                attached = other == parent or any(
                    K.child_body().name() == other and K.parent_body().name() == parent and K.num_positions() == 0
                    for K in (plant.get_joint(k) for k in plant.GetJointIndices(robot)))
                if not attached:
                    continue
                j = FETCH_JOINTS.index(J.name())
                lo, hi = lim.position_lower[j], lim.position_upper[j]
                always = True
                for value in np.linspace(lo, hi, SAMPLES_ACROSS_RANGE) if np.isfinite(lo + hi) else ():
                    q = np.array(q_obs, float)
                    q[j] = value
                    self.set_robot(q)
                    always &= (a_name, b_name) in self._robot_pairs()
                reason = (f"{child} moves on {J.name()} ({J.type_name()}) relative to {other}, "
                          f"{'its parent' if other == parent else f'welded to the same {parent}'}")
                reason += (f"; their shapes overlap at all {SAMPLES_ACROSS_RANGE} positions tried across "
                           f"{J.name()}'s range ({lo:g} to {hi:g}), so the model's primitive shapes cannot tell a "
                           "contact from the structure: the pair is not checked" if always
                           else "; they overlap at the observation configuration: the pair is not checked")
            self.structural_reasons[f"{a_name}/{b_name}"] = reason
        decl = CollisionFilterDeclaration()
        for gs in pairs.values():
            for g1, g2 in gs:
                decl.ExcludeBetween(GeometrySet(g1), GeometrySet(g2))
        self.scene_graph.collision_filter_manager(self.sg_context).Apply(decl)
        self.set_robot(q_obs)

    # -- state ----------------------------------------------------------------------------------------------
    def place_objects(self, poses: dict | None) -> None:
        """Objects standing at planar poses {name: (x, y, yaw)} in S (missing names: the scene's pose)."""
        for name, (obj, _) in self.objects.items():
            p = (poses or {}).get(name)
            self.set_planar(name, *(p if p is not None else (obj.center[0], obj.center[1], obj.yaw)))

    def set_planar(self, name: str, x: float, y: float, yaw: float) -> None:
        from pydrake.math import RigidTransform, RollPitchYaw

        obj, body = self.objects[name]
        self.poses[name] = (float(x), float(y), float(yaw))
        X = self.X_WS @ RigidTransform(RollPitchYaw(0.0, 0.0, yaw), [x, y, obj.size[2] / 2.0])
        self.plant.SetFreeBodyPose(self.plant_context, body, X)

    def set_pose(self, name: str, X_WO) -> None:
        self.plant.SetFreeBodyPose(self.plant_context, self.objects[name][1], X_WO)

    def pose(self, name: str):
        return self.plant.EvalBodyPoseInWorld(self.plant_context, self.objects[name][1])

    def tool_pose(self):
        return self.plant.EvalBodyPoseInWorld(self.plant_context, self.tool_body)

    def set_robot(self, q) -> None:
        """Robot at planned-joint positions q (``FETCH_JOINTS`` order); the head stays at its configuration."""
        full = self.plant.GetPositions(self.plant_context).copy()
        full[self.joint_positions] = q
        self.plant.SetPositions(self.plant_context, full)

    def _penetrations(self):
        """(robot-side geometry or A, other geometry, depth m, unit normal in W pointing from the first into the
        second) of every penetration deeper than the tolerance."""
        query = self.scene_graph.get_query_output_port().Eval(self.sg_context)
        out = []
        for p in query.ComputePointPairPenetration():
            if p.depth <= self.tolerance:
                continue
            n = np.asarray(p.nhat_BA_W)  # from B into A
            a, b = p.id_A, p.id_B
            if a not in self.robot_geometries and b in self.robot_geometries:
                a, b, n = b, a, -n
            out.append((a, b, float(p.depth), -n))  # -n: from the robot-side geometry into the other
        return out

    # -- association ----------------------------------------------------------------------------------------
    def associate(self, action: dict | None):
        """(scene object name or None, reason) for the object the action may touch (module docstring)."""
        if not action or not self.objects:
            return None, "no action"
        est = action.get("estimate")
        if not isinstance(est, dict):
            return None, (f"the file records no estimate of {action.get('object')!r}: no object may be touched")
        ex, ey = float(est["x"]), float(est["y"])
        eyaw, esize, eshape = float(est.get("yaw", 0.0)), est["size"], est["shape"]
        found = []
        for name, (obj, _) in self.objects.items():
            x, y, yaw = self.poses[name]
            if (_footprint_holds(obj.shape, obj.size, x, y, yaw, ex, ey, ASSOCIATION_TOL)
                    or _footprint_holds(eshape, esize, ex, ey, eyaw, x, y, ASSOCIATION_TOL)):
                found.append((math.hypot(x - ex, y - ey), name))
        if not found:
            return None, (f"the estimate of {action.get('object')!r} at x {ex:+.3f}, y {ey:+.3f} m matches no scene "
                          "object: no object may be touched")
        name = min(found)[1]
        claimed = action.get("scene_object")
        if claimed is not None and claimed != name:
            return None, (f"the file associates {action.get('object')!r} with {claimed!r}, but its estimate at x "
                          f"{ex:+.3f}, y {ey:+.3f} m matches {name!r}: no object may be touched")
        return name, f"{action.get('object')!r} is {name!r} (estimate within its footprint)"

    # -- the motions ----------------------------------------------------------------------------------------
    def check_motions(self, traj, out: list, step: float, violation) -> int:
        """Checks every motion of ``traj`` against this world (module docstring), appending ``violation(kind,
        motion, time, what, value, limit, message)`` records to ``out``; returns the configurations checked.
        ``self.report`` then holds, per motion, the touched object and how far the file's ``objects_before``
        lies from the checked world."""
        from slax_drake.hardware.interpolation import quintic_hermite

        self.place_objects(None)
        count = 0
        motions = []
        held = None  # the grip (X_TO) a motion hands on to the next, which goes on holding its object
        for m_index, m in enumerate(traj.motions):
            offset, worst = self._offset(m.objects_before)
            if m_index > 0 and offset is not None:
                if offset <= WORLD_TOL:
                    self._adopt(m.objects_before)
                else:
                    what = (f"the file's objects_before has no pose for {worst}" if not math.isfinite(offset) else
                            f"the file's objects_before puts {worst} {offset * 1000:.0f} mm from where the scene and "
                            f"the checked motions before leave it (more than {WORLD_TOL * 1000:.0f} mm)")
                    out.append(violation("world", m_index, 0.0, worst, offset, WORLD_TOL,
                                         what + ": this motion was planned for another world; it is checked in the "
                                         "checker's own world"))
            name, why = self.associate(m.action)
            entry = {"touched": name, "association": why, "objects_before_offset_m": offset}
            motions.append(entry)
            extra = np.arange(0.0, m.duration, step) if step and step > 0 else np.zeros(0)
            times = np.union1d(m.times, extra)
            qs, _, _ = quintic_hermite(m.times, m.q, m.v, m.a, times)
            kind = (m.action or {}).get("type")
            model = _Push(self, name, m.action, m_index, violation, out) if kind == "push" and name else \
                _Suction(self, name, m, m_index, violation, out, held) if kind == "suction" and name else None
            following = traj.motions[m_index + 1].action or {} if m_index + 1 < len(traj.motions) else {}
            for t, q in zip(times, qs):
                count += 1
                self.set_robot(q)
                pens = model.resolve(t) if model is not None else self._penetrations()
                for a, b, depth, _ in pens:  # robot pairs, and a carried object's (the only other ones allowed)
                    what = f"{self.body_name[a]}/{self.body_name.get(b, '?')}"
                    out.append(violation("collision", m_index, float(t), what, depth, self.tolerance,
                                         f"{self.body_name[a]} penetrates {self.body_name.get(b, '?')} by "
                                         f"{depth * 1000:.1f} mm at t = {t:.4f} s"))
            held = None
            if model is not None:  # the push-in again higher at the board's edge goes on holding the object
                held = model.finish(entry, keep=bool(following.get("edge_retry_motion")))
        self.report = {"motions": motions}
        return count

    def _offset(self, poses):
        """(largest distance m between the file's planar poses and the world's, that object), or (None, None)."""
        if not isinstance(poses, dict) or not self.objects:
            return None, None
        worst, which = 0.0, None
        for name, (x, y, _) in self.poses.items():
            p = poses.get(name)
            d = math.inf if not isinstance(p, dict) else math.hypot(float(p["x"]) - x, float(p["y"]) - y)
            if which is None or d > worst:
                worst, which = d, name
        return (round(worst, 5) if math.isfinite(worst) else math.inf), which

    def _adopt(self, poses) -> None:
        for name in self.objects:
            p = poses[name]
            self.set_planar(name, float(p["x"]), float(p["y"]), float(p["yaw"]))


def _clear_shift(place, blocked, lo: float, reach: float) -> float | None:
    """The smallest shift in (lo, reach] (m, to ``PUSH_BISECTIONS`` halvings) at which ``blocked()`` is false after
    ``place(shift)``, left placed there; None when even ``reach`` is blocked (left placed at ``reach``)."""
    place(reach)
    if blocked():
        return None
    hi = reach
    for _ in range(PUSH_BISECTIONS):
        mid = 0.5 * (lo + hi)
        place(mid)
        lo, hi = (mid, hi) if blocked() else (lo, mid)
    place(hi)
    return hi


class _Push:
    """The tool pushing the touched object along sign(d) x_S (module docstring)."""

    def __init__(self, world: CollisionWorld, name: str, action: dict, motion: int, violation, out):
        self.w, self.name, self.motion, self.violation, self.out = world, name, motion, violation, out
        d = float(action.get("d", 0.0))
        self.sign = math.copysign(1.0, d)
        self.limit = abs(d) + PUSH_SLACK
        self.start = world.poses[name]
        self.shift = 0.0
        self.previous = None
        self.reported = False

    def _place(self, shift):
        x, y, yaw = self.start
        self.w.set_planar(self.name, x + shift * self.sign, y, yaw)

    def _touching(self) -> bool:
        w = self.w
        return any(a in w.tool_geometries and w.object_of_geometry.get(b) == self.name
                   for a, b, _, _ in w._penetrations())

    def _tool_x(self) -> float:
        w = self.w
        return float((w.X_WS.inverse() @ w.tool_pose()).translation()[0])

    def resolve(self, t):
        w = self.w
        x = self._tool_x()
        advance = 0.0 if self.previous is None else (x - self.previous) * self.sign
        self.previous = x
        if advance > 0.0 and self._touching():
            reach = min(self.shift + advance + PUSH_STEP_SLACK, self.limit)
            cleared = _clear_shift(self._place, self._touching, self.shift, reach)
            if cleared is None:
                if reach >= self.limit and not self.reported:
                    self.reported = True
                    self.out.append(self.violation(
                        "collision", self.motion, float(t), f"tool/{self.name}", reach, self.limit,
                        f"the tool would push {self.name} by more than |d| + {PUSH_SLACK:g} = {self.limit:.3f} m "
                        f"at t = {t:.4f} s"))
                self._place(self.shift)
            else:
                self.shift = cleared
        return w._penetrations()

    def finish(self, entry, keep: bool = False):
        entry["pushed_m"] = round(self.shift, 5)
        return None  # a push hands no grip on


class _Suction:
    """The cup sucking the touched object and carrying it while the suction is on (module docstring)."""

    def __init__(self, world: CollisionWorld, name: str, motion, m_index: int, violation, out, held=None):
        self.w, self.name = world, name
        self.intervals = []
        on = None
        for t, state in motion.suction_events:
            if state and on is None:
                on = t
            elif not state and on is not None:
                self.intervals.append((on, t))
                on = None
        if on is not None:
            self.intervals.append((on, motion.duration))
        self.X_TO = held  # the grip the motion before handed on (it goes on holding the object), or None
        self.carried = False
        guarded = (motion.action or {}).get("guarded_push_in") or {}
        # a trial's stopped guarded push-in: the window in which the carried object pushes what it meets
        self.window = ((float(guarded["t_start_s"]), float(guarded["t_end_s"]))
                       if guarded.get("stopped_at_s") is not None else None)
        self.previous_y = None
        self.met = {}  # name -> (first contact time s, shift m along the push)
        self.pressing = set()  # neighbours the seal's press may press the carried object against until they part
        self.pressed = {}  # name -> deepest press (m), for the report

    def resolve(self, t):
        w = self.w
        inside = any(a <= t <= b for a, b in self.intervals)
        if inside and self.X_TO is None and self._cup_distance() <= CUP_REACH:
            self.X_TO = w.tool_pose().inverse() @ w.pose(self.name)  # the cup holds it from here on
            self._filter(carried=True)
            self.pressing = self._neighbours_within(CUP_PRESS)
        if inside and self.X_TO is not None:
            w.set_pose(self.name, w.tool_pose() @ self.X_TO)
            self.carried = True
            if self.window is not None and t <= self.window[1]:
                self._push_met(t)
        elif self.X_TO is not None:
            self._release()
        if self.pressing:  # a neighbour the carried object has parted from is pressed no more
            self.pressing = self._neighbours_within(CUP_PRESS, self.pressing)
        pens = w._penetrations()
        keep = []
        for a, b, depth, n in pens:
            if w.object_of_geometry.get(b) == self.name and a in w.tool_geometries:
                if (inside and self.X_TO is not None) or (a in w.cup_geometries and depth <= CUP_PRESS):
                    continue
            pair = {w.object_of_geometry.get(a), w.object_of_geometry.get(b)}
            if self.X_TO is not None and self.name in pair:
                other = next(iter(pair - {self.name}), None)
                if other in self.pressing and depth <= CUP_PRESS:  # the seal's press (module docstring)
                    self.pressed[other] = max(self.pressed.get(other, 0.0), depth)
                    continue
            if a not in w.robot_geometries and w.object_of_geometry.get(b) == self.name:
                a, b, n = b, a, -n  # the carried object first: "object_3 penetrates object_0"
            keep.append((a, b, depth, n))
        return keep

    def _neighbours_within(self, reach: float, among=None) -> set:
        """The other objects (of ``among``, default all) the touched object stands within ``reach`` (m) of (signed
        distance)."""
        w = self.w
        query = w.scene_graph.get_query_output_port().Eval(w.sg_context)
        mine = [g for g, n in w.object_of_geometry.items() if n == self.name]
        return {n for g, n in w.object_of_geometry.items() if n != self.name and (among is None or n in among)
                and any(query.ComputeSignedDistancePairClosestPoints(m, g).distance <= reach for m in mine)}

    def _push_met(self, t: float) -> None:
        """Inside a stopped guarded push-in's window: every object the carried one penetrates is moved along S's
        y, the way the carried object advanced since the previous sample, by at most that advance plus
        ``PUSH_STEP_SLACK``, to the smallest shift that clears it (module docstring); one it cannot clear stays
        (a collision)."""
        w = self.w
        y = float((w.X_WS.inverse() @ w.pose(self.name)).translation()[1])
        advance = 0.0 if self.previous_y is None else y - self.previous_y
        self.previous_y = y
        if abs(advance) <= 0.0:
            return
        sign = math.copysign(1.0, advance)
        met = set()
        for a, b, _, _ in w._penetrations():
            pair = {w.object_of_geometry.get(a), w.object_of_geometry.get(b)}
            if self.name in pair:
                met |= pair
        for other in sorted(met - {None, self.name}):
            x0, y0, yaw = w.poses[other]

            def place(shift, other=other, x0=x0, y0=y0, yaw=yaw):
                w.set_planar(other, x0, y0 + sign * shift, yaw)

            cleared = _clear_shift(place, lambda other=other: self._meets(other), 0.0, abs(advance) + PUSH_STEP_SLACK)
            if cleared is None:
                place(0.0)
                continue
            first, shift = self.met.get(other, (float(t), 0.0))
            self.met[other] = (first, shift + cleared)

    def _meets(self, other: str) -> bool:
        """Whether the carried object penetrates ``other`` (beyond the world's tolerance)."""
        w = self.w
        return any({w.object_of_geometry.get(a), w.object_of_geometry.get(b)} == {self.name, other}
                   for a, b, _, _ in w._penetrations())

    def _filter(self, carried: bool) -> None:
        """While carried, the object's contacts with the shelf's walls and top and with the other objects count
        (its support surface does not: a carried object may slide on it)."""
        from pydrake.geometry import CollisionFilterDeclaration, GeometrySet

        w = self.w
        mine = GeometrySet([g for g, n in w.object_of_geometry.items() if n == self.name])
        others = GeometrySet([g for g, n in w.object_of_geometry.items() if n != self.name] + list(w.shelf_obstacles))
        decl = CollisionFilterDeclaration()
        decl = decl.AllowBetween(mine, others) if carried else decl.ExcludeBetween(mine, others)
        w.scene_graph.collision_filter_manager(w.sg_context).Apply(decl)

    def _cup_distance(self) -> float:
        """The smallest signed distance (m) between the cup's geometries and the object."""
        w = self.w
        query = w.scene_graph.get_query_output_port().Eval(w.sg_context)
        return min(query.ComputeSignedDistancePairClosestPoints(c, g).distance
                   for c in w.cup_geometries for g, n in w.object_of_geometry.items() if n == self.name)

    def _release(self):
        from pydrake.math import RollPitchYaw

        w = self.w
        X = w.X_WS.inverse() @ w.pose(self.name)
        yaw = float(RollPitchYaw(X.rotation()).yaw_angle())
        w.set_planar(self.name, float(X.translation()[0]), float(X.translation()[1]), yaw)
        self.X_TO = None
        self._filter(carried=False)

    def finish(self, entry, keep: bool = False):
        """Records the motion's report in ``entry``; releases the object, or with ``keep`` (the next motion goes on
        holding it) returns the grip (X_TO, None when nothing is held)."""
        held = self.X_TO if keep else None
        if self.X_TO is not None and not keep:
            self._release()
        entry["carried"] = self.carried
        if self.met:
            entry["guarded_met"] = {name: {"time_s": round(t, 4), "pushed_m": round(shift, 5)}
                                    for name, (t, shift) in self.met.items()}
        if self.pressed:
            entry["seal_pressed"] = {name: round(depth, 5) for name, depth in self.pressed.items()}
        return held
