"""``train`` refuses what would silently destroy or poison a model: an output folder holding a model trained with
other options (without --resume), and a learning rate that is not a finite positive number."""

from __future__ import annotations

import json

import pytest

from slax_drake.cli import main
from slax_drake.errors import WeightFileError
from slax_drake.perception.data import from_scenes
from slax_drake.perception.training import TrainOptions, train
from slax_drake.scene.sampling import sample_scene

TARGET = (0.06, 0.06, 0.06)
OPTIONS = TrainOptions(epochs=1, batch_size=4, base_channels=4, levels=3, num_threads=1, val_fraction=0.25)


@pytest.fixture(scope="module")
def tiny_data(sim_scenario):
    return from_scenes([sample_scene(sim_scenario, 3 + i, i, target_size=TARGET) for i in range(4)], (32, 24))


def _quiet(*_):
    pass


def test_training_without_resume_into_a_folder_of_another_seed_is_refused(tiny_data, tmp_path):
    train(tiny_data, tmp_path, OPTIONS, progress=False, log=_quiet)
    before = {name: (tmp_path / name).read_bytes() for name in ("model.pt", "checkpoint.pt", "metrics.json")}
    other_seed = TrainOptions(**{**OPTIONS.__dict__, "seed": 7})
    with pytest.raises(WeightFileError, match="seed 0"):
        train(tiny_data, tmp_path, other_seed, progress=False, log=_quiet)
    assert {name: (tmp_path / name).read_bytes() for name in before} == before
    assert json.loads((tmp_path / "metrics.json").read_text())["options"]["seed"] == 0


def test_training_again_with_the_same_options_is_allowed(tiny_data, tmp_path):
    train(tiny_data, tmp_path, OPTIONS, progress=False, log=_quiet)
    train(tiny_data, tmp_path, OPTIONS, progress=False, log=_quiet)


def test_a_model_without_its_checkpoint_is_not_overwritten(tiny_data, tmp_path):
    (tmp_path / "model.pt").write_bytes(b"someone's model")
    with pytest.raises(WeightFileError, match="without the checkpoint"):
        train(tiny_data, tmp_path, OPTIONS, progress=False, log=_quiet)
    assert (tmp_path / "model.pt").read_bytes() == b"someone's model"


@pytest.mark.parametrize("lr", ["nan", "inf", "-1", "0"])
def test_train_refuses_a_learning_rate_that_is_not_a_positive_number(tmp_path, capsys, lr):
    with pytest.raises(SystemExit) as exit_:
        main(["train", "--data", str(tmp_path), "--out", str(tmp_path / "m"), "--lr", lr])
    assert exit_.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--lr" in err[0]
    assert not (tmp_path / "m").exists()
