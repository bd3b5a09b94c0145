"""What the robot sees at one step: the observation that perception hands to the estimator and the policies.

An :class:`Observation` holds, all at the camera's resolution (H, W):

- ``depth``: float32 metres along the optical axis; 0 where the sensor has no return (too near, too far,
  dropped). Non-finite values given to the constructor (Drake's +inf beyond range, NaN) are stored as 0.
- ``segmentation``: int32 instance labels of the *occluding* objects, 0 for shelf, background and the target.
- ``target_mask``: bool, the pixels where the target is seen. A real robot finds them by the target's known
  colour (:func:`target_mask_from_color`); in simulation the label image's target id stands in for colour
  detection (:func:`target_mask_from_labels`).
- ``camera``: the :class:`~slax_drake.scene.camera.Camera` that took the frame (intrinsics and X_SC), so that
  pixels back-project into the shelf frame S.
- ``joint_state``: the robot's joint positions (radians / metres, the station's order), or None.

The constructor validates everything: a frame that does not fit the camera, a wrong data type, or a depth image
with mostly no returns raises :class:`~slax_drake.errors.ObservationError` (a user error: one line,
exit code 2), since real frames reach it from files (``plan-step``).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from slax_drake.errors import ObservationError
from slax_drake.scene.camera import Camera

MIN_VALID_FRACTION = 0.5  # an observation needs depth returns on at least this fraction of its pixels


@dataclasses.dataclass(frozen=True, eq=False)
class Observation:
    """One camera frame with its occluder segmentation and target mask (see the module docstring)."""

    depth: np.ndarray
    segmentation: np.ndarray
    target_mask: np.ndarray
    camera: Camera
    joint_state: np.ndarray | None = None
    min_valid_fraction: float = MIN_VALID_FRACTION

    def __post_init__(self) -> None:
        shape = (self.camera.height, self.camera.width)
        object.__setattr__(self, "depth", _checked_depth(self.depth, shape, self.camera, self.min_valid_fraction))
        object.__setattr__(self, "segmentation", _checked_segmentation(self.segmentation, shape))
        object.__setattr__(self, "target_mask", _checked_mask(self.target_mask, shape))
        if self.joint_state is not None:
            object.__setattr__(self, "joint_state", _checked_joint_state(self.joint_state))
        both = int(np.count_nonzero(self.target_mask & (self.segmentation > 0)))
        if both:
            raise ObservationError(
                f"{both} pixels are both in the target mask and in an occluder segment; remove the target's pixels "
                "from the segmentation (occluder_segmentation does)"
            )

    @property
    def valid(self) -> np.ndarray:
        """(H, W) bool: pixels with a depth return."""
        return self.depth > 0

    @property
    def segment_ids(self) -> list[int]:
        """The occluder labels present, ascending."""
        ids = np.unique(self.segmentation)
        return [int(i) for i in ids if i > 0]

    @property
    def target_visible_pixels(self) -> int:
        return int(np.count_nonzero(self.target_mask))

    def replaced(self, **changes) -> "Observation":
        """A copy with some fields changed (validated again)."""
        return dataclasses.replace(self, **changes)


def resample_nearest(image: np.ndarray, width: int, height: int) -> np.ndarray:
    """``image`` (h, w), any dtype, at ``width`` x ``height``: each pixel takes the value of the input pixel nearest
    its centre (the same field of view; no mixing of values across edges, so depth and labels resample alike).
    When the scale is an even integer the centre falls between two input pixels and the one below and to the
    right is taken (round half to even): the frame is then that of the working camera shifted by a quarter of an
    input pixel per halving, e.g. 1/8 px at 640 -> 160. Returns ``image`` itself at its own resolution."""
    h, w = image.shape[:2]
    if (w, h) == (width, height):
        return image
    rows = np.clip(np.rint((np.arange(height) + 0.5) * h / height - 0.5), 0, h - 1).astype(int)
    cols = np.clip(np.rint((np.arange(width) + 0.5) * w / width - 0.5), 0, w - 1).astype(int)
    return image[np.ix_(rows, cols)]


def occluder_segmentation(labels: np.ndarray, target_mask: np.ndarray, min_pixels: int = 1) -> np.ndarray:
    """Instance labels (H, W) of all objects (e.g. from ``segment_depth``, which cannot tell the target from
    an occluder) -> labels of the occluders only: target pixels become 0, and a segment left with fewer than
    ``min_pixels`` pixels is dropped (0). The remaining labels keep their values."""
    labels = np.asarray(labels)
    mask = np.asarray(target_mask, dtype=bool)
    if labels.shape != mask.shape:
        raise ObservationError(f"segmentation of shape {labels.shape} and target mask of shape {mask.shape} differ")
    out = np.where(mask, 0, labels).astype(np.int32)
    if min_pixels > 1:
        ids, counts = np.unique(out[out > 0], return_counts=True)
        out[np.isin(out, ids[counts < min_pixels])] = 0
    return out


def labelled_frame(depth: np.ndarray, labels: np.ndarray, count: int, camera: Camera) -> "Observation":
    """The frame of a ray-cast whose label image (0 shelf, i + 1 object i of ``count``, ``count`` + 1 the target)
    stands for the segmentation, as the shelf simulator's camera mode makes it with label segmentation: the
    occluders segmented by their labels, the target's pixels its mask."""
    target = np.asarray(labels) == count + 1
    segments = occluder_segmentation(np.where((labels >= 1) & (labels <= count), labels, 0), target)
    return Observation(depth, segments, target, camera, min_valid_fraction=0.0)


def target_mask_from_labels(label_image: np.ndarray, target_label: int) -> np.ndarray:
    """The simulation's stand-in for colour detection: pixels whose render label is the target's."""
    label_image = np.asarray(label_image)
    if not np.issubdtype(label_image.dtype, np.integer):
        raise ObservationError(f"label image must hold integers, got {label_image.dtype}")
    return label_image == int(target_label)


def target_mask_from_color(rgb: np.ndarray, color, tolerance: float = 40.0, min_pixels: int = 0) -> np.ndarray:
    """Pixels of an RGB(A) image (H, W, 3 or 4; uint8 0..255, or float 0..1) whose colour lies within
    ``tolerance`` (Euclidean distance in 0..255 RGB units) of the target's known ``color`` (r, g, b in 0..255).
    When fewer than ``min_pixels`` pixels match, the target counts as unseen (all False): isolated specks of a
    similar colour are not a detection."""
    image = np.asarray(rgb)
    if image.ndim != 3 or image.shape[2] not in (3, 4):
        raise ObservationError(f"colour image must have shape (H, W, 3) or (H, W, 4), got {image.shape}")
    if image.dtype == np.uint8:
        values = image[..., :3].astype(np.float32)
    elif np.issubdtype(image.dtype, np.floating):
        values = image[..., :3].astype(np.float32) * 255.0
    else:
        raise ObservationError(f"colour image must be uint8 (0..255) or float (0..1), got {image.dtype}")
    reference = np.asarray(color, dtype=np.float32).reshape(-1)
    if reference.shape != (3,) or not np.all((reference >= 0) & (reference <= 255)):
        raise ObservationError(f"target colour must be three values r, g, b in 0..255, got {color!r}")
    if not tolerance >= 0:
        raise ObservationError(f"colour tolerance must be non-negative, got {tolerance!r}")
    mask = np.sum((values - reference) ** 2, axis=-1) <= float(tolerance) ** 2
    if np.count_nonzero(mask) < min_pixels:
        mask[:] = False
    return mask


# ------------------------------------------------------------------------------------------------------------


def _shape_problem(name: str, array: np.ndarray, shape: tuple[int, int]) -> None:
    if array.shape != shape:
        raise ObservationError(
            f"{name} of shape {array.shape} does not fit the camera's image shape {shape} (height, width)"
        )


def _checked_depth(depth, shape, camera: Camera, min_valid_fraction: float) -> np.ndarray:
    depth = np.asarray(depth)
    if depth.dtype not in (np.float32, np.float64):
        hint = " (raw sensor units? convert to metres first)" if np.issubdtype(depth.dtype, np.integer) else ""
        raise ObservationError(f"depth image must be float32 (or float64) metres, got {depth.dtype}{hint}")
    _shape_problem("depth image", depth, shape)
    depth = np.where(np.isfinite(depth) & (depth > 0), depth, 0.0).astype(np.float32)
    if not depth.flags.writeable:
        depth = depth.copy()
    fraction = float(np.count_nonzero(depth)) / depth.size
    if fraction < min_valid_fraction:
        raise ObservationError(
            f"depth image has returns on only {100 * fraction:.0f}% of its pixels (at least "
            f"{100 * min_valid_fraction:.0f}% needed): is the camera covered or the frame empty?"
        )
    if np.median(depth[depth > 0]) > camera.far:
        raise ObservationError(
            f"depth image's median {np.median(depth[depth > 0]):.1f} exceeds the camera's far limit {camera.far} m: "
            "is it in millimetres?"
        )
    return depth


def _checked_segmentation(segmentation, shape) -> np.ndarray:
    segmentation = np.asarray(segmentation)
    if not np.issubdtype(segmentation.dtype, np.integer):
        raise ObservationError(f"segmentation must hold integer labels, got {segmentation.dtype}")
    _shape_problem("segmentation", segmentation, shape)
    if segmentation.size and segmentation.min() < 0:
        raise ObservationError("segmentation holds negative labels; 0 means no occluder, 1..K the occluders")
    return segmentation.astype(np.int32)


def _checked_mask(mask, shape) -> np.ndarray:
    mask = np.asarray(mask)
    if mask.dtype != np.bool_:
        raise ObservationError(f"target mask must be boolean, got {mask.dtype}")
    _shape_problem("target mask", mask, shape)
    return mask


def _checked_joint_state(q) -> np.ndarray:
    try:
        q = np.asarray(q, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise ObservationError(f"joint state must be a list of numbers: {exc}") from None
    if q.ndim != 1 or not np.all(np.isfinite(q)):
        raise ObservationError(f"joint state must be a flat list of finite numbers, got shape {q.shape}")
    return q
