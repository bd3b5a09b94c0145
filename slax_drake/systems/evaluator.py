"""EvaluatorSystem: the trial's referee, the only system of the trial diagram that reads ground truth.

Input ports:
    label_image   ImageLabel16I: the render's labels (0 shelf, i + 1 for scene object i, n + 1 the target).
    body_poses    the plant's body poses (world frame).
    deciding      BasicVector(1) from the planner: 1.0 at the ticks where it decides (robot idle, trial running).
    segmentation  ImageLabel16I from the PerceptionSystem: its occluder segments, to tell which true object each
                  hypothesis ``segment_<id>`` is (the object most of the segment's pixels show in the label image).
Output port:
    stop          BasicVector(1): 1.0 once the target's visible fraction has reached the threshold v (success),
                  else 0.0. The planner reads it (it never sees the fraction or any pose) and ends the trial.

Every ``period`` seconds (the planner's decision period, same phase) a periodic update checks ``deciding``; when the
planner decides at this tick it records one :class:`Snapshot` (so the camera is not rendered between decisions): the
target's visible fraction (its pixels in the label image over the pixels it covers with no occluder where it stands
now, ray-cast again whenever the target has moved: a target a move pushed deeper covers fewer pixels, and all of it
seen must read 1) and the objects lost (toppled: z axis tilted over 20 deg; dropped: centre outside the bay), with
every object's planar pose in the shelf frame S. The runner joins them to the planner's decisions by time for the
trial record. The ``stop`` output is computed from the label image directly (a direct feedthrough), so the planner
sees success at the very tick it happens.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.systems.framework import BasicVector, LeafSystem
from pydrake.systems.sensors import ImageLabel16I

from slax_drake.scene.model import Scene

TOPPLE_ANGLE = math.radians(20.0)


@dataclasses.dataclass(frozen=True)
class Snapshot:
    """What the evaluator saw at ``time`` s: ``visible_fraction`` of the target, ``lost`` object names, ``poses``
    {name: (x, y, yaw)} in S (metres, radians), ``segments`` {"segment_<id>": true object name}."""

    time: float
    visible_fraction: float
    lost: tuple
    poses: dict
    segments: dict


class EvaluatorSystem(LeafSystem):
    """See the module docstring. ``scene``: the trial's initial scene (names, camera, target); ``body_indices``:
    the plant BodyIndex of every scene object (scene order); ``target_body_index``: the target's (None: it stands
    where the scene puts it); ``X_WS``: the shelf frame in the world."""

    def __init__(self, scene: Scene, body_indices, X_WS, threshold: float = 0.80, period: float = 0.1,
                 image_size=(640, 480), target_body_index=None):
        LeafSystem.__init__(self)
        self.scene = scene
        self.body_indices = list(body_indices)
        self.target_body_index = target_body_index
        self.X_SW = X_WS.inverse()
        self.threshold = threshold
        self._target_pixels = None  # ((rounded pose, image shape), pixels): the last ray-cast of the target alone
        w, h = image_size
        self._labels = self.DeclareAbstractInputPort("label_image", AbstractValue.Make(ImageLabel16I(w, h)))
        self._poses = self.DeclareAbstractInputPort("body_poses", AbstractValue.Make([X_WS]))
        self._deciding = self.DeclareVectorInputPort("deciding", 1)
        self._segmentation = self.DeclareAbstractInputPort("segmentation", AbstractValue.Make(ImageLabel16I(1, 1)))
        self._log = self.DeclareAbstractState(AbstractValue.Make(()))
        self.DeclareInitializationUnrestrictedUpdateEvent(self._reset)
        self.DeclarePeriodicUnrestrictedUpdateEvent(period, 0.0, self._record)
        self.DeclareVectorOutputPort("stop", BasicVector(1), self._calc_stop,
                                     prerequisites_of_calc={self._labels.ticket()})

    def snapshots(self, root_context) -> tuple:
        """Every Snapshot recorded so far, in time order."""
        return self.GetMyContextFromRoot(root_context).get_abstract_state(self._log).get_value()

    def snapshot_at(self, root_context, time: float) -> Snapshot | None:
        """The snapshot recorded at ``time`` (to 1e-6 s), or None."""
        return next((s for s in self.snapshots(root_context) if abs(s.time - time) < 1e-6), None)

    # ---------------------------------------------------------------------------------------------------------
    def target_pose(self, context) -> np.ndarray:
        """X_ST (4x4) of the target where it stands now: the plant's pose of its body, or the scene's."""
        if self.target_body_index is None:
            return self.scene.target.X_ST
        return (self.X_SW @ self._poses.Eval(context)[int(self.target_body_index)]).GetAsMatrix4()

    def visible_fraction(self, context) -> float:
        """The target's pixels in the label image over the pixels it covers where it stands now with nothing in
        front of it (ray-cast at the label image's size, again only when it moved by 0.1 mm or 1e-4 in rotation)."""
        raw = np.array(self._labels.Eval(context).data[:, :, 0], dtype=np.int32)
        target_label = len(self.scene.objects) + 1
        X_ST = self.target_pose(context)
        key = (tuple(np.round(X_ST[:3, :].ravel(), 4)), raw.shape)
        if self._target_pixels is None or self._target_pixels[0] != key:
            from slax_drake.scene.raycast import SceneRaycaster

            h, w = raw.shape
            alone = dataclasses.replace(self.scene, objects=(),
                                        target=dataclasses.replace(self.scene.target, X_ST=X_ST))
            _, lab = SceneRaycaster(alone, include_target=True).render(self.scene.camera.with_resolution(w, h))
            self._target_pixels = (key, max(1, int(np.count_nonzero(lab == 1))))
        return float(np.count_nonzero(raw == target_label)) / self._target_pixels[1]

    def poses_and_lost(self, context) -> tuple[dict, list]:
        poses = self._poses.Eval(context)
        shelf = self.scene.shelf
        out, lost = {}, []
        for obj, index in zip(self.scene.objects, self.body_indices):
            X_SO = (self.X_SW @ poses[int(index)]).GetAsMatrix4()
            c = X_SO[:3, 3]
            tilt = math.acos(min(1.0, max(-1.0, abs(X_SO[2, 2]))))
            inside = abs(c[0]) < shelf.width / 2 and abs(c[1]) < shelf.depth / 2 and -0.02 < c[2] < shelf.height
            if tilt > TOPPLE_ANGLE or not inside:
                lost.append(obj.name)
            out[obj.name] = (float(c[0]), float(c[1]), math.atan2(X_SO[1, 0], X_SO[0, 0]))
        return out, lost

    def segment_owners(self, context) -> dict:
        """{"segment_<id>": the scene object most of the segment's pixels show in the label image}."""
        segments = np.array(self._segmentation.Eval(context).data[:, :, 0], dtype=np.int32)
        raw = np.array(self._labels.Eval(context).data[:, :, 0], dtype=np.int32)
        h, w = segments.shape
        rows = np.clip(np.rint((np.arange(h) + 0.5) * raw.shape[0] / h - 0.5), 0, raw.shape[0] - 1).astype(int)
        cols = np.clip(np.rint((np.arange(w) + 0.5) * raw.shape[1] / w - 0.5), 0, raw.shape[1] - 1).astype(int)
        labels = raw[np.ix_(rows, cols)]
        n = len(self.scene.objects)
        owners = {}
        for sid in np.unique(segments[segments > 0]):
            under = labels[segments == sid]
            under = under[(under >= 1) & (under <= n)]
            if len(under):
                owners[f"segment_{int(sid)}"] = self.scene.objects[int(np.bincount(under).argmax()) - 1].name
        return owners

    def _calc_stop(self, context, output) -> None:
        output.SetAtIndex(0, 1.0 if self.visible_fraction(context) >= self.threshold else 0.0)

    def _reset(self, context, state) -> None:
        state.get_mutable_abstract_state(0).set_value(())

    def _record(self, context, state) -> None:
        if self._deciding.Eval(context)[0] < 0.5:
            return
        log = context.get_abstract_state(self._log).get_value()
        poses, lost = self.poses_and_lost(context)
        snap = Snapshot(round(context.get_time(), 6), self.visible_fraction(context), tuple(lost), poses,
                        self.segment_owners(context))
        state.get_mutable_abstract_state(0).set_value(log + (snap,))
