"""The suction cup of the bluction tool as a force element (a LeafSystem feeding the plant's applied forces).

Model (after the pressure model discussed in Drake's issue tracker,
https://github.com/RobotLocomotion/drake/issues/13977, and Drake's suction-gripper example,
https://github.com/RobotLocomotion/drake/pull/19491):

- A vacuum of ``vacuum_pressure`` (Pa) acts over the cup's area A = pi * cup_radius^2, so a sealed cup pulls
  with at most F_max = vacuum_pressure * A (60 kPa over a 0.03 m cup: 42.4 N).
- Each step the element finds the object body nearest to the cup tip (``cup_tip_frame``): the signed distance
  d from the tip to the object's surface, the outward surface normal n at the nearest point N, and the cup axis
  a (``cup_tip_frame``'s x). Suction acts only when the command is on (> 0.5), d < ``max_distance`` and the cup
  looks at the surface: angle(a, -n) < ``max_angle_deg``.
- The pull has magnitude F = F_max * clamp(1 - d / max_distance, 0, 1): full pressure when the lip touches
  (d <= 0), falling linearly to zero at ``max_distance`` (a leaking, not yet sealed cup). It acts on the object
  at N along n (toward the cup) and, opposite, on the tool at the cup tip.
- The seal breaks by itself: the pull presses the object onto the cup's lip (eight spheres on the rim of the cup
  in the robot model), so the lip's contact forces carry moments and friction (mu * F) carries shear. A pull-off
  load above F_max opens a gap, which lowers F further, and the object drops; a shear or moment load above what
  the lip holds slides or tilts the face away from the cup axis until the distance or angle test fails.

Inputs: ``suction_command`` (1-vector, on when > 0.5), ``query_object`` (from SceneGraph).
Output: ``spatial_forces`` (a list of ExternallyAppliedSpatialForce for the plant's
``applied_spatial_force`` input) and ``suction_state`` (1-vector: the present pull in newtons, 0 when off).
"""

import math

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.multibody.math import SpatialForce
from pydrake.multibody.plant import ExternallyAppliedSpatialForce
from pydrake.systems.framework import LeafSystem

from slax_drake.station.scenario import SuctionParameters


class SuctionCup(LeafSystem):
    """Suction force element acting between the tool's cup and the nearest free object (see module docstring).

    ``plant`` must be finalized and registered with the SceneGraph whose ``query_object`` feeds this system.
    ``cup_frame`` is the plant frame at the cup tip, x along the cup axis pointing away from the tool.
    Only bodies in ``object_bodies`` (BodyIndex list; default: every free body) can be picked.
    """

    def __init__(self, plant, scene_graph, cup_frame, params: SuctionParameters | None = None, object_bodies=None):
        super().__init__()
        self._params = params or SuctionParameters()
        self._cup_body_index = cup_frame.body().index()
        self._X_BT = cup_frame.GetFixedPoseInBodyFrame()  # cup tip in the cup's body frame
        self._cup_frame_id = plant.GetBodyFrameIdOrThrow(self._cup_body_index)
        if object_bodies is None:
            object_bodies = [i for i in plant.GetFloatingBaseBodies()]
        # geometry id -> body index for the proximity geometries of the pickable bodies; body index -> frame id
        self._geometry_body = {}
        self._body_frame = {}
        for body_index in object_bodies:
            body = plant.get_body(body_index)
            self._body_frame[body_index] = plant.GetBodyFrameIdOrThrow(body_index)
            for geometry_id in plant.GetCollisionGeometriesForBody(body):
                self._geometry_body[geometry_id] = body_index
        self.DeclareVectorInputPort("suction_command", 1)
        self.DeclareAbstractInputPort("query_object", AbstractValue.Make(scene_graph.get_query_output_port().Allocate().get_value()))
        self.DeclareAbstractOutputPort(
            "spatial_forces", lambda: AbstractValue.Make([ExternallyAppliedSpatialForce()]), self._calc_forces
        )
        self.DeclareVectorOutputPort("suction_state", 1, self._calc_state)

    @property
    def params(self) -> SuctionParameters:
        return self._params

    def grip(self, context):
        """(body index, pull in N, point N in world, normal n in world) of the present pull, or None."""
        if self.get_input_port(0).Eval(context)[0] <= 0.5:
            return None
        query = self.get_input_port(1).Eval(context)
        p = self._params
        X_WB = query.GetPoseInWorld(self._cup_frame_id)
        X_WT = X_WB @ self._X_BT
        p_WT = X_WT.translation()
        axis_W = X_WT.rotation().matrix()[:, 0].copy()
        best = None
        for result in query.ComputeSignedDistanceToPoint(p_WT, p.max_distance):
            owner = self._geometry_body.get(result.id_G)
            if owner is None:
                continue
            if best is None or result.distance < best[1].distance:
                best = (owner, result)
        if best is None:
            return None
        body_index, result = best
        normal_W = np.asarray(result.grad_W, dtype=float)
        norm = np.linalg.norm(normal_W)
        if not norm > 0.5:  # gradient undefined (tip at the centre of a shape)
            return None
        normal_W = normal_W / norm
        if float(np.dot(axis_W, -normal_W)) < math.cos(math.radians(p.max_angle_deg)):
            return None
        scale = min(1.0, max(0.0, 1.0 - result.distance / p.max_distance))
        if scale <= 0.0:
            return None
        X_WG = query.GetPoseInWorld(result.id_G)
        p_WN = X_WG.multiply(np.asarray(result.p_GN, dtype=float))
        return body_index, p.max_force * scale, p_WN, normal_W, p_WT

    def _calc_forces(self, context, output):
        grip = self.grip(context)
        if grip is None:
            output.set_value([])
            return
        body_index, force, p_WN, normal_W, p_WT = grip
        query = self.get_input_port(1).Eval(context)
        X_WO = query.GetPoseInWorld(self._body_frame[body_index])
        X_WC = query.GetPoseInWorld(self._cup_frame_id)
        on_object = ExternallyAppliedSpatialForce()
        on_object.body_index = body_index
        on_object.p_BoBq_B = X_WO.inverse().multiply(p_WN)
        on_object.F_Bq_W = SpatialForce(np.zeros(3), force * normal_W)
        on_tool = ExternallyAppliedSpatialForce()
        on_tool.body_index = self._cup_body_index
        on_tool.p_BoBq_B = X_WC.inverse().multiply(p_WT)
        on_tool.F_Bq_W = SpatialForce(np.zeros(3), -force * normal_W)
        output.set_value([on_object, on_tool])

    def _calc_state(self, context, output):
        grip = self.grip(context)
        output.SetAtIndex(0, 0.0 if grip is None else grip[1])
