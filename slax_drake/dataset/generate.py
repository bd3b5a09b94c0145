"""Dataset generation: random scenes -> Drake depth + label images and ground-truth occupancy -> HDF5 shards.

Scene i of a dataset with seed s is fully determined by (s, i): its object count N (uniform in
``objects.count_range``, [2, 12] for the paper), its target ratio (uniform over ``TARGET_SIZES``) and its scene
seed come from ``numpy.random.SeedSequence([s, i])``. Shard k holds scenes [k * shard_size, (k + 1) *
shard_size), so any shard can be (re)made alone, in any order, by any worker, and a run killed and restarted
with the same arguments produces exactly the data of an uninterrupted run: finished shards are kept, missing
ones are made, a half-written shard only ever exists under a temporary name.
"""

from __future__ import annotations

import dataclasses
import json
import time
from pathlib import Path

import numpy as np

from slax_drake.errors import DatasetError
from slax_drake.dataset.shards import MANIFEST, TARGET_SIZES, Sample, shard_name, write_shard

PARAMS = "dataset_params.json"
DEFAULT_GRID_STEP = 0.005


@dataclasses.dataclass(frozen=True)
class DatasetSpec:
    """Everything that determines a dataset's content."""

    config: str  # scenario YAML path
    scenes: int
    resolution: tuple[int, int]  # (width, height) of the images and of p2d
    seed: int = 0
    shard_size: int = 256
    grid_step: float = DEFAULT_GRID_STEP

    @property
    def num_shards(self) -> int:
        return (self.scenes + self.shard_size - 1) // self.shard_size

    def shard_range(self, k: int) -> range:
        return range(k * self.shard_size, min((k + 1) * self.shard_size, self.scenes))

    def to_dict(self) -> dict:
        d = dataclasses.asdict(self)
        d["resolution"] = list(self.resolution)
        d["config"] = str(self.config)
        return d


def dataset_memory_bytes(spec: DatasetSpec, workers: int) -> float:
    """Estimated bytes of the large arrays while ``workers`` processes each make a shard: a shard's samples
    are held until it is written (depth and label, three p2d in float32 and their converted copies: about 40
    bytes a pixel each), beside one occupancy computation (``occupancy_memory_bytes``) and the renderer's
    images (about 32 bytes a pixel)."""
    from slax_drake.config import load_scenario
    from slax_drake.occupancy.hidden import occupancy_memory_bytes
    from slax_drake.scene.camera import Camera
    from slax_drake.scene.model import Scene
    from slax_drake.scene.sampling import shelf_of

    scenario = load_scenario(spec.config)
    camera = Camera.from_config(scenario.camera).with_resolution(*spec.resolution)
    empty = Scene(shelf=shelf_of(scenario), camera=camera, objects=(), target=None)
    pixels = spec.resolution[0] * spec.resolution[1]
    occupancy = occupancy_memory_bytes(empty, TARGET_SIZES, spec.grid_step, scenario.target.surface_point_spacing)
    per_worker = 40.0 * pixels * min(spec.shard_size, spec.scenes) + occupancy + 32.0 * pixels
    return min(workers, spec.num_shards) * per_worker


def scene_draw(spec_seed: int, index: int, count_range) -> tuple[int, int, int]:
    """(object count, target ratio index, scene seed) of scene ``index``."""
    rng = np.random.default_rng(np.random.SeedSequence([spec_seed, index]))
    n = int(rng.integers(count_range[0], count_range[1] + 1))
    ratio = int(rng.integers(len(TARGET_SIZES)))
    seed = int(rng.integers(2**62))
    return n, ratio, seed


class SampleMaker:
    """Makes samples for one spec; holds the Drake renderer (built once) and the scenario."""

    def __init__(self, spec: DatasetSpec):
        from slax_drake.config import load_scenario
        from slax_drake.scene.camera import Camera
        from slax_drake.station.renderer import SceneRenderer

        self.spec = spec
        self.scenario = load_scenario(spec.config)
        self.camera = Camera.from_config(self.scenario.camera).with_resolution(*spec.resolution)
        self.renderer = SceneRenderer(self.camera)

    def make(self, index: int) -> Sample:
        from slax_drake.occupancy import compute_occupancies
        from slax_drake.scene import sample_scene, scene_to_json
        from slax_drake.scene.raycast import SceneRaycaster

        n, ratio, seed = scene_draw(self.spec.seed, index, self.scenario.objects.count_range)
        scene = sample_scene(self.scenario, n, seed, target_size=TARGET_SIZES[ratio])
        depth, label = self.renderer.render(scene)
        raycaster = SceneRaycaster(scene)
        spacing = self.scenario.target.surface_point_spacing
        occs = compute_occupancies(scene, TARGET_SIZES, self.spec.grid_step, self.camera, spacing, raycaster)
        return Sample(
            depth=depth,
            label=label,
            p2d=np.stack([o.p2d for o in occs]),
            p1d=np.stack([o.p1d for o in occs]),
            num_hidden=np.array([o.num_hidden for o in occs], dtype=np.int32),
            target_ratio=ratio,
            num_objects=n,
            scene_index=index,
            scene_seed=seed,
            scene_json=scene_to_json(scene),
        )


_MAKER: SampleMaker | None = None


def make_shard(spec_dict: dict, out: str, k: int) -> tuple[int, int]:
    """Makes and writes shard ``k`` (a worker's unit of work; a plain function so any backend can run it).
    Returns (k, number of samples)."""
    global _MAKER
    spec = spec_from_dict(spec_dict)
    if _MAKER is None or _MAKER.spec != spec:
        _MAKER = SampleMaker(spec)
    samples = [_MAKER.make(i) for i in spec.shard_range(k)]
    write_shard(Path(out) / shard_name(k), samples)
    return k, len(samples)


def spec_from_dict(d: dict) -> DatasetSpec:
    return DatasetSpec(config=d["config"], scenes=int(d["scenes"]), resolution=tuple(d["resolution"]),
                       seed=int(d["seed"]), shard_size=int(d["shard_size"]), grid_step=float(d["grid_step"]))


def prepare_output(spec: DatasetSpec, out: Path) -> list[int]:
    """Creates or checks the output folder; returns the shards still to make. Stale temporary files of an
    interrupted run are removed; a folder made with other arguments is refused."""
    from slax_drake.io import write_text_atomic

    out.mkdir(parents=True, exist_ok=True)
    params_path = out / PARAMS
    wanted = spec.to_dict()
    if params_path.exists():
        try:
            found = json.loads(params_path.read_text())
        except json.JSONDecodeError:
            raise DatasetError(f"{params_path}: corrupt; remove the folder or choose another --out") from None
        if found != wanted:
            diff = sorted(k for k in wanted if found.get(k) != wanted[k])
            raise DatasetError(f"{out} holds a dataset made with other arguments ({', '.join(diff)} differ); "
                               "use the same arguments to resume or choose another --out")
    else:
        write_text_atomic(params_path, json.dumps(wanted, indent=1) + "\n")
    for tmp in out.glob(".shard_*.tmp"):
        tmp.unlink()
    return [k for k in range(spec.num_shards) if not (out / shard_name(k)).exists()]


def write_manifest(spec: DatasetSpec, out: Path) -> dict:
    import h5py

    from slax_drake import __version__
    from slax_drake.config import load_scenario
    from slax_drake.io import write_text_atomic

    shards, counts = [], np.zeros(len(TARGET_SIZES), dtype=int)
    objects = {}
    for k in range(spec.num_shards):
        path = out / shard_name(k)
        try:
            with h5py.File(path, "r") as f:
                count = int(f.attrs["count"])
                ratios = f["target_ratio"][:]
                n_obj = f["num_objects"][:]
        except (OSError, KeyError) as e:
            raise DatasetError(f"{path}: cannot read shard ({e}); delete it and run again to remake it") from None
        if count != len(spec.shard_range(k)):
            raise DatasetError(f"{path}: holds {count} samples, expected {len(spec.shard_range(k))}")
        counts += np.bincount(ratios, minlength=len(TARGET_SIZES))
        for n in n_obj.tolist():
            objects[str(n)] = objects.get(str(n), 0) + 1
        shards.append({"file": shard_name(k), "count": count, "first_scene": spec.shard_range(k).start})
    scenario_text = Path(load_scenario_path(spec.config)).read_text()
    manifest = {
        "format": "slax-drake occupancy dataset",
        "package_version": __version__,
        "num_scenes": spec.scenes,
        "params": spec.to_dict(),
        "target_sizes": [list(s) for s in TARGET_SIZES],
        "scenes_per_target_ratio": counts.tolist(),
        "scenes_per_object_count": dict(sorted(objects.items(), key=lambda kv: int(kv[0]))),
        "seeds": "scene i: numpy SeedSequence([seed, i]) draws N, target ratio, scene seed",
        "config_yaml": scenario_text,
        "shards": shards,
    }
    load_scenario(spec.config)  # validated again so the manifest never records a broken config
    write_text_atomic(out / MANIFEST, json.dumps(manifest, indent=1) + "\n")
    return manifest


def load_scenario_path(config: str) -> Path:
    from slax_drake.config import REPO_ROOT

    path = Path(config)
    if not path.is_file() and not path.is_absolute() and (REPO_ROOT / path).is_file():
        path = REPO_ROOT / path
    return path


def generate(spec: DatasetSpec, out: str | Path, workers: int = 1, backend: str = "local",
             progress: bool = True) -> dict:
    """Makes every missing shard of ``spec`` in ``out`` and writes the manifest; returns it."""
    from slax_drake.config import load_scenario

    load_scenario(spec.config)  # a bad config fails here, once, with its own message
    out = Path(out)
    todo = prepare_output(spec, out)
    done_scenes = spec.scenes - sum(len(spec.shard_range(k)) for k in todo)
    bar = _progress(spec.scenes, done_scenes, progress)
    t0 = time.perf_counter()
    try:
        _run(spec, out, todo, workers, backend, bar)
    finally:
        bar.close()
    manifest = write_manifest(spec, out)
    manifest["elapsed_s"] = time.perf_counter() - t0
    return manifest


def _progress(total: int, initial: int, enabled: bool):
    from tqdm import tqdm

    return tqdm(total=total, initial=initial, unit="scene", disable=not enabled, smoothing=0.1,
                desc="dataset", dynamic_ncols=True)


def _run(spec: DatasetSpec, out: Path, todo: list[int], workers: int, backend: str, bar) -> None:
    """Makes shards ``todo`` as tasks of ``backend`` (slax_drake.backends); shards are written by the tasks."""
    from slax_drake.backends import run_tasks

    d = spec.to_dict()
    for _, (_, n) in run_tasks(_make_shard_star, [(d, str(out.resolve()), k) for k in todo], workers=workers,
                               backend=backend):
        bar.update(n)


def _make_shard_star(args):
    return make_shard(*args)
