"""`slax-drake train` and `slax-drake evaluate-perception` end to end on a tiny dataset (24 scenes at 32x24)."""

import json

import pytest

from slax_drake.cli import main


@pytest.fixture(scope="module")
def tiny_dataset(tmp_path_factory):
    from slax_drake.dataset.generate import DatasetSpec, generate

    out = tmp_path_factory.mktemp("data") / "tiny"
    generate(DatasetSpec(config="sim_configs/sim_shelf.yaml", scenes=24, resolution=(32, 24), seed=3, shard_size=12),
             out, workers=1, progress=False)
    return out


@pytest.mark.slow  # several seconds; runs in CI's slow step
def test_train_then_evaluate_writes_models_metrics_and_pictures(tiny_dataset, tmp_path, capsys):
    out = tmp_path / "model"
    args = ["train", "--data", str(tiny_dataset), "--out", str(out), "--epochs", "2", "--channels", "4", "--levels", "3",
            "--batch-size", "8", "--threads", "1", "--val-fraction", "0.25", "--no-progress"]
    assert main(args) == 0
    text = capsys.readouterr().out
    assert "24 samples at 32x24" in text and "best epoch" in text
    metrics = json.loads((out / "metrics.json").read_text())
    assert [r["epoch"] for r in metrics["history"]] == [1, 2]
    # Evaluating the saved model on the whole tiny set runs and writes its outputs.
    png, js = tmp_path / "grid.png", tmp_path / "m.json"
    assert main(["evaluate-perception", "--data", str(tiny_dataset), "--model", str(out), "--png", str(png),
                 "--json", str(js), "--examples", "3", "--segmentation"]) == 0
    result = json.loads(js.read_text())
    assert result["metrics"]["samples"] == 24 and 0 <= result["metrics"]["iou_1d"] <= 1
    assert result["segmentation"]["images"] == 24
    assert png.stat().st_size > 1000


def test_cli_errors_are_one_line_with_exit_code_2(tiny_dataset, tmp_path, capsys):
    assert main(["train", "--data", str(tmp_path / "nope"), "--out", str(tmp_path / "m")]) == 2
    assert "no such dataset folder" in capsys.readouterr().err
    assert main(["train", "--data", str(tiny_dataset), "--out", str(tmp_path / "m"), "--epochs", "0"]) == 2
    assert "--epochs must be positive" in capsys.readouterr().err
    bad = tmp_path / "bad.pt"
    bad.write_bytes(b"\x00" * 100)
    assert main(["evaluate-perception", "--data", str(tiny_dataset), "--model", str(bad)]) == 2
    err = capsys.readouterr().err
    assert "truncated or corrupt" in err and err.count("\n") == 1


def test_dataset_default_resolution_is_the_shipped_models_input():
    from slax_drake.cli import build_parser
    from slax_drake.dataset.commands import parse_resolution
    from slax_drake.perception.weights import load_weights

    args = build_parser().parse_args(["dataset", "--scenes", "1", "--out", "unused"])
    config = load_weights().config
    assert parse_resolution(args.resolution) == (config.width, config.height) == (128, 96)


def test_a_dataset_of_another_size_is_refused_with_the_resolution_to_use(tiny_dataset, capsys):
    assert main(["evaluate-perception", "--data", str(tiny_dataset)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "32x24 images, but model " in err
    assert err.endswith("unet128/model.pt takes 128x96 (make the dataset with --resolution 128x96)\n")


@pytest.mark.slow
def test_default_dataset_evaluates_with_the_default_model(tmp_path, capsys):
    """The issue's probe: `dataset` and `evaluate-perception` with their defaults work together."""
    data = tmp_path / "data"
    assert main(["dataset", "--scenes", "4", "--out", str(data), "--no-progress"]) == 0
    assert main(["evaluate-perception", "--data", str(data), "--png", str(tmp_path / "grid.png"), "--examples", "2"]) == 0
    assert "on 4 samples" in capsys.readouterr().out
