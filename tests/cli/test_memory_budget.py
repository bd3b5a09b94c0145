"""Size and resolution arguments are refused up front, with the memory they imply, when it exceeds what the
machine has available (the available figure is pinned to 8 GB here so the messages are exact)."""

import json

import pytest

from slax_drake import resources
from slax_drake.cli import main


@pytest.fixture
def eight_gb(monkeypatch):
    monkeypatch.setattr(resources, "available_memory_bytes", lambda: 8_000_000_000)


def _error(capsys) -> str:
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err
    return err.strip()


def test_occupancy_grid_step_far_too_fine_is_refused_with_the_estimate(tmp_path, eight_gb, capsys):
    scene, out = tmp_path / "scene.json", tmp_path / "occ.npz"
    assert main(["scene", "--objects", "4", "--seed", "1", "--out", str(scene)]) == 0
    capsys.readouterr()
    assert main(["occupancy", str(scene), "--grid-step", "0.00001", "--out", str(out)]) == 2
    err = _error(capsys)
    assert err.startswith("slax-drake occupancy: error: --grid-step 1e-05 m with --surface-spacing 0.005 m needs "
                          "about ")
    assert err.endswith(" TB of memory, more than the 8 GB available; use a coarser grid or spacing (the default is "
                        "0.005 m for both)")
    assert not out.exists()


def test_occupancy_estimate_is_small_at_the_defaults(sim_scenario):
    from slax_drake.occupancy.hidden import occupancy_memory_bytes
    from slax_drake.scene import sample_scene

    scene = sample_scene(sim_scenario, 8, 0)
    assert occupancy_memory_bytes(scene, [scene.target.size], 0.005, 0.005) < 100e6
    # a grid not aligned with the samples takes the direct path: every sample of every placement at once
    assert occupancy_memory_bytes(scene, [scene.target.size], 0.001, 0.005) > 10e9


def test_dataset_resolution_beyond_memory_is_refused_before_the_folder_is_made(tmp_path, eight_gb, capsys):
    out = tmp_path / "data"
    assert main(["dataset", "--scenes", "256", "--resolution", "4096x3072", "--out", str(out), "--no-progress"]) == 2
    assert _error(capsys) == (
        "slax-drake dataset: error: --resolution 4096x3072 with --shard-size 256, --grid-step 0.005 and --workers 1 "
        "needs about 130 GB of memory, more than the 8 GB available; use a smaller resolution or shard, a coarser "
        "grid or fewer workers")
    assert not out.exists()


def test_train_beyond_memory_is_refused_before_reading_the_data(tmp_path, eight_gb, capsys):
    data = tmp_path / "data"
    data.mkdir()
    (data / "manifest.json").write_text(json.dumps(
        {"shards": [], "num_scenes": 100000, "params": {"resolution": [128, 96]}}))
    code = main(["train", "--data", str(data), "--out", str(tmp_path / "model"), "--channels", "512", "--no-progress"])
    assert code == 2
    assert _error(capsys).startswith(
        "slax-drake train: error: training on 100000 samples at 128x96 with --batch-size 16, --channels 512 and "
        "--levels 4 needs about ")
    assert not (tmp_path / "model").exists()


def test_memory_check_passes_what_fits():
    resources.check_memory(1e9, "x", "y", available=2_000_000_000)
    with pytest.raises(resources.MemoryBudgetError, match="^x needs about 3 GB of memory, more than the 2 GB "
                       "available; y$"):
        resources.check_memory(3e9, "x", "y", available=2_000_000_000)


def test_export_rate_beyond_memory_is_refused(tmp_path, eight_gb, capsys):
    from trial_records import fake_trial

    src, out = tmp_path / "trial.json", tmp_path / "t.json"
    src.write_text(json.dumps({k: v for k, v in fake_trial().items() if k != "full_trajectory"}))
    from slax_drake.config import load_scenario
    from slax_drake.scene.io import save_scene
    from slax_drake.scene.sampling import sample_scene

    scene = tmp_path / "scene.json"
    save_scene(sample_scene(load_scenario("sim_configs/sim_shelf.yaml"), 2, seed=3), scene)
    assert main(["export", str(src), "--rate", "1e9", "--scene", str(scene), "--out", str(out)]) == 2
    err = _error(capsys)
    assert err.startswith("slax-drake export: error: --rate 1e+09 Hz (")
    assert "points) needs about " in err and err.endswith("available; use a lower rate")
    assert not out.exists()


def test_collision_step_beyond_memory_is_refused(tmp_path, eight_gb, capsys):
    from trial_records import fake_trial

    from slax_drake.hardware.export import export_trial
    from slax_drake.hardware.trajectory_file import save_trajectory

    path = tmp_path / "traj.json"
    save_trajectory(export_trial(fake_trial()), path)
    assert main(["check-trajectory", str(path), "--collision-step", "1e-12"]) == 2
    err = _error(capsys)
    assert err.startswith("slax-drake check-trajectory: error: --collision-step 1e-12 s (")
    assert "configurations) needs about " in err
    assert err.endswith(" of memory, more than the 8 GB available; use a longer step")
