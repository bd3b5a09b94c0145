"""``slax-drake train`` and ``slax-drake evaluate-perception``: the occupancy network's training and held-out
evaluation."""

from __future__ import annotations

import argparse
import json
import sys

from slax_drake.io import plural


def register(subparsers) -> None:
    from slax_drake import arguments
    from slax_drake.perception.shipped_model import DEFAULT_MODEL

    p = subparsers.add_parser(
        "train",
        help="train the occupancy network on a dataset folder",
        description="Train the depth-image -> occupancy-distribution network (three heads, one per target ratio; "
        "the loss only on each sample's own ratio) with a seeded validation split. Writes model.pt (the best "
        "epoch), checkpoint.pt, metrics.json and learning_curve.png into --out.",
    )
    p.add_argument("--data", required=True, help="dataset folder written by `slax-drake dataset`")
    p.add_argument("--out", required=True, help="output folder, e.g. models/perception/NAME")
    p.add_argument("--epochs", type=int, default=20, help="epochs (default: 20)")
    p.add_argument("--device", default="auto", choices=["auto", "cpu", "cuda"], help="default: auto")
    p.add_argument("--seed", type=arguments.seed, default=0, help="seed of the split, initialisation and shuffles (default: 0)")
    p.add_argument("--batch-size", type=int, default=16, help="default: 16")
    p.add_argument("--lr", type=arguments.positive_float, default=3e-3, help="peak learning rate of the one-cycle schedule (default: 3e-3)")
    p.add_argument("--channels", type=int, default=16, help="channels of the first U-Net level (default: 16)")
    p.add_argument("--levels", type=int, default=4, help="U-Net levels; image sides must divide by 2^levels (default: 4)")
    p.add_argument("--val-fraction", type=arguments.positive_float, default=0.1, help="validation share of the samples (default: 0.1)")
    p.add_argument("--limit", type=int, help="use only the first N samples of the dataset")
    p.add_argument("--threads", type=int, help="torch CPU threads (default: torch's choice)")
    p.add_argument("--resume", action="store_true", help="continue from --out/checkpoint.pt (same options and data)")
    p.add_argument("--no-progress", action="store_true", help="no progress bars")
    p.set_defaults(func=run_train)

    e = subparsers.add_parser(
        "evaluate-perception",
        help="held-out metrics of a trained occupancy network and a PNG of examples",
        description="Evaluate a trained network on a dataset folder: KL divergence (2D, 1D), 1D support IoU, "
        "X-RAY's 2D balanced accuracy and IoU at the model's stored thresholds; write a PNG grid of depth "
        "images, true and predicted distributions.",
    )
    e.add_argument("--data", required=True, help="dataset folder written by `slax-drake dataset`")
    e.add_argument("--model", default=DEFAULT_MODEL, help=f"weight file or its folder (default: {DEFAULT_MODEL})")
    e.add_argument("--png", default="perception_eval.png", help="example grid to write (default: perception_eval.png)")
    e.add_argument("--examples", type=int, default=6, help="rows of the example grid (default: 6)")
    e.add_argument("--limit", type=int, help="evaluate only the first N samples")
    e.add_argument("--segmentation", action="store_true",
                   help="also measure the depth-only instance segmentation against the label images (mean IoU)")
    e.add_argument("--json", help="also write the metrics as JSON to this file")
    e.add_argument("--threads", type=int, help="torch CPU threads (default: torch's choice)")
    e.set_defaults(func=run_evaluate)


def _positive(value, name: str) -> None:
    from slax_drake.errors import UserError

    if value is not None and not value > 0:
        raise UserError(f"{name} must be positive, got {value}")


def _check_training_memory(args: argparse.Namespace) -> None:
    """Refuses options whose arrays would not fit in memory, before the dataset is read. A folder without a
    readable manifest is left to the dataset reader's own message."""
    from slax_drake.dataset.shards import read_manifest
    from slax_drake.errors import UserError
    from slax_drake.perception.training import training_memory_bytes
    from slax_drake.resources import check_memory

    try:
        manifest = read_manifest(args.data)
        samples = int(manifest["num_scenes"])
        w, h = (int(v) for v in manifest["params"]["resolution"])
    except (UserError, KeyError, TypeError, ValueError):
        return
    if args.limit is not None:
        samples = min(samples, args.limit)
    check_memory(training_memory_bytes(samples, (w, h), args.batch_size, args.channels, args.levels),
                 f"training on {samples} samples at {w}x{h} with --batch-size {args.batch_size}, --channels "
                 f"{args.channels} and --levels {args.levels}", "use a smaller batch, fewer channels or --limit")


def run_train(args: argparse.Namespace) -> int:
    from slax_drake.perception.data import load_dataset
    from slax_drake.perception.training import TrainOptions, train

    for name in ("epochs", "batch_size", "lr", "channels", "levels", "limit", "threads"):
        _positive(getattr(args, name), "--" + name.replace("_", "-"))
    if not 0 < args.val_fraction < 1:
        from slax_drake.errors import UserError

        raise UserError(f"--val-fraction must lie in (0, 1), got {args.val_fraction}")
    _check_training_memory(args)
    data = load_dataset(args.data, limit=args.limit, progress=not args.no_progress)
    w, h = data.resolution
    print(f"{plural(len(data), 'sample')} at {w}x{h} from {args.data}", flush=True)
    options = TrainOptions(
        epochs=args.epochs, batch_size=args.batch_size, learning_rate=args.lr, val_fraction=args.val_fraction,
        seed=args.seed, device=args.device, num_threads=args.threads, base_channels=args.channels, levels=args.levels,
    )
    result = train(data, args.out, options, resume=args.resume, progress=not args.no_progress and sys.stderr.isatty(),
                   log=lambda line: print(line, flush=True))
    best = result["best"]
    v = best["val"]
    print(
        f"best epoch {best['epoch']}: validation KL {v['kl_2d']:.3f}, 1D IoU {v['iou_1d']:.3f}, 2D IoU "
        f"{v['iou_2d']:.3f}, balanced accuracy {v['balanced_accuracy_2d']:.3f}; wrote {args.out}/model.pt"
    )
    return 0


def run_evaluate(args: argparse.Namespace) -> int:
    from slax_drake.perception.data import load_dataset
    from slax_drake.perception.evaluation import evaluate_model, save_example_grid, segmentation_mean_iou
    from slax_drake.perception.weights import load_weights
    from slax_drake.io import write_text_atomic

    _positive(args.limit, "--limit")
    _positive(args.examples, "--examples")
    model = load_weights(args.model)
    bars = sys.stderr.isatty()  # progress bars on a terminal only
    data = load_dataset(args.data, limit=args.limit, progress=bars)
    metrics, predictions = evaluate_model(model, data, num_threads=args.threads, progress=bars)
    print(f"model {model.path} on {plural(len(data), 'sample')} of {args.data} ({data.resolution[0]}x{data.resolution[1]}):")
    print(f"  KL divergence 2D        {metrics['kl_2d']:.4f} nats")
    print(f"  KL divergence 1D        {metrics['kl_1d']:.4f} nats")
    print(f"  1D support IoU          {metrics['iou_1d']:.4f}  (threshold {metrics['support_threshold_1d']:g} x uniform)")
    print(f"  2D IoU                  {metrics['iou_2d']:.4f}  (threshold {metrics['support_threshold_2d']:g} x uniform)")
    print(f"  2D balanced accuracy    {metrics['balanced_accuracy_2d']:.4f}")
    result = {"model": str(model.path), "data": str(args.data), "metrics": metrics}
    if args.segmentation:
        seg = segmentation_mean_iou(args.data, limit=args.limit)
        result["segmentation"] = seg
        print(f"  segmentation mean IoU   {seg['mean_iou_all_objects']:.4f} (all visible objects), "
              f"{seg['mean_iou_objects_min_pixels']:.4f} (objects of >= {seg['min_pixels']} px), {seg['images']} images")
    save_example_grid(data, predictions, model, args.png, count=args.examples)
    print(f"wrote {args.png}")
    if args.json:
        from pathlib import Path

        write_text_atomic(Path(args.json), json.dumps(result, indent=2) + "\n")
        print(f"wrote {args.json}")
    return 0
