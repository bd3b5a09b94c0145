"""PerceptionSystem: camera frames -> what the planner may know (segmentation, target mask, object hypotheses,
the target occupancy distribution), as a Drake LeafSystem.

Input ports:
    depth_image      ImageDepth32F, metres along the optical axis, at the resolution of ``input_camera`` (default:
                     the working resolution); 0 and +inf (Drake's too-near / too-far) count as no return.
    label_image      ImageLabel16I (only with ``target_label``): the render's labels. Its pixels equal to
                     ``target_label`` are the target mask (the simulation's stand-in for detecting the target by
                     its known colour); with ``segmentation="labels"`` its labels 1 .. target_label - 1 are also the
                     occluders' segmentation (the idealised segmentation option).
Output ports (all at the working resolution W x H: the network's, or ``width`` px wide for the depth source):
    occupancy_1d     BasicVector of size W: the 1D target distribution along image x (sums to one, zero outside the
                     support), from the ``source``: "network" (the occupancy network) or "depth" (the hidden
                     placements judged from the depth image, ``occupancy.from_depth``, clear of the hypotheses).
    occupancy_2d     AbstractValue holding a (H, W) float32 numpy array: the 2D distribution.
    segmentation     ImageLabel16I (W x H): instance labels of the occluding objects, 0 for the shelf, background and
                     the target ("depth": ``perception.segmentation.segment_depth``; "labels": see above).
    target_mask      AbstractValue holding a (H, W) bool array.
    observation      AbstractValue holding the :class:`~slax_drake.perception.observation.Observation` (depth,
                     segmentation, target mask, working camera).
    hypotheses       AbstractValue holding a tuple of :class:`~slax_drake.perception.estimator.Hypothesis`, one per
                     segment (``segment_<id>``).

A frame at another resolution than the working one is resampled to the nearest pixel (depth and labels alike, no
mixing of ranges across edges). Nothing is computed per simulation step: each result is a cache entry that depends
only on the input ports, so it is computed when a port is evaluated after the frame changed, once for all ports.
"""

from __future__ import annotations

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.systems.framework import BasicVector, LeafSystem, ValueProducer
from pydrake.systems.sensors import ImageDepth32F, ImageLabel16I

from slax_drake.errors import ImageSizeError
from slax_drake.perception.estimator import estimate_objects
from slax_drake.perception.observation import Observation, occluder_segmentation, resample_nearest
from slax_drake.perception.segmentation import segment_depth
from slax_drake.scene.camera import Camera
from slax_drake.scene.model import Shelf

SEGMENTATIONS = ("depth", "labels")
SOURCES = ("network", "depth")


class PerceptionSystem(LeafSystem):
    """Camera frames -> segmentation, target mask, observation, hypotheses and occupancy (see the module docstring).

    ``camera`` is the observing camera (any resolution with the working aspect; it is rescaled to the working
    resolution), ``shelf`` the bay; both are needed to tell objects from shelf panels. ``source``: "network"
    (``model``: a weight file path, a loaded model or None for the shipped default; the working resolution is the
    model's) or "depth" (working resolution ``width`` px wide). ``input_camera``: the camera of the incoming frames
    when they are not at the working resolution (the station camera). ``target_label``: declares the
    ``label_image`` input (see the module docstring); None: no target mask (all False)."""

    def __init__(self, camera: Camera, shelf: Shelf, target_size=(0.06, 0.06, 0.06), model=None,
                 num_threads: int | None = 1, source: str = "network", segmentation: str = "depth",
                 target_label: int | None = None, input_camera: Camera | None = None, width: int = 160):
        LeafSystem.__init__(self)
        if source not in SOURCES:
            raise ValueError(f"source must be one of {SOURCES}, got {source!r}")
        if segmentation not in SEGMENTATIONS:
            raise ValueError(f"segmentation must be one of {SEGMENTATIONS}, got {segmentation!r}")
        if segmentation == "labels" and target_label is None:
            raise ValueError("segmentation 'labels' needs the label image: give target_label")
        self._source_kind = source
        if source == "network":
            from slax_drake.perception.inference import OccupancyPredictor

            self._predictor = OccupancyPredictor(model, num_threads=num_threads)
            self._head = self._predictor.head_of(target_size)
            width, height = self._predictor.resolution
            if abs(camera.width * height - camera.height * width) > 0:
                raise ImageSizeError(f"camera {camera.width}x{camera.height} does not have the aspect of the model's "
                                     f"{width}x{height} images")
        else:
            height = max(1, int(round(camera.height * width / camera.width)))
        self._target_size = tuple(float(v) for v in target_size)
        self._camera = camera.with_resolution(width, height)
        self._input_camera = input_camera or self._camera
        self._shelf = shelf
        self._width, self._height = width, height
        self._segmentation_kind = segmentation
        self._target_label = target_label
        self.network_evaluations = 0
        self.segmentations = 0

        w_in, h_in = self._input_camera.width, self._input_camera.height
        self._depth_port = self.DeclareAbstractInputPort("depth_image", AbstractValue.Make(ImageDepth32F(w_in, h_in)))
        tickets = {self._depth_port.ticket()}
        self._label_port = None
        if target_label is not None:
            self._label_port = self.DeclareAbstractInputPort("label_image",
                                                             AbstractValue.Make(ImageLabel16I(w_in, h_in)))
            tickets.add(self._label_port.ticket())

        def entry(description, calc, prerequisites):
            return self.DeclareCacheEntry(
                description=description,
                value_producer=ValueProducer(allocate=lambda: AbstractValue.Make(object()), calc=calc),
                prerequisites_of_calc=prerequisites)

        self._frame = entry("frame at the working resolution", self._calc_frame, tickets)
        self._segments = entry("segmentation", self._calc_segments, {self._frame.ticket()})
        self._observed = entry("observation", self._calc_observation, {self._segments.ticket()})
        self._estimated = entry("hypotheses", self._calc_hypotheses, {self._observed.ticket()})
        occupancy_needs = {self._frame.ticket()} if source == "network" else {self._estimated.ticket()}
        self._prediction = entry("occupancy", self._calc_prediction, occupancy_needs)
        prediction_ticket = {self._prediction.ticket()}
        self.DeclareVectorOutputPort("occupancy_1d", BasicVector(width), self._calc_occupancy_1d,
                                     prerequisites_of_calc=prediction_ticket)
        self.DeclareAbstractOutputPort(
            "occupancy_2d", lambda: AbstractValue.Make(np.zeros((height, width), np.float32)),
            self._calc_occupancy_2d, prerequisites_of_calc=prediction_ticket,
        )
        self.DeclareAbstractOutputPort(
            "segmentation", lambda: AbstractValue.Make(ImageLabel16I(width, height)), self._calc_segmentation,
            prerequisites_of_calc={self._segments.ticket()},
        )
        self.DeclareAbstractOutputPort(
            "target_mask", lambda: AbstractValue.Make(np.zeros((height, width), bool)),
            lambda context, output: output.set_value(self._frame.Eval(context)[1]),
            prerequisites_of_calc={self._frame.ticket()},
        )
        self.DeclareAbstractOutputPort(
            "observation", lambda: AbstractValue.Make(object()),
            lambda context, output: output.set_value(self._observed.Eval(context)),
            prerequisites_of_calc={self._observed.ticket()},
        )
        self.DeclareAbstractOutputPort(
            "hypotheses", lambda: AbstractValue.Make(()),
            lambda context, output: output.set_value(self._estimated.Eval(context)),
            prerequisites_of_calc={self._estimated.ticket()},
        )

    @property
    def camera(self) -> Camera:
        """The working camera (the outputs' resolution)."""
        return self._camera

    # caches ----------------------------------------------------------------------------------------------
    def _resampled(self, image: np.ndarray) -> np.ndarray:
        return resample_nearest(image, self._width, self._height)

    def _depth(self, context) -> np.ndarray:
        image = self._depth_port.Eval(context)
        expected = (self._input_camera.width, self._input_camera.height)
        if (image.width(), image.height()) != expected:
            raise ImageSizeError(f"depth_image is {image.width()}x{image.height()}, expected {expected[0]}x{expected[1]}")
        depth = np.array(image.data[:, :, 0], dtype=np.float32)
        return self._resampled(np.where(np.isfinite(depth), depth, 0.0).astype(np.float32))

    def _calc_frame(self, context, value) -> None:
        """(depth, target mask, render labels or None) at the working resolution."""
        depth = self._depth(context)
        labels = None
        mask = np.zeros(depth.shape, bool)
        if self._label_port is not None:
            labels = self._resampled(np.array(self._label_port.Eval(context).data[:, :, 0], dtype=np.int32))
            mask = labels == self._target_label
        value.set_value((depth, mask, labels))

    def _calc_segments(self, context, value) -> None:
        self.segmentations += 1
        depth, mask, labels = self._frame.Eval(context)
        if self._segmentation_kind == "labels":
            raw = np.where((labels >= 1) & (labels < self._target_label), labels, 0)
        else:
            raw = segment_depth(depth, self._camera, self._shelf)
        value.set_value(occluder_segmentation(raw, mask) if mask.any() else raw.astype(np.int32))

    def _calc_observation(self, context, value) -> None:
        depth, mask, _ = self._frame.Eval(context)
        value.set_value(Observation(depth, self._segments.Eval(context), mask, self._camera, min_valid_fraction=0.0))

    def _calc_hypotheses(self, context, value) -> None:
        value.set_value(tuple(estimate_objects(self._observed.Eval(context), self._shelf)))

    def _calc_prediction(self, context, value) -> None:
        if self._source_kind == "network":
            self.network_evaluations += 1
            predicted = self._predictor.predict(self._frame.Eval(context)[0], head=self._head)
            value.set_value((predicted.p1d[0], predicted.p2d[0]))
            return
        from slax_drake.occupancy.from_depth import occupancy_from_depth

        obs = self._observed.Eval(context)
        obstacles = tuple(h.object for h in self._estimated.Eval(context))
        occ = occupancy_from_depth(obs.depth, self._camera, self._shelf, self._target_size, obstacles=obstacles)
        value.set_value((occ.p1d, occ.p2d))

    # outputs ---------------------------------------------------------------------------------------------
    def _calc_occupancy_1d(self, context, output) -> None:
        output.SetFromVector(np.asarray(self._prediction.Eval(context)[0], dtype=np.float64))

    def _calc_occupancy_2d(self, context, output) -> None:
        output.set_value(np.asarray(self._prediction.Eval(context)[1], dtype=np.float32))

    def _calc_segmentation(self, context, output) -> None:
        image = ImageLabel16I(self._width, self._height)
        image.mutable_data[:, :, 0] = self._segments.Eval(context).astype(np.int16)
        output.set_value(image)
