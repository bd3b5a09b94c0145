"""Perception network, loss, metrics, weight files, inference and training (tiny networks and images)."""

import json

import numpy as np
import pytest
import torch

from slax_drake.perception.data import TrainingData, from_scenes
from slax_drake.errors import ImageSizeError, WeightFileError
from slax_drake.perception.inference import OccupancyPredictor, truncate_support
from slax_drake.perception.loss import kl_per_head, masked_kl_loss, own_head_mask
from slax_drake.perception.metrics import MetricsAccumulator
from slax_drake.perception.network import NetworkConfig, OccupancyUNet, distributions_2d
from slax_drake.perception.targets import TARGET_SIZES, ratio_index
from slax_drake.perception.training import TrainOptions, full_targets, seed_everything, train
from slax_drake.perception.weights import load_weights, make_header, save_weights
from slax_drake.scene import sample_scene

TINY = NetworkConfig(width=32, height=24, base_channels=4, levels=3)


def tiny_network(seed=0, config=TINY):
    torch.manual_seed(seed)
    return OccupancyUNet(config).eval()


@pytest.fixture(scope="module")
def tiny_data(sim_scenario):
    """Eight real samples at 32x24: scenes with 3..10 objects, the three target ratios in turn."""
    scenes = [sample_scene(sim_scenario, 3 + i, i, target_size=TARGET_SIZES[i % 3]) for i in range(8)]
    return from_scenes(scenes, (32, 24))


def test_network_shapes_and_normalised_distributions():
    net = tiny_network()
    depth = torch.rand(5, 24, 32) + 0.5
    depth[0, 3, 4] = float("nan")  # invalid returns are allowed
    depth[1, 5, 6] = 0.0
    logits = net(depth)
    assert logits.shape == (5, 3, 24, 32)
    assert torch.isfinite(logits).all()
    p = distributions_2d(logits)
    assert torch.allclose(p.sum((-1, -2)), torch.ones(5, 3), atol=1e-5)
    assert (p > 0).all()


def test_network_rejects_wrong_image_size():
    net = tiny_network()
    with pytest.raises(ImageSizeError, match=r"takes \(batch, 24, 32\), i.e. 32x24 pixels"):
        net(torch.ones(2, 32, 24))
    with pytest.raises(ImageSizeError, match="divisible by 8"):
        NetworkConfig(width=30, height=24, levels=3)


def test_ratio_index_selects_heads():
    assert [ratio_index(s) for s in TARGET_SIZES] == [0, 1, 2]
    assert ratio_index([0.0601, 0.06, 0.1199]) == 2
    with pytest.raises(Exception, match="has no network head"):
        ratio_index((0.1, 0.1, 0.1))


def test_kl_is_zero_for_the_truth_and_positive_otherwise():
    p = torch.rand(2, 3, 6, 8) ** 4
    p[0, 1, :3] = 0.0  # zeros in the true distribution are fine
    p = p / p.sum((-1, -2), keepdim=True)
    exact = torch.log(p.clamp_min(1e-30))
    assert torch.allclose(kl_per_head(exact, p), torch.zeros(2, 3), atol=1e-5)
    assert (kl_per_head(torch.zeros_like(p), p) > 0.01).all()


def test_loss_is_masked_to_the_own_head():
    torch.manual_seed(1)
    logits = torch.randn(4, 3, 6, 8, requires_grad=True)
    p = torch.rand(4, 3, 6, 8)
    p = p / p.sum((-1, -2), keepdim=True)
    own = torch.tensor([0, 2, 1, 2])
    mask = own_head_mask(own, 3)
    assert mask.tolist() == [[True, False, False], [False, False, True], [False, True, False], [False, False, True]]
    loss = masked_kl_loss(logits, p, mask)
    expected = kl_per_head(logits, p)[torch.arange(4), own].mean()
    assert torch.allclose(loss, expected)
    loss.backward()
    grad_norm = logits.grad.flatten(-2).abs().sum(-1)
    assert (grad_norm[~mask] == 0).all()
    assert (grad_norm[mask] > 0).all()
    # Changing an unsupervised head's target does not change the loss.
    p2 = p.clone()
    p2[0, 1] = torch.flip(p2[0, 1], dims=[0])
    assert torch.equal(masked_kl_loss(logits, p2, mask), loss)


def test_full_targets_puts_the_own_distribution_on_its_head():
    p = torch.rand(3, 4, 5)
    own = torch.tensor([2, 0, 1])
    full = full_targets(p, own, 3)
    for i, r in enumerate(own.tolist()):
        assert torch.equal(full[i, r], p[i])
        assert full[i].sum() == p[i].sum()


def test_metrics_of_a_perfect_and_of_a_uniform_prediction():
    h, w = 6, 8
    p = torch.zeros(2, h, w)
    p[0, 4:, 2:5] = 1.0
    p[1, 3:, 5:] = 1.0
    p = p / p.sum((-1, -2), keepdim=True)
    perfect = torch.full((2, 3, h, w), -30.0)
    perfect[:, 1] = torch.log(p.clamp_min(1e-30))
    acc = MetricsAccumulator()
    acc.add(perfect, p, torch.tensor([1, 1]))
    s = acc.summary(*acc.best_thresholds())
    assert s["iou_1d"] == pytest.approx(1.0)
    assert s["iou_2d"] == pytest.approx(1.0)
    assert s["balanced_accuracy_2d"] == pytest.approx(1.0)
    assert s["kl_2d"] == pytest.approx(0.0, abs=1e-6)
    uniform = MetricsAccumulator()
    uniform.add(torch.zeros(2, 3, h, w), p, torch.tensor([0, 2]))
    u = uniform.summary(0.01, 0.01)  # everything predicted: IoU = |true support| / all
    assert u["iou_1d"] == pytest.approx((3 / 8 + 3 / 8) / 2)
    assert u["balanced_accuracy_2d"] == pytest.approx(0.5)
    assert u["kl_2d"] > 0.5


def test_truncate_support_keeps_normalised_distributions():
    rng = np.random.default_rng(0)
    p = rng.random((3, 6, 8)) ** 6
    p /= p.sum((1, 2), keepdims=True)
    q2, q1 = truncate_support(p, 1.0, 1.0)
    assert np.allclose(q2.sum((1, 2)), 1) and np.allclose(q1.sum(1), 1)
    assert ((q2 == 0) == (p < 1.0 / 48)).all()
    raw1 = p.sum(1)
    assert ((q1 == 0) == (raw1 < 1.0 / 8)).all()
    # Nothing above a huge threshold: the largest entry is kept.
    q2, q1 = truncate_support(p, 1e6, 1e6)
    assert ((q2 > 0).sum((1, 2)) == 1).all() and ((q1 > 0).sum(1) == 1).all()


def test_save_load_round_trip_and_predictor(tmp_path):
    net = tiny_network(3)
    header = make_header(TINY, support_threshold_1d=0.5, support_threshold_2d=0.2, note="round trip")
    path = tmp_path / "m.pt"
    save_weights(path, net, header)
    loaded = load_weights(path)
    assert loaded.header == header
    assert loaded.config == TINY
    depth = (torch.rand(3, 24, 32) + 0.5).numpy()
    with torch.no_grad():
        expected = distributions_2d(net(torch.from_numpy(depth)))
    predictor = OccupancyPredictor(loaded)
    for size, head in zip(TARGET_SIZES, range(3)):
        out = predictor.predict(depth, size)
        assert out.p2d.shape == (3, 24, 32) and out.p1d.shape == (3, 32)
        assert np.allclose(out.raw_p2d, expected[:, head].numpy(), atol=1e-6)
        assert np.allclose(out.p2d.sum((1, 2)), 1, atol=1e-5) and np.allclose(out.p1d.sum(1), 1, atol=1e-5)
        assert ((out.p1d == 0) == (out.raw_p2d.sum(1) < 0.5 / 32)).all()
    single = predictor.predict(depth[1], head=2)
    assert single.p2d.shape == (1, 24, 32)
    assert np.allclose(single.raw_p2d[0], expected[1, 2].numpy(), atol=1e-6)
    with pytest.raises(ImageSizeError, match=r"takes 32x24 images, i.e. shape \(24, 32\)"):
        predictor.predict(np.ones((48, 64), np.float32))


def test_bad_weight_files_fail_with_one_clear_line(tmp_path):
    good = tmp_path / "good.pt"
    save_weights(good, tiny_network(), make_header(TINY))
    with pytest.raises(WeightFileError, match="no such weight file"):
        load_weights(tmp_path / "missing.pt")
    truncated = tmp_path / "truncated.pt"
    truncated.write_bytes(good.read_bytes()[: good.stat().st_size // 2])
    with pytest.raises(WeightFileError, match="truncated or corrupt"):
        load_weights(truncated)
    garbage = tmp_path / "garbage.pt"
    garbage.write_text("not a model")
    with pytest.raises(WeightFileError, match="truncated or corrupt"):
        load_weights(garbage)
    no_header = tmp_path / "bare.pt"
    torch.save(tiny_network().state_dict(), no_header)
    with pytest.raises(WeightFileError, match="no header/state_dict"):
        load_weights(no_header)
    for change, message in [
        ({"version": 99}, "weight file version 99, this code reads 1"),
        ({"format": "other"}, "format 'other'"),
        ({"architecture": "ResNet"}, "architecture 'ResNet'"),
    ]:
        bad = tmp_path / "bad.pt"
        save_weights(bad, tiny_network(), {**make_header(TINY), **change})
        with pytest.raises(WeightFileError, match=message):
            load_weights(bad)
    # The header describes another network than the weights hold.
    other = tmp_path / "mismatch.pt"
    bigger = NetworkConfig(width=32, height=24, base_channels=8, levels=3)
    save_weights(other, tiny_network(), make_header(bigger))
    with pytest.raises(WeightFileError, match="weights do not match the header's network"):
        load_weights(other)
    with pytest.raises(WeightFileError, match="model takes 32x24 depth images, but 64x48 images are given"):
        load_weights(good, expected_resolution=(64, 48))
    with pytest.raises(WeightFileError) as info:
        load_weights(truncated)
    assert "\n" not in str(info.value) and str(truncated) in str(info.value)


@pytest.mark.slow  # several seconds; runs in CI's slow step
def test_tiny_network_overfits_eight_samples(tiny_data):
    seed_everything(0)
    torch.set_num_threads(1)
    net = OccupancyUNet(NetworkConfig(width=32, height=24, base_channels=8, levels=3))
    optimizer = torch.optim.Adam(net.parameters(), lr=1e-2)
    depth = torch.from_numpy(tiny_data.depth)
    own = torch.from_numpy(tiny_data.own)
    target = full_targets(torch.from_numpy(tiny_data.p2d_own), own, 3)
    mask = own_head_mask(own, 3)
    losses = []
    for _ in range(300):
        loss = masked_kl_loss(net(depth), target, mask)
        optimizer.zero_grad()
        loss.backward()
        optimizer.step()
        losses.append(float(loss.detach()))
    net.eval()
    with torch.no_grad():
        final = float(masked_kl_loss(net(depth), target, mask))
    assert losses[0] > 2.0
    assert final < 0.1 and final < 0.05 * losses[0], (losses[0], final)


def test_training_is_deterministic_resumable_and_writes_its_outputs(tiny_data, tmp_path):
    options = TrainOptions(epochs=2, batch_size=4, base_channels=4, levels=3, num_threads=1, val_fraction=0.25)
    a = train(tiny_data, tmp_path / "a", options, progress=False, log=lambda *_: None)

    def interrupt(line):  # Ctrl-C after the first epoch's checkpoint
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        train(tiny_data, tmp_path / "b", options, progress=False, log=interrupt)
    assert len(json.loads((tmp_path / "b" / "metrics.json").read_text())["history"]) == 1
    b = train(tiny_data, tmp_path / "b", options, resume=True, progress=False, log=lambda *_: None)
    assert [r["train_loss"] for r in a["history"]] == [r["train_loss"] for r in b["history"]]
    wa, wb = (torch.load(tmp_path / x / "checkpoint.pt", weights_only=True)["network"] for x in "ab")
    assert all(torch.equal(wa[k], wb[k]) for k in wa)
    for name in ("model.pt", "checkpoint.pt", "metrics.json", "learning_curve.png"):
        assert (tmp_path / "a" / name).stat().st_size > 0
    metrics = json.loads((tmp_path / "a" / "metrics.json").read_text())
    assert len(metrics["history"]) == 2 and metrics["data"]["samples"] == 8
    model = load_weights(tmp_path / "a")
    assert model.header["training"]["train_samples"] == 6 and model.header["training"]["val_samples"] == 2
    assert model.support_threshold_1d == model.header["metrics"]["validation"]["support_threshold_1d"]
    # Resuming with other hyper-parameters is refused.
    with pytest.raises(WeightFileError, match="trained with other options"):
        train(tiny_data, tmp_path / "a", TrainOptions(**{**options.__dict__, "learning_rate": 1.0}), resume=True,
              progress=False, log=lambda *_: None)


def test_training_data_checks_shapes():
    with pytest.raises(Exception, match="inconsistent shapes"):
        TrainingData(np.zeros((2, 4, 4), np.float32), np.zeros((2, 4, 5), np.float32), np.zeros(2, np.int64))


@pytest.mark.parametrize("tensor, value", [("encoders.0.0.weight", float("nan")), ("stem.1.running_var", float("inf"))])
def test_non_finite_weights_are_refused(tmp_path, capsys, tensor, value):
    """A weight file holding a NaN (a diverged training) would evaluate to KL = nan with exit code 0."""
    from slax_drake.cli import main

    net = tiny_network()
    with torch.no_grad():
        net.state_dict()[tensor].view(-1)[0] = value
    path = tmp_path / "nan.pt"
    save_weights(path, net, make_header(TINY))
    count = net.state_dict()[tensor].numel()
    message = (f"{path}: tensor '{tensor}' holds 1 non-finite values (NaN or inf) of {count}: the weights are "
               "unusable (did the training diverge?)")
    with pytest.raises(WeightFileError) as info:
        load_weights(path)
    assert str(info.value) == message
    assert main(["evaluate-perception", "--data", str(tmp_path / "data"), "--model", str(path),
                 "--png", str(tmp_path / "grid.png")]) == 2
    assert capsys.readouterr().err == f"slax-drake evaluate-perception: error: {message}\n"
    assert not (tmp_path / "grid.png").exists()


def test_non_finite_threshold_in_the_header_is_refused(tmp_path):
    path = tmp_path / "t.pt"
    save_weights(path, tiny_network(), make_header(TINY, support_threshold_2d=float("nan")))
    with pytest.raises(WeightFileError, match="header 'support_threshold_2d' = nan must be a finite number >= 0"):
        load_weights(path)
