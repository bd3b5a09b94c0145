"""Cartesian tool waypoints of a bluction action, in the shelf frame S (x right, y into the shelf, z up; m).

A motion leaves the observation pose (the blade hanging below the tube, edge-on, out of the camera's view),
moves in free space to the first waypoint, follows straight tool segments through the rest, and returns in
free space to the observation pose. Each waypoint names the tool frame it places, its pose X_SF, the shaft
angle, whether the segment *arriving* at it may touch the manipulated object (``contact``) and the suction
command from it on.

Push (q, d) of ``slax_drake.shelf.actions``: q = (x of the blade lane's centre, y of the blade's tip,
blade_height / 2). The blade (``blade_face_frame``, its faces normal to S x, hanging below the tube, the tube
pointing along S +y) goes ``PUSH_STANDOFF`` beside the object's extreme x (so that the 3 cm tube above the blade
clears a tall object) instead of the lane's centre, and pushes d plus the gap between the object and the tool's
surface that meets it (the blade's face, or the tube's side for an object reaching the tube, :func:`push_lead`),
so the object moves by d: pre-approach in front of the opening (``APPROACH_MARGIN``), insert along +y to the tip
depth, push along x, back off that gap (the surface as far from the object as at the insert), retract along -y.

Suction (q, d_x, d_z, yaw): q = the contact point on the camera-facing side. The blade is turned up
(``SHAFT_BLADE_UP``), the cup (``cup_tip_frame``, its axis along S +y turned by the action's yaw about S z, so
along a turned face's normal) approaches along its axis to 1 cm before the face, seals (suction on, pressing
``SEAL_PRESS`` in along the axis), and, keeping its yaw, lifts ``LIFT`` (about 1 cm), pulls the object out of the shelf
toward the camera (by default until its back is out of the shelf; the planner may carry it across shallower,
:func:`pull_out_options`, or turned about the cup's vertical axis on the way out and back on the way in,
:func:`carry_options`), translates d_x, pushes in until the object's centre is at y = d_z, lowers, releases
(suction off), backs off along its axis and retracts along it out of the shelf (a turned tool leaves as it
came). The lift is ``LIFT`` unless the carried object's way
(its footprint swept in 5 mm steps) crosses another object: then it is lifted ``LIFT_CLEARANCE`` above the
tallest one crossed (the action model's "over-lower" rule lets objects pass over lower ones); the lift on the
way out clears the ways out and across, the height at which it is pushed in the ways across and in, and the
translation rises or falls between the two (the arm reaches a low pull-out near the robot more easily). The segments
arriving at "pull out", "translate" and "push in" carry the object clear of the support (``carried``): the
planner checks the object with the tool there ("clear"); on the lift and the lowering ("resting") it checks the
object less its bottom ``LIFT``, which touches the support at one end of the segment.

A drag (a Suction with ``drag`` set, the action model's ``drag_grasp`` rule) has the same approach, seal, release
and retreat, with q sealed low on the face; between them the object stays on the floor: the cup pulls it along
its axis until its front is ``DRAG_FRONT_MARGIN`` inside the opening (``pull``, :func:`drag_pull_cup_y`),
translates it by d_x (``drag across``) and pushes it in until its centre is at y = d_z (``push in``), at the seal's
height all the way. These segments carry the object ``"resting"`` (checked less its bottom ``LIFT``: it slides on
the support). There is one way to drag an object (no shallower pull-outs, no turned carry).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from slax_drake.shelf.actions import (APPROACH_MARGINS, BLADE_LIFT, CARRY_YAWS_DEG, DRAG_FRONT_MARGIN, GRAVITY, LIFT,
                                      LIFT_CLEARANCE, OUT_MARGIN, PULL_STEP, SEAL_PRESS, TUBE_STANDOFF, Push, Suction)
from slax_drake.shelf.rules import ToolConfig
from slax_drake.scene.footprint import TOUCH_ALLOWANCE, Footprint, touch_overlap
from slax_drake.scene.mass import object_mass
from slax_drake.scene.model import SceneObject, Shelf
from slax_drake.station import robot as robot_model

# APPROACH_MARGINS (the action model's): the planner's margins of the tool's tip in front of the opening before
# entering (m), to try in turn: the nominal one, then with the tip just outside the opening, which keeps the wrist
# 4 cm farther from the robot's body (the front of the bay is at the edge of the arm's folded reach).
APPROACH_MARGIN = APPROACH_MARGINS[0]
BLADE_HALF_LENGTH = 0.0325  # blade_face_frame to the blade's tip along the tube (m, URDF)
BLADE_HALF_THICKNESS = 0.002  # m (URDF)
TUBE_RADIUS = 0.015  # m (URDF); the tube runs along the blade's upper edge, centred on the blade's plane
TUBE_END_PAST_BLADE_FACE = 0.0465  # m along the tube, blade_face_frame to the end of the cup's body (URDF: 0.3675, 0.414)
PUSH_STANDOFF = TUBE_RADIUS + TUBE_STANDOFF - BLADE_HALF_THICKNESS  # blade face to the object's extreme (m): the tube clears it
# The tube, not the blade, pushes an object whose top reaches the tube's side: where its surface's normal is within
# TUBE_PUSH_ANGLE of horizontal (measured in Drake, research/push_contact.py --heights: boxes 8-20 cm tall went
# 8.5-11.9 mm farther than a push planned for the blade; a 7.5 cm box, meeting the tube 32 deg below its axis, as
# far as planned).
TUBE_PUSH_ANGLE = np.radians(20.0)
# BLADE_LIFT (the blade's lower edge above the support, m) is the action model's, whose push_tube_check reads it
# SEAL_PRESS (the action model's): the cup pressed this far into the face (m)
CUP_STANDOFF = 0.01  # m before the face, then the cup moves in with suction on
# LIFT (m), LIFT_CLEARANCE (the carried object's bottom this far above the tallest object it passes over, m) and
# PULL_STEP (m between the pull-out depths the planner tries) are the action model's, which checks the carry
# against the reach map's hold layers
# Turns of the tool about the cup's vertical axis (rad) while it carries an object pulled all the way out, tried
# (each way round) when no depth of the straight carry plans (:func:`carry_options`). At 30 deg every pull-out
# and translate pose of the Table I carries the arm could not reach straight has an IK solution.
CARRY_YAWS = tuple(float(np.radians(d)) for d in CARRY_YAWS_DEG)
TARGET_CLEARANCE = 0.005  # m, an object carried across inside the shelf keeps this far from the target
SWEEP_STEP = 0.005  # m between footprints of the carried object's sweep when looking for objects it crosses
# OUT_MARGIN (the action model's): the carried object's back this far in front of the opening (m)
RELEASE_BACKOFF = 0.02  # m
PUSH_BACK_SLACK = 0.02  # m: at most this much farther than its gap and give a push backs off (push_back_slack)
DWELL = 0.3  # s at rest after sealing and after releasing
PULL_DWELL = 0.1  # s at rest at the end of a sideways drag's pull when it is weighed there (the weigh_drag_pull rule:
# slax_drake.systems.drag_weigh): the arm decides there whether to slide the object across or push it back
WEIGH_DWELL = 0.3  # s at rest at a lifted suction's lift, where the arm weighs what the cup holds (the arm settles in
# about 0.2 s after the lift on the sim station: slax_drake.systems.guard.weigh_time); a lift higher than LIFT (over
# a tall object on the way) rests at LIFT first ("weigh"), so that an object the cup cannot hold falls from 1 cm


def push_lead(top_z: float, tool: ToolConfig = ToolConfig()) -> float:
    """How far in front of the blade's plane (m, along the push) the tool surface stands that meets an object whose
    top is at ``top_z`` (m above the support): the blade's face (``BLADE_HALF_THICKNESS``), or the tube's side at
    the object's top where it reaches lower than ``TUBE_PUSH_ANGLE`` below the tube's axis (at the blade's upper
    edge), up to ``TUBE_RADIUS`` for an object as tall as the axis or taller. A push moves the tool d plus the
    gap between that surface and the object, so that the object moves d."""
    below_axis = max(0.0, tool.geometry.blade_height + BLADE_LIFT - top_z)
    if below_axis > TUBE_RADIUS * np.sin(TUBE_PUSH_ANGLE):
        return BLADE_HALF_THICKNESS
    return max(BLADE_HALF_THICKNESS, float(np.sqrt(TUBE_RADIUS ** 2 - below_axis ** 2)))


def push_lane_shift(obj: SceneObject, objects: tuple[SceneObject, ...], sign: float, plane_x: float, y_from: float,
                    y_to: float, tool: ToolConfig = ToolConfig()) -> float:
    """How far (m, toward the pushed object ``obj``) to move the blade's plane from ``plane_x`` (S x) so that the
    tube, coming in along S +y on that plane from ``y_from`` to ``y_to`` (its end), stands as far from the pushed
    object as from the nearest neighbour on its other side that reaches the tube's underside: half the difference
    of the two clearances when the neighbour's is the smaller, else 0 (the tube keeps ``TUBE_STANDOFF`` from the
    object). ``sign``: the push's direction along x (the neighbour is on the far side, +x of the tube for a push
    toward -x)."""
    from shapely.geometry import LineString, Point

    axis = LineString([(plane_x, y_from), (plane_x, y_to)])
    underside = tool.geometry.blade_height + BLADE_LIFT - TUBE_RADIUS

    def clearance(o: SceneObject) -> float:  # the tube's surface to the object's outline on the floor (m)
        fp = Footprint.of(o)
        if fp.shape == "cylinder":
            return float(Point(fp.x, fp.y).distance(axis)) - fp.half_x - TUBE_RADIUS
        return float(fp.polygon().distance(axis)) - TUBE_RADIUS

    own = clearance(obj)
    beyond = [clearance(o) for o in objects if o.name != obj.name and o.size[2] > underside
              and sign * (float(o.center[0]) - plane_x) < 0.0]
    if not beyond or min(beyond) >= own:
        return 0.0
    return (own - min(beyond)) / 2.0


def push_give(obj: SceneObject, compliance: float, tool: ToolConfig = ToolConfig()) -> float:
    """How far (m) the tool gives way at the end of a push of ``obj``: the station's ``compliance`` (m/N) times
    the force the object resists with while it slides, ``drag_friction`` x m g, m as the action model reckons it
    (its weighed or recorded mass, else its class's ``mass_quantile``: :func:`slax_drake.scene.mass.object_mass`).
    The push travels this much farther so that it ends where planned, and backs off by as much more."""
    if compliance <= 0.0:
        return 0.0
    mass = object_mass(obj, tool.physics.object_density, tool.physics, tool.rules.mass_quantile)
    return compliance * tool.rules.drag_friction * mass * GRAVITY


def push_back_slack(d: float) -> float:
    """How much farther (m) than the push's gap and give the tool backs off before it retracts along S -y: the
    push's length, up to ``PUSH_BACK_SLACK``. An object that moved less than d (the arm's give, a light tall object
    that leans on the tool as it is pushed at its foot) still touches the tool where a back-off of the gap alone ends,
    and the retract drags it toward the opening (Table I household 8:8 and 10:13 at ba55d14: thin cylinders 16-18
    cm tall pushed 2 and 2.5 cm moved 1.1 cm, leaned 5 deg onto the tube, were dragged 3 cm to the board's front
    edge by the retract and fell off at the next push). Backing off by d more returns the tool to the lane it came
    in by, which was free."""
    return min(abs(float(d)), PUSH_BACK_SLACK)


def push_rotation() -> np.ndarray:
    """R_SB of ``blade_face_frame`` when pushing: tube (x) along S +y, face normal (y) along S -x, z up."""
    return np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])


def suction_rotation(yaw: float = 0.0) -> np.ndarray:
    """R_SC of ``cup_tip_frame`` with the blade up, the tool turned ``yaw`` (rad) about S z: cup axis (x) along
    (-sin yaw, cos yaw, 0) in S (S +y at yaw 0), y along (cos yaw, sin yaw, 0), z down."""
    c, s = np.cos(yaw), np.sin(yaw)
    Rz = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    return Rz @ np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])


@dataclasses.dataclass(frozen=True)
class ToolWaypoint:
    """A tool pose to pass through: ``frame`` at X_SF (4x4, shelf frame), the shaft angle (rad)."""

    label: str
    frame: str
    X_SF: np.ndarray
    shaft: float
    contact: bool = False  # the segment arriving here may touch the manipulated object
    suction: bool = False  # the suction command while moving to this waypoint and during its dwell
    dwell: float = 0.0  # seconds at rest on arrival
    carried: str = ""  # the segment arriving here carries the manipulated object: "clear" of its support all the
    # way, or "resting" (it leaves or reaches its support: lift, lower)

    @property
    def position(self) -> np.ndarray:
        return self.X_SF[:3, 3]


def _pose(R: np.ndarray, p) -> np.ndarray:
    X = np.eye(4)
    X[:3, :3] = R
    X[:3, 3] = p
    return X


def action_waypoints(action, objects: tuple[SceneObject, ...], shelf: Shelf, tool: ToolConfig = ToolConfig(),
                     approach_margin: float = APPROACH_MARGIN, pull_to: float | None = None, carry_yaw: float = 0.0,
                     push_compliance: float = 0.0):
    """The tool waypoints of ``action`` (Push or Suction) on the objects as they stand; the tool's tip is
    ``approach_margin`` in front of the opening at the pre-approach and retract waypoints. ``pull_to``: the
    cup's y (S) while a suctioned object is carried across (default :func:`full_pull_out`). ``carry_yaw`` (rad,
    about S z): the tool, and the object with it, turns by this much about the cup's vertical axis on the way
    out (lift to pull out) and back on the way in (push in), so it is carried across turned; the seal, the
    lowering and the release keep the action's yaw, so the object ends where the action puts it.
    ``push_compliance`` (m/N, the station's): a push travels :func:`push_give` farther, and backs off as much."""
    obj = next((o for o in objects if o.name == action.name), None)
    if obj is None:
        raise ValueError(f"no object named {action.name!r}")
    y_open = -shelf.depth / 2.0
    if isinstance(action, Push):
        sign = 1.0 if action.d > 0 else -1.0
        edge = action.q[0] + sign * tool.geometry.blade_width / 2.0
        x = edge - sign * (BLADE_HALF_THICKNESS + PUSH_STANDOFF)
        y = action.q[1] - BLADE_HALF_LENGTH
        z = tool.geometry.blade_height / 2.0 + BLADE_LIFT
        y_pre = y_open - approach_margin - BLADE_HALF_LENGTH
        shift = push_lane_shift(obj, objects, sign, x, y_pre, y + TUBE_END_PAST_BLADE_FACE, tool)
        x += sign * shift
        gap = BLADE_HALF_THICKNESS + PUSH_STANDOFF - shift - push_lead(float(obj.center[2]) + obj.size[2] / 2.0, tool)
        give = push_give(obj, push_compliance, tool)
        x_end = x + action.d + sign * (gap + give)
        x_back = x_end - sign * (gap + give + push_back_slack(action.d))
        R, f, s = push_rotation(), robot_model.BLADE_FACE_FRAME, robot_model.SHAFT_BLADE_DOWN
        return [
            ToolWaypoint("pre-approach", f, _pose(R, (x, y_pre, z)), s),
            ToolWaypoint("insert", f, _pose(R, (x, y, z)), s),
            ToolWaypoint("push", f, _pose(R, (x_end, y, z)), s, contact=True),
            ToolWaypoint("back off", f, _pose(R, (x_back, y, z)), s, contact=True),
            ToolWaypoint("retract", f, _pose(R, (x_back, y_pre, z)), s, contact=True),
        ]
    if isinstance(action, Suction):
        cx, cy, cz = action.q
        _, ey = Footprint.of(obj).extents()
        oy = float(obj.center[1])
        y_place = cy + (action.dz - oy)
        y_pre = y_open - approach_margin
        y_far = full_pull_out(action, obj, shelf, approach_margin) if pull_to is None else pull_to
        # Lifted on the way out as high as the way out and across needs, pushed in as high as the way across and in
        # needs: the translation between them rises or falls, above what it crosses at both ends.
        way = carry_offsets(action, y_far, y_place, carry_yaw)
        lift_out = carry_lift(obj, objects, way[:3], pivot=action.q[:2])
        lift_in = carry_lift(obj, objects, way[1:], pivot=action.q[:2])
        # The tube comes in along its axis a (turned by the action's yaw toward the face's normal): the
        # pre-approach is on that axis in front of the opening, the cup meets the face along it and presses in;
        # once sealed the tool keeps its yaw and carries the object along S y and x; it backs off along -a.
        ax, ay = action.axis
        back = (cy - y_pre) / ay  # along the axis from the contact to the pre-approach's depth
        px, py = cx + SEAL_PRESS * ax, cy + SEAL_PRESS * ay  # the cup at the seal
        x2 = px + action.dx
        y_in = py + (y_place - cy)  # the cup with the object at its placement
        R, f, s = suction_rotation(action.yaw), robot_model.CUP_TIP_FRAME, robot_model.SHAFT_BLADE_UP
        R_across = suction_rotation(action.yaw + carry_yaw)
        on = dict(contact=True, suction=True)
        x_off, y_off = x2 - (RELEASE_BACKOFF + SEAL_PRESS) * ax, y_in - (RELEASE_BACKOFF + SEAL_PRESS) * ay
        x_out = x_off - (y_off - y_pre) / ay * ax  # the retract, back along the axis to the pre-approach's depth
        if action.drag:  # on the floor all the way, at the seal's height
            slide = dict(carried="resting", **on)
            y_pull = drag_pull_cup_y(action, obj, shelf) + SEAL_PRESS * ay
            weighed = tool.rules.weigh_drag_pull and abs(action.dx) > 1e-9  # rests where the pull is weighed
            return [
                ToolWaypoint("pre-approach", f, _pose(R, (cx - back * ax, y_pre, cz)), s),
                ToolWaypoint("approach", f, _pose(R, (cx - CUP_STANDOFF * ax, cy - CUP_STANDOFF * ay, cz)), s),
                ToolWaypoint("seal", f, _pose(R, (px, py, cz)), s, contact=True, suction=True, dwell=DWELL),
                ToolWaypoint("pull", f, _pose(R, (px, y_pull, cz)), s, dwell=PULL_DWELL if weighed else 0.0, **slide),
                ToolWaypoint("drag across", f, _pose(R, (x2, y_pull, cz)), s, **slide),
                ToolWaypoint("push in", f, _pose(R, (x2, y_in, cz)), s, **slide),
                ToolWaypoint("release", f, _pose(R, (x2, y_in, cz)), s, contact=True, dwell=DWELL),
                ToolWaypoint("back off", f, _pose(R, (x_off, y_off, cz)), s, contact=True),
                ToolWaypoint("retract", f, _pose(R, (x_out, y_pre, cz)), s, contact=True),
            ]
        # the arm weighs the object resting LIFT up (a "weigh" waypoint below a higher lift), before lifting it higher
        weigh = ([ToolWaypoint("weigh", f, _pose(R, (px, py, cz + LIFT)), s, carried="resting", dwell=WEIGH_DWELL, **on)]
                 if lift_out > LIFT + 1e-9 else [])
        return [
            ToolWaypoint("pre-approach", f, _pose(R, (cx - back * ax, y_pre, cz)), s),
            ToolWaypoint("approach", f, _pose(R, (cx - CUP_STANDOFF * ax, cy - CUP_STANDOFF * ay, cz)), s),
            ToolWaypoint("seal", f, _pose(R, (px, py, cz)), s, contact=True, suction=True, dwell=DWELL),
            *weigh,
            ToolWaypoint("lift", f, _pose(R, (px, py, cz + lift_out)), s, carried="resting",
                         dwell=0.0 if weigh else WEIGH_DWELL, **on),
            ToolWaypoint("pull out", f, _pose(R_across, (px, y_far, cz + lift_out)), s, carried="clear", **on),
            ToolWaypoint("translate", f, _pose(R_across, (x2, y_far, cz + lift_in)), s, carried="clear", **on),
            ToolWaypoint("push in", f, _pose(R, (x2, y_in, cz + lift_in)), s, carried="clear", **on),
            ToolWaypoint("lower", f, _pose(R, (x2, y_in, cz)), s, carried="resting", **on),
            ToolWaypoint("release", f, _pose(R, (x2, y_in, cz)), s, contact=True, dwell=DWELL),
            ToolWaypoint("back off", f, _pose(R, (x_off, y_off, cz)), s, contact=True),
            ToolWaypoint("retract", f, _pose(R, (x_out, y_pre, cz)), s, contact=True),
        ]
    raise TypeError(f"not an action: {action!r}")


def drag_pull_cup_y(action, obj: SceneObject, shelf: Shelf) -> float:
    """The contact's y (S) when a dragged object's front is ``DRAG_FRONT_MARGIN`` inside the opening (where the
    action model's drag pulls it: :meth:`slax_drake.shelf.actions.ActionModel.drag_pull_y`), or where it stands
    when it is already that far out."""
    _, ey = Footprint.of(obj).extents()
    oy = float(obj.center[1])
    y_centre = min(oy, -shelf.depth / 2.0 + ey + DRAG_FRONT_MARGIN)
    return action.q[1] + (y_centre - oy)


def full_pull_out(action, obj: SceneObject, shelf: Shelf, approach_margin: float = APPROACH_MARGIN) -> float:
    """The cup's y (S) when the suctioned object's back is ``OUT_MARGIN`` in front of the opening (the action
    model's way out of the shelf), and at least as far out as the pre-approach."""
    _, ey = Footprint.of(obj).extents()
    y_open = -shelf.depth / 2.0
    y_out = action.q[1] + (y_open - ey - OUT_MARGIN - float(obj.center[1]))
    return min(y_out, y_open - approach_margin)


def pull_out_options(action, obj: SceneObject, shelf: Shelf, target=None,
                     approach_margin: float = APPROACH_MARGIN, hidden=None) -> list[float]:
    """Cup y values (S) at which to carry a suctioned object across, in the order to try: the full pull-out,
    then shallower ones ``PULL_STEP`` apart (the object crosses inside the shelf, which the planner's
    carried-object checks then clear against the known objects and the shelf) while the cup is pulled at least
    ``PULL_STEP`` back from its seal. A depth at which the carried object's way across would overlap the
    target's footprint (which the planning world does not hold) is left out, and so is one whose way across
    crosses space hidden from the camera, when ``hidden`` (a :class:`~slax_drake.shelf.floor.FloorGrid` and its
    hidden cells, bool (ny, nx): the ``carry_hidden_check`` rule) is given: the bounding box of the object's
    footprint swept along x at that depth meets a hidden cell (what stands there was never seen)."""
    from slax_drake.scene.footprint import clear_of
    from slax_drake.shelf.floor import band_crosses_hidden

    y_full = full_pull_out(action, obj, shelf, approach_margin)
    cy = action.q[1]
    options = [y_full]
    y = y_full + PULL_STEP
    fp = Footprint.of(obj)
    ex, ey = fp.extents()
    ox = float(obj.center[0])
    while y <= cy - PULL_STEP + 1e-9:
        ok = True
        if hidden is not None:
            grid, cells = hidden
            y_centre = float(obj.center[1]) + (y - (cy + SEAL_PRESS * action.axis[1]))  # the cup seals SEAL_PRESS in
            ok = not bool(band_crosses_hidden(grid, cells, y_centre - ey, y_centre + ey,
                                              ox + min(0.0, action.dx) - ex, ox + max(0.0, action.dx) + ex))
        if ok and target is not None:
            x0, y0 = float(obj.center[0]), float(obj.center[1]) + (y - cy)
            n = max(1, int(np.ceil(abs(action.dx) / SWEEP_STEP)))
            xs = x0 + np.linspace(0.0, action.dx, n + 1)
            centres = np.column_stack([xs, np.full(len(xs), y0)])
            ok = bool(clear_of(fp.shape, centres, fp.yaw, (fp.half_x, fp.half_y), Footprint.of(target.as_object()),
                               TARGET_CLEARANCE).all())
        if ok:
            options.append(float(y))
        y += PULL_STEP
    return options


def carry_options(action, obj: SceneObject, shelf: Shelf, target=None, approach_margin: float = APPROACH_MARGIN,
                  wrist_side: float = 1.0, hidden=None) -> list[tuple[float, float]]:
    """(pull_to, carry_yaw) of the ways to carry a suctioned object across, in the order to try: the depths of
    :func:`pull_out_options` with the tool keeping its yaw, then the full pull-out with the tool turned by
    ``CARRY_YAWS`` about the cup's vertical axis while it carries (:func:`action_waypoints`), each magnitude with
    the sign that swings the wrist toward ``wrist_side`` (+1: S +x; the side away from the shoulder) first. Near
    the robot the arm cannot hold the tube straight along S y (the wrist folds into the shoulder: the elbow and
    the torso are at their limits), turned it can. A turned way is left out when its footprints, turning about
    the cup, would come within ``TARGET_CLEARANCE`` of the target's (the planning world does not hold it).
    ``hidden``: as for :func:`pull_out_options`."""
    if getattr(action, "drag", False):
        return [(drag_pull_cup_y(action, obj, shelf), 0.0)]  # one way: action_waypoints drags it
    options = [(y, 0.0) for y in pull_out_options(action, obj, shelf, target, approach_margin, hidden)]
    y_full = options[0][0]
    y_place = action.q[1] + (action.dz - float(obj.center[1]))
    first = 1.0 if wrist_side >= 0 else -1.0
    for magnitude in CARRY_YAWS:
        for sign in (first, -first):
            yaw = sign * magnitude
            if target is not None:
                sweep = carried_sweep(obj, carry_offsets(action, y_full, y_place, yaw), pivot=action.q[:2])
                if not sweep_clear_of(obj, sweep, target.as_object(), TARGET_CLEARANCE):
                    continue
            options.append((y_full, yaw))
    return options


def carry_offsets(action, y_far: float, y_place: float, carry_yaw: float = 0.0) -> list[tuple[float, float, float]]:
    """The carried way of a suction as a polyline of (dx, dy, dyaw) of the cup from the contact (m, m, rad, S):
    pulled out to cup y ``y_far`` (turning by ``carry_yaw``), across by the action's dx, in until the object's
    centre is at ``y_place`` (turning back)."""
    cy = action.q[1]
    return [(0.0, 0.0, 0.0), (0.0, y_far - cy, carry_yaw), (action.dx, y_far - cy, carry_yaw),
            (action.dx, y_place - cy, 0.0)]


def carried_sweep(obj: SceneObject, offsets, pivot=None) -> list[tuple[np.ndarray, float]]:
    """The footprints of ``obj`` along its carried way, as (centres (K, 2), yaw) groups in S: ``offsets`` is a
    polyline of (dx, dy) or (dx, dy, dyaw) of the cup from where it holds the object (``pivot``, its (x, y) in S;
    the object turns by dyaw about the cup's vertical axis there), sampled so that no point of the footprint
    moves more than ``SWEEP_STEP`` between samples."""
    fp = Footprint.of(obj)
    c0 = np.array([float(obj.center[0]), float(obj.center[1])])
    p0 = c0 if pivot is None else np.asarray(pivot, float)[:2]
    arm = c0 - p0
    reach = float(np.linalg.norm(arm)) + float(np.hypot(fp.half_x, fp.half_y))  # farthest footprint point, m
    points = [(float(o[0]), float(o[1]), float(o[2]) if len(o) > 2 else 0.0) for o in offsets]
    groups = {}
    for (ax, ay, aw), (bx, by, bw) in zip(points[:-1], points[1:]):
        n = max(1, int(np.ceil(max(np.hypot(bx - ax, by - ay), abs(bw - aw) * reach) / SWEEP_STEP)))
        for t in np.linspace(0.0, 1.0, n + 1):
            w = aw + t * (bw - aw)
            c, s_ = np.cos(w), np.sin(w)
            centre = p0 + np.array([ax + t * (bx - ax), ay + t * (by - ay)]) + np.array([c * arm[0] - s_ * arm[1],
                                                                                        s_ * arm[0] + c * arm[1]])
            groups.setdefault(round(w, 9), []).append(centre)
    return [(np.array(centres), fp.yaw + w) for w, centres in groups.items()]


def sweep_clear_of(obj: SceneObject, sweep, other: SceneObject, clearance: float = 0.0) -> bool:
    """Whether every footprint of ``sweep`` (:func:`carried_sweep`) is ``clearance`` clear of ``other``'s."""
    from slax_drake.scene.footprint import clear_of

    fp, fo = Footprint.of(obj), Footprint.of(other)
    return all(bool(clear_of(fp.shape, centres, yaw, (fp.half_x, fp.half_y), fo, clearance).all())
               for centres, yaw in sweep)


def carry_lift(obj: SceneObject, objects, offsets, pivot=None) -> float:
    """How high (m) to lift ``obj`` for its carried way: the polyline ``offsets`` of :func:`carried_sweep`
    ((dx, dy) of its centre, or (dx, dy, dyaw) of the cup at ``pivot``), in S. ``LIFT``, or ``LIFT_CLEARANCE``
    above the tallest other object whose footprint the swept footprint (``SWEEP_STEP`` apart, no clearance)
    overlaps. A neighbour whose estimate overlaps ``obj``'s where it stands (two objects physics left touching,
    :func:`~slax_drake.scene.footprint.touch_overlap`) is one it slides out along, as the planning world lets it
    (:meth:`~slax_drake.planning.world.PlanningWorld.carry`): the sweep is tested against it with ``obj``'s
    footprint shrunk by that overlap and ``TOUCH_ALLOWANCE``, so only a way that goes deeper into it lifts over it."""
    sweep = carried_sweep(obj, offsets, pivot)
    tallest = 0.0
    for other in objects:
        if other.name == obj.name or sweep_clear_of(obj, sweep, other):
            continue
        depth = touch_overlap(obj, other)
        if depth > 0.0:
            slim = _shrunk(obj, depth + TOUCH_ALLOWANCE)
            if sweep_clear_of(slim, carried_sweep(slim, offsets, pivot), other):
                continue
        tallest = max(tallest, float(other.size[2]))
    return LIFT if tallest == 0.0 else max(LIFT, tallest + LIFT_CLEARANCE)


def _shrunk(obj: SceneObject, by: float) -> SceneObject:
    """``obj`` with its footprint shrunk by ``by`` (m) on every side (its height kept)."""
    sx, sy, sz = obj.size
    return dataclasses.replace(obj, size=(max(1e-4, sx - 2.0 * by), max(1e-4, sy - 2.0 * by), sz))
