"""In-memory training arrays for the perception network, and how they are filled.

:class:`TrainingData` holds what training and evaluation need: depth images (N, H, W) float32 in metres, the
true 2D distribution of each sample's own target ratio (N, H, W) float32 (sums to one), and the head index of
that ratio (N,). Only the own head's distribution is kept, since only that head is supervised (paper Sec. V-B);
this keeps 5,000 samples at 128x96 under 0.5 GB.

Sources: :func:`load_dataset` reads a dataset folder written by ``slax-drake dataset`` through the dataset
package's own reader (this module is only a thin adapter); :func:`from_scenes` renders scenes with the ray
caster and computes their occupancy directly (small sets for tests and quick experiments).
"""

from __future__ import annotations

import dataclasses
import hashlib
from pathlib import Path

import numpy as np

from slax_drake.errors import PerceptionDataError
from slax_drake.perception.targets import TARGET_SIZES, ratio_index


@dataclasses.dataclass
class TrainingData:
    depth: np.ndarray  # (N, H, W) float32, metres along the optical axis
    p2d_own: np.ndarray  # (N, H, W) float32, each sums to one
    own: np.ndarray  # (N,) int64 head index of the sample's target ratio
    source: str = ""

    def __post_init__(self):
        n = len(self.depth)
        if self.depth.ndim != 3 or self.p2d_own.shape != self.depth.shape or self.own.shape != (n,):
            raise PerceptionDataError(
                f"{self.source or 'data'}: inconsistent shapes depth {self.depth.shape}, "
                f"p2d {self.p2d_own.shape}, own {self.own.shape}"
            )
        if n == 0:
            raise PerceptionDataError(f"{self.source or 'data'}: no samples")

    def __len__(self) -> int:
        return len(self.depth)

    @property
    def resolution(self) -> tuple[int, int]:
        """(width, height) in pixels."""
        return self.depth.shape[2], self.depth.shape[1]

    def subset(self, idx) -> "TrainingData":
        idx = np.asarray(idx)
        return TrainingData(self.depth[idx], self.p2d_own[idx], self.own[idx], f"{self.source}[{len(idx)}]")

    def describe(self) -> dict:
        """Size, resolution, ratio counts and a content fingerprint (so a resume on other data is caught)."""
        digest = hashlib.sha1()
        for a in (self.depth[:: max(1, len(self) // 64)], self.own):
            digest.update(np.ascontiguousarray(a).tobytes())
        w, h = self.resolution
        return {
            "source": self.source,
            "samples": len(self),
            "resolution": f"{w}x{h}",
            "ratio_counts": np.bincount(self.own, minlength=len(TARGET_SIZES)).tolist(),
            "fingerprint": digest.hexdigest()[:16],
        }


def load_dataset(folder: str | Path, limit: int | None = None, progress: bool = False) -> TrainingData:
    """Reads a ``slax-drake dataset`` folder (through ``slax_drake.dataset``'s reader) into memory: each
    sample's depth image and the 2D distribution of its own target ratio. ``limit`` keeps the first samples."""
    from slax_drake.dataset.shards import TARGET_SIZES as DATASET_SIZES
    from slax_drake.dataset.shards import DatasetReader

    folder = Path(folder)
    if not folder.is_dir():
        raise PerceptionDataError(f"{folder}: no such dataset folder (make one with `slax-drake dataset`)")
    if [tuple(s) for s in DATASET_SIZES] != [tuple(s) for s in TARGET_SIZES]:
        raise PerceptionDataError(f"{folder}: dataset target ratios {DATASET_SIZES} differ from the heads {TARGET_SIZES}")
    reader = DatasetReader(folder)
    n = len(reader) if limit is None else min(limit, len(reader))
    if n == 0:
        raise PerceptionDataError(f"{folder}: the dataset holds no samples")
    first = reader[0]
    h, w = first["depth"].shape[-2:]
    depth = np.empty((n, h, w), np.float32)
    p2d = np.empty((n, h, w), np.float32)
    own = np.empty(n, np.int64)
    from tqdm import tqdm

    try:
        for i in tqdm(range(n), desc=f"reading {folder.name}", unit="sample", disable=not progress, leave=False):
            sample = reader[i]
            r = int(sample["target_ratio"])
            depth[i] = sample["depth"][0]
            p2d[i] = sample["p2d"][r]
            own[i] = r
    finally:
        reader.close()
    return TrainingData(depth, p2d, own, str(folder))


def from_scenes(scenes, resolution: tuple[int, int], grid_step: float = 0.005) -> TrainingData:
    """Renders each scene's depth image at ``resolution`` (width, height) with the ray caster and computes the
    occupancy of its own target size (the ground truth of ``slax_drake.occupancy``)."""
    from slax_drake.occupancy import compute_occupancy
    from slax_drake.scene.raycast import SceneRaycaster

    depths, p2ds, owns = [], [], []
    for scene in scenes:
        camera = scene.camera.with_resolution(*resolution)
        raycaster = SceneRaycaster(scene)
        depth, _ = raycaster.render(camera)
        occ = compute_occupancy(scene, scene.target.size, grid_step, camera=camera, raycaster=raycaster)
        depths.append(depth.astype(np.float32))
        p2ds.append(occ.p2d.astype(np.float32))
        owns.append(ratio_index(scene.target.size))
    return TrainingData(np.stack(depths), np.stack(p2ds), np.asarray(owns, dtype=np.int64), "scenes")
