"""``slax-drake trial --benchmark-scene N:INDEX``: the options of the very trial the physics benchmark runs for that
scene (no simulation here), and one clear message with exit code 2 for a bad request."""

from pathlib import Path

import pytest

from slax_drake.cli import main
from slax_drake.evaluation.table1 import scene_seed
from slax_drake.systems.trial import DEFAULT_OBJECTS, DEFAULT_SEED, TrialOptions
from slax_drake.evaluation.benchmark_trial import benchmark_scene_options


def test_benchmark_scene_gives_the_protocols_seed_target_horizon_and_station():
    opts = benchmark_scene_options(TrialOptions(config="sim_configs/table1.yaml"), "8:1")
    assert (opts.objects, opts.seed, opts.horizon) == (8, scene_seed(0, 8, 1), 16) and opts.seed == 80057
    assert opts.target_size == (0.06, 0.06, 0.06)
    assert opts.station.endswith("sim_configs/station_sim_shelf.yaml")
    given = benchmark_scene_options(TrialOptions(config="sim_configs/table1.yaml", station="my.yaml"), "4:0")
    assert given.station == "my.yaml" and given.seed == scene_seed(0, 4, 0)
    plain = TrialOptions()
    assert (plain.objects, plain.seed) == (DEFAULT_OBJECTS, DEFAULT_SEED)



def test_benchmark_scene_counts_the_target_among_n_when_the_protocol_does(tmp_path):
    """With ``protocol.count_includes_target`` the Drake trial of scene N:INDEX holds N - 1 occluders, as the
    Table I benchmark's scene of that seed does (slax_drake.evaluation.table1), and H stays 2N."""
    text = f"base: {Path('sim_configs/table1.yaml').resolve()}\nprotocol:\n  count_includes_target: true\n"
    config = tmp_path / "table1.yaml"
    config.write_text(text)
    opts = benchmark_scene_options(TrialOptions(config=str(config)), "8:1")
    assert (opts.objects, opts.seed, opts.horizon) == (7, scene_seed(0, 8, 1), 16)

@pytest.mark.parametrize("argv, message", [
    (["--benchmark-scene", "8-1"], "N:INDEX"),
    (["--benchmark-scene", "0:1"], "N >= 1"),
    (["--benchmark-scene", "8:1", "--seed", "3"], "replaces --objects and --seed"),
])
def test_bad_benchmark_scene_requests_exit_with_code_2(capsys, argv, message):
    assert main(["trial", "--config", "sim_configs/table1.yaml", *argv]) == 2
    err = capsys.readouterr().err
    assert message in err and len(err.strip().splitlines()) == 1
