"""DepthNoiseSystem: the L515 depth-sensor model (``perception.sensor_noise``) as a Drake LeafSystem.

Input port:
    depth_image   ImageDepth32F (W x H), metres along the optical axis; 0 and +inf count as no return.
Output port:
    depth_image   ImageDepth32F (W x H): the same frame as an L515 would return it -- range noise growing with
                  distance, no return at depth edges, on grazing surfaces and outside 0.25-9 m, 0 where there is
                  no return (see :mod:`slax_drake.perception.sensor_noise` for the model and the datasheet
                  figures it uses).

Deterministic: the output depends only on the input image, the ``seed`` given at construction and the
context's time, whose microsecond count is the noise's time step (so re-evaluating at one time gives the same
image, and a new time gives fresh noise). Placed between the station camera and the PerceptionSystem.
"""

from __future__ import annotations

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.systems.framework import LeafSystem
from pydrake.systems.sensors import ImageDepth32F

from slax_drake.perception.sensor_noise import L515Noise, l515_depth_noise
from slax_drake.scene.camera import Camera

TIME_STEP_RESOLUTION = 1e-6  # seconds per noise time step


class DepthNoiseSystem(LeafSystem):
    """depth_image -> depth_image with the L515 model; ``camera`` is the camera that takes the images (its
    resolution must match the input's)."""

    def __init__(self, camera: Camera, seed: int, noise: L515Noise = L515Noise()):
        LeafSystem.__init__(self)
        if int(seed) < 0:
            raise ValueError(f"seed must be a non-negative integer, got {seed}")
        self._camera = camera
        self._seed = int(seed)
        self._noise = noise
        w, h = camera.width, camera.height
        self._input = self.DeclareAbstractInputPort("depth_image", AbstractValue.Make(ImageDepth32F(w, h)))
        self.DeclareAbstractOutputPort(
            "depth_image", lambda: AbstractValue.Make(ImageDepth32F(w, h)), self._calc,
            prerequisites_of_calc={self._input.ticket(), self.time_ticket()},
        )

    @property
    def seed(self) -> int:
        return self._seed

    def _calc(self, context, output) -> None:
        image = self._input.Eval(context)
        if (image.width(), image.height()) != (self._camera.width, self._camera.height):
            raise ValueError(
                f"depth_image is {image.width()}x{image.height()}, the camera is "
                f"{self._camera.width}x{self._camera.height}"
            )
        depth = np.array(image.data[:, :, 0], dtype=np.float32)
        step = int(round(context.get_time() / TIME_STEP_RESOLUTION))
        noisy = l515_depth_noise(depth, self._camera, self._seed, step, self._noise)
        result = ImageDepth32F(self._camera.width, self._camera.height)
        result.mutable_data[:, :, 0] = noisy
        output.set_value(result)
