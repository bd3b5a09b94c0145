"""``slax-drake dataset``: render scenes and their ground-truth occupancy into HDF5 shards (resumable)."""

from __future__ import annotations

import argparse

from slax_drake import arguments
from slax_drake.config import DEFAULT_CONFIG


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "dataset",
        help="generate a training dataset: depth and label images with occupancy distributions",
        description="Sample scenes (N objects uniform in objects.count_range), render depth and label images "
        "with Drake, compute the 2D and 1D occupancy distributions of the three target ratios and write HDF5 "
        "shards with a manifest. Killed and restarted with the same arguments, it resumes.",
    )
    p.add_argument("--config", default=DEFAULT_CONFIG, help=f"scenario YAML (default: {DEFAULT_CONFIG})")
    p.add_argument("--scenes", type=int, required=True, help="number of scenes")
    p.add_argument("--out", required=True, help="output folder")
    p.add_argument("--workers", type=int, default=1, help="worker processes (default: 1)")
    p.add_argument("--backend", choices=("local", "ray"), default="local",
                   help="local processes or Ray tasks (extra 'cluster') (default: local)")
    p.add_argument("--resolution", default="128x96",
                   help="image size WIDTHxHEIGHT (default: 128x96, the input of the shipped model models/perception/unet128)")
    p.add_argument("--seed", type=arguments.seed, default=0, help="dataset seed (default: 0)")
    p.add_argument("--shard-size", type=int, default=256, help="scenes per shard (default: 256)")
    p.add_argument("--grid-step", type=float, default=0.005,
                   help="occupancy placement grid in metres (default: 0.005)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.set_defaults(func=run)


def parse_resolution(text: str) -> tuple[int, int]:
    from slax_drake.errors import DatasetError

    try:
        w, h = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise DatasetError(f"--resolution {text!r}: expected WIDTHxHEIGHT, for example 128x96") from None
    if not (8 <= w <= 4096 and 8 <= h <= 4096):
        raise DatasetError(f"--resolution {text!r}: width and height must lie in [8, 4096]")
    return w, h


def run(args: argparse.Namespace) -> int:
    from slax_drake.dataset import DatasetSpec, generate
    from slax_drake.dataset.generate import dataset_memory_bytes
    from slax_drake.resources import check_memory
    from slax_drake.errors import DatasetError
    from slax_drake.io import plural

    if args.scenes < 1:
        raise DatasetError(f"--scenes {args.scenes}: must be at least 1")
    if args.workers < 1:
        raise DatasetError(f"--workers {args.workers}: must be at least 1")
    if args.shard_size < 1:
        raise DatasetError(f"--shard-size {args.shard_size}: must be at least 1")
    if not args.grid_step > 0:
        raise DatasetError(f"--grid-step {args.grid_step}: must be positive")
    spec = DatasetSpec(config=args.config, scenes=args.scenes, resolution=parse_resolution(args.resolution),
                       seed=args.seed, shard_size=args.shard_size, grid_step=args.grid_step)
    check_memory(dataset_memory_bytes(spec, args.workers),
                 f"--resolution {args.resolution} with --shard-size {args.shard_size}, --grid-step {args.grid_step:g} "
                 f"and --workers {args.workers}", "use a smaller resolution or shard, a coarser grid or fewer workers")
    manifest = generate(spec, args.out, workers=args.workers, backend=args.backend,
                        progress=not args.no_progress)
    print(f"wrote {args.out}: {plural(manifest['num_scenes'], 'scene')} in {plural(len(manifest['shards']), 'shard')} "
          f"({manifest['elapsed_s']:.1f} s this run)")
    return 0
