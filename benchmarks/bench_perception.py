"""Perception figures: inference latency per depth image on one core (batch 1), inference throughput for a
batch of 32, training images per second on the CPU (all of torch's threads and one), and on a GPU when torch
sees one. Uses the shipped model (or --model); timings on a shared machine are noisy, so medians are printed.

    python benchmarks/bench_perception.py [--model PATH] [--repeats 50] [--train-steps 20]

With ``--policy-gap N`` it instead runs Bluction-DAR on the Table I protocol's first N scenes per density with
ground-truth and with learned distributions (the learned model plugged into the policies' registry exactly as
the one-line hook in ``make_distribution_model`` would), and prints both success rates:

    python benchmarks/bench_perception.py --policy-gap 10 --out results/perception_gap [--workers 1]
"""

import argparse
import json
import statistics
import time

import numpy as np
import torch

from slax_drake.perception.inference import OccupancyPredictor
from slax_drake.perception.loss import masked_kl_loss, own_head_mask
from slax_drake.perception.network import OccupancyUNet
from slax_drake.perception.weights import DEFAULT_MODEL, load_weights


def median_ms(fn, repeats: int) -> float:
    fn()  # warm-up
    times = []
    for _ in range(repeats):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return 1000 * statistics.median(times)


def train_images_per_second(config, device: torch.device, threads: int | None, steps: int, batch: int = 16) -> float:
    if threads:
        torch.set_num_threads(threads)
    torch.manual_seed(0)
    net = OccupancyUNet(config).to(device).train()
    opt = torch.optim.AdamW(net.parameters(), lr=1e-3)
    depth = (torch.rand(batch, config.height, config.width) + 0.5).to(device)
    p = torch.rand(batch, config.num_heads, config.height, config.width, device=device)
    p = p / p.sum((-1, -2), keepdim=True)
    mask = own_head_mask(torch.arange(batch, device=device) % config.num_heads, config.num_heads)

    def step():
        loss = masked_kl_loss(net(depth), p, mask)
        opt.zero_grad()
        loss.backward()
        opt.step()

    step()
    if device.type == "cuda":
        torch.cuda.synchronize()
    t = time.perf_counter()
    for _ in range(steps):
        step()
    if device.type == "cuda":
        torch.cuda.synchronize()
    return steps * batch / (time.perf_counter() - t)


def policy_gap(model_path: str, scenes: int, out: str, config: str = "sim_configs/table1.yaml") -> None:
    from pathlib import Path

    import slax_drake.policies.registry as registry
    from slax_drake.config import load_scenario
    from slax_drake.perception.distribution_model import LearnedDistribution
    from slax_drake.evaluation.table1 import run_benchmark

    ground_truth = registry.make_distribution_model

    def with_learned(perception, target_size):
        if perception == "learned":
            return LearnedDistribution(target_size, model=model_path)
        return ground_truth(perception, target_size)

    registry.make_distribution_model = with_learned
    scenario = load_scenario(config)
    rows = {}
    for perception in ("ground-truth", "learned"):
        t = time.perf_counter()
        table = run_benchmark(scenario, ["bluction-dar"], scenes, scenario.protocol.seed, Path(out) / perception,
                              workers=1, perception=perception, progress=False)
        rows[perception] = table["policies"]["bluction-dar"]
        print(f"{perception:>12}: " + ", ".join(
            f"{k}: {100 * (v['success_rate'] or 0):.0f}%"
            for k, v in rows[perception].items()) + f"  ({time.perf_counter() - t:.0f} s)", flush=True)
    # Per-trial comparison on the same scenes.
    trials = {p: {(t["density"], t["seed"]): t["success"] for t in
                  json.loads((Path(out) / p / "table1.json").read_text())["trials"]} for p in rows}
    both = trials["ground-truth"].keys() & trials["learned"].keys()
    lost = sum(trials["ground-truth"][k] and not trials["learned"][k] for k in both)
    gained = sum(trials["learned"][k] and not trials["ground-truth"][k] for k in both)
    print(f"same scenes: {len(both)}; solved with ground truth only: {lost}; with learned only: {gained}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--model", default=DEFAULT_MODEL)
    parser.add_argument("--repeats", type=int, default=50)
    parser.add_argument("--train-steps", type=int, default=20)
    parser.add_argument("--policy-gap", type=int, metavar="N", help="Bluction-DAR success, ground truth vs learned")
    parser.add_argument("--out", default="results/perception_gap", help="trial folder for --policy-gap")
    args = parser.parse_args()
    if args.policy_gap:
        policy_gap(args.model, args.policy_gap, args.out)
        return
    model = load_weights(args.model)
    cfg = model.config
    params = sum(p.numel() for p in model.network.parameters())
    print(f"model {model.path}: {cfg.width}x{cfg.height}, base {cfg.base_channels} channels, {cfg.levels} levels, "
          f"{params:,} parameters; torch {torch.__version__}, {torch.get_num_threads()} threads available")
    rng = np.random.default_rng(0)
    depth = (0.5 + rng.random((32, cfg.height, cfg.width))).astype(np.float32)
    one_core = OccupancyPredictor(model, num_threads=1)
    ms1 = median_ms(lambda: one_core.predict(depth[0]), args.repeats)
    print(f"inference, 1 image, 1 thread:    {ms1:7.2f} ms/image (median of {args.repeats})")
    ms32 = median_ms(lambda: one_core.predict(depth), max(3, args.repeats // 10)) / 32
    print(f"inference, batch 32, 1 thread:   {ms32:7.2f} ms/image")
    threads = torch.get_num_threads()
    all_cores = OccupancyPredictor(model, num_threads=threads)
    msall = median_ms(lambda: all_cores.predict(depth), max(3, args.repeats // 10)) / 32
    print(f"inference, batch 32, {threads} threads:  {msall:7.2f} ms/image")
    for t in sorted({1, threads}):
        ips = train_images_per_second(cfg, torch.device("cpu"), t, args.train_steps)
        print(f"training, CPU, {t} thread(s), batch 16: {ips:7.1f} images/s")
    if torch.cuda.is_available():
        gpu = OccupancyPredictor(model, num_threads=1, device="cuda")
        ms_gpu1 = median_ms(lambda: gpu.predict(depth[0]), args.repeats)
        ms_gpu32 = median_ms(lambda: gpu.predict(depth), args.repeats) / 32
        print(f"inference, GPU ({torch.cuda.get_device_name()}), 1 image: {ms_gpu1:7.2f} ms/image; "
              f"batch 32: {ms_gpu32:7.3f} ms/image (with host copies)")
        ips = train_images_per_second(cfg, torch.device("cuda"), None, args.train_steps * 5)
        print(f"training, GPU ({torch.cuda.get_device_name()}), batch 16: {ips:7.1f} images/s")
    else:
        print("training, GPU: not measured (torch sees no CUDA device)")


if __name__ == "__main__":
    main()
