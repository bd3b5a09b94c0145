"""PerceptionSystem: the occupancy network and the depth-only segmentation as a Drake LeafSystem.

Input port:
    depth_image      ImageDepth32F, metres along the optical axis, at the model's resolution (W x H);
                     0 and +inf (Drake's too-near / too-far) count as no return.
Output ports:
    occupancy_1d     BasicVector of size W: the predicted 1D target distribution along image x (sums to one,
                     zero outside the predicted support) for the chosen target ratio.
    occupancy_2d     AbstractValue holding a (H, W) float32 numpy array: the predicted 2D distribution.
    segmentation     ImageLabel16I (W x H): instance labels of the occluding objects, 0 for the shelf and
                     background (``perception.segmentation.segment_depth``).

Nothing is computed per simulation step: the network runs in a cache entry that depends only on the input
port, so it runs when one of the distribution ports is evaluated after the depth image changed, once for
both ports; the segmentation likewise runs only when its port is evaluated.
"""

from __future__ import annotations

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.systems.framework import BasicVector, LeafSystem, ValueProducer
from pydrake.systems.sensors import ImageDepth32F, ImageLabel16I

from slax_drake.perception.errors import ImageSizeError
from slax_drake.perception.inference import OccupancyPredictor, PredictedOccupancy
from slax_drake.perception.segmentation import segment_depth
from slax_drake.scene.camera import Camera
from slax_drake.scene.model import Shelf


class PerceptionSystem(LeafSystem):
    """Depth image -> occupancy_1d, occupancy_2d and segmentation (see the module docstring).

    ``camera`` is the observing camera (any resolution with the model's aspect; it is rescaled to the model's
    resolution), ``shelf`` the bay; both are needed to tell objects from shelf panels in the segmentation.
    ``model`` is a weight file path, a loaded model or None for the shipped default."""

    def __init__(self, camera: Camera, shelf: Shelf, target_size=(0.06, 0.06, 0.06), model=None,
                 num_threads: int | None = 1):
        LeafSystem.__init__(self)
        self._predictor = OccupancyPredictor(model, num_threads=num_threads)
        self._head = self._predictor.head_of(target_size)
        width, height = self._predictor.resolution
        if abs(camera.width * height - camera.height * width) > 0:
            raise ImageSizeError(
                f"camera {camera.width}x{camera.height} does not have the aspect of the model's {width}x{height} images"
            )
        self._camera = camera.with_resolution(width, height)
        self._shelf = shelf
        self._width, self._height = width, height
        self.network_evaluations = 0
        self.segmentations = 0

        self._depth_port = self.DeclareAbstractInputPort("depth_image", AbstractValue.Make(ImageDepth32F(width, height)))
        ticket = {self._depth_port.ticket()}
        self._prediction = self.DeclareCacheEntry(
            description="network prediction",
            value_producer=ValueProducer(
                allocate=lambda: AbstractValue.Make(object()), calc=self._calc_prediction
            ),
            prerequisites_of_calc=ticket,
        )
        prediction_ticket = {self._prediction.ticket()}
        self.DeclareVectorOutputPort("occupancy_1d", BasicVector(width), self._calc_occupancy_1d,
                                     prerequisites_of_calc=prediction_ticket)
        self.DeclareAbstractOutputPort(
            "occupancy_2d", lambda: AbstractValue.Make(np.zeros((height, width), np.float32)),
            self._calc_occupancy_2d, prerequisites_of_calc=prediction_ticket,
        )
        self.DeclareAbstractOutputPort(
            "segmentation", lambda: AbstractValue.Make(ImageLabel16I(width, height)), self._calc_segmentation,
            prerequisites_of_calc=ticket,
        )

    def _depth(self, context) -> np.ndarray:
        image = self._depth_port.Eval(context)
        if (image.width(), image.height()) != (self._width, self._height):
            raise ImageSizeError(
                f"depth_image is {image.width()}x{image.height()}, the model takes {self._width}x{self._height}"
            )
        depth = np.array(image.data[:, :, 0], dtype=np.float32)
        return np.where(np.isfinite(depth), depth, 0.0).astype(np.float32)

    def _calc_prediction(self, context, value) -> None:
        self.network_evaluations += 1
        value.set_value(self._predictor.predict(self._depth(context), head=self._head))

    def _predicted(self, context) -> PredictedOccupancy:
        return self._prediction.Eval(context)

    def _calc_occupancy_1d(self, context, output) -> None:
        output.SetFromVector(self._predicted(context).p1d[0].astype(np.float64))

    def _calc_occupancy_2d(self, context, output) -> None:
        output.set_value(self._predicted(context).p2d[0])

    def _calc_segmentation(self, context, output) -> None:
        self.segmentations += 1
        labels = segment_depth(self._depth(context), self._camera, self._shelf)
        image = ImageLabel16I(self._width, self._height)
        image.mutable_data[:, :, 0] = labels.astype(np.int16)
        output.set_value(image)
