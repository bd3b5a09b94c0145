"""Dataset shards: content, resume after a kill mid-shard, the Ray backend equal to the local one."""

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import h5py
import numpy as np
import pytest

from slax_drake.dataset import DatasetReader, DatasetSpec, generate
from slax_drake.errors import DatasetError

ARGS = ["--scenes", "6", "--shard-size", "2", "--resolution", "64x48", "--seed", "5", "--grid-step", "0.01"]
SPEC = DatasetSpec(config="sim_configs/sim_shelf.yaml", scenes=6, resolution=(64, 48), seed=5, shard_size=2,
                   grid_step=0.01)


def _cli(out, *extra):
    return [sys.executable, "-m", "slax_drake.cli", "dataset", *ARGS, "--out", str(out), "--no-progress", *extra]


def _arrays(folder):
    data = {}
    for k in range(3):
        with h5py.File(Path(folder) / f"shard_{k:05d}.h5", "r") as f:
            for name in f:
                data[(k, name)] = f[name][:]
    return data


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    out = tmp_path_factory.mktemp("ref")
    generate(SPEC, out, workers=1, progress=False)
    return out


def test_samples_content(reference):
    reader = DatasetReader(reference)
    assert len(reader) == 6
    manifest = json.loads((reference / "manifest.json").read_text())
    assert manifest["num_scenes"] == 6 and sum(manifest["scenes_per_target_ratio"]) == 6
    assert manifest["package_version"] and "shelf:" in manifest["config_yaml"]
    for i in range(len(reader)):
        s = reader[i]
        assert s["depth"].shape == (1, 48, 64) and s["depth"].dtype == np.float32
        assert s["p2d"].shape == (3, 48, 64) and s["p1d"].shape == (3, 64)
        assert (s["p2d"] >= 0).all()
        for r in range(3):
            assert s["p2d"][r].sum() == pytest.approx(1.0 if s["num_hidden"][r] else 0.0, abs=1e-5)
            np.testing.assert_allclose(s["p1d"][r], s["p2d"][r].sum(axis=0), atol=1e-6)
        assert s["num_hidden"][s["target_ratio"]] > 0
        scene = json.loads(reader.scene_json(i))
        assert 2 <= len(scene["objects"]) <= 12
        assert not (s["label"] == len(scene["objects"]) + 1).any()  # the target is hidden in the image too
    with h5py.File(reference / "shard_00000.h5", "r") as f:
        assert f["depth"].dtype == np.float16 and f["depth"].compression == "gzip"


@pytest.mark.slow
def test_resume_after_kill_mid_shard(reference, tmp_path):
    out = tmp_path / "ds"
    proc = subprocess.Popen(_cli(out), stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.time() + 120
    while not (out / "shard_00000.h5").exists() and time.time() < deadline and proc.poll() is None:
        time.sleep(0.002)
    assert proc.poll() is None, "the run finished before it could be killed"
    # Killed at once: the run is now making the second shard (a shard of two scenes takes tens of
    # milliseconds, so waiting longer here could let the whole run finish first).
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait()
    finished = sorted(p.name for p in out.glob("shard_*.h5"))
    assert finished and len(finished) < 3
    assert not (out / "manifest.json").exists()
    before = {name: (out / name).stat().st_mtime_ns for name in finished}
    assert subprocess.run(_cli(out), capture_output=True).returncode == 0
    for name, mtime in before.items():  # finished shards were kept, not remade
        assert (out / name).stat().st_mtime_ns == mtime
    assert not list(out.glob(".*.tmp"))
    got, want = _arrays(out), _arrays(reference)
    assert got.keys() == want.keys()
    for key in want:
        np.testing.assert_array_equal(got[key], want[key], err_msg=str(key))


def test_other_arguments_refused(reference):
    spec = DatasetSpec(config=SPEC.config, scenes=6, resolution=(64, 48), seed=6, shard_size=2, grid_step=0.01)
    with pytest.raises(DatasetError, match="other arguments"):
        generate(spec, reference, progress=False)


@pytest.mark.slow
def test_bad_resolution_is_a_user_error(tmp_path):
    r = subprocess.run([sys.executable, "-m", "slax_drake.cli", "dataset", "--scenes", "2", "--out",
                        str(tmp_path / "x"), "--resolution", "big"], capture_output=True, text=True)
    assert r.returncode == 2 and "WIDTHxHEIGHT" in r.stderr and "Traceback" not in r.stderr


def test_corrupt_shard_is_a_user_error(reference, tmp_path):
    import shutil

    copy = tmp_path / "copy"
    shutil.copytree(reference, copy)
    (copy / "shard_00001.h5").write_bytes(b"not hdf5")
    reader = DatasetReader(copy)
    with pytest.raises(DatasetError, match="shard_00001"):
        reader[2]


@pytest.mark.slow
def test_ray_backend_equals_local(reference, tmp_path):
    ray = pytest.importorskip("ray")
    ray.init(num_cpus=1, include_dashboard=False, log_to_driver=False)
    try:
        generate(SPEC, tmp_path / "ray", workers=1, backend="ray", progress=False)
    finally:
        ray.shutdown()
    got, want = _arrays(tmp_path / "ray"), _arrays(reference)
    assert got.keys() == want.keys()
    for key in want:
        np.testing.assert_array_equal(got[key], want[key], err_msg=str(key))
