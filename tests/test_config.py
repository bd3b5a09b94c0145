"""Scenario YAML loading: the shipped configs load, and every bad value gives one clear ConfigError."""

import textwrap
from pathlib import Path

import pytest

from slax_drake.config import load_scenario
from slax_drake.errors import ConfigError

REPO = Path(__file__).resolve().parents[1]


@pytest.mark.parametrize("name", ["sim_shelf.yaml", "physical_shelf.yaml", "table1.yaml"])
def test_shipped_configs_load(name):
    scenario = load_scenario(REPO / "sim_configs" / name)
    assert scenario.shelf.width > 0


def test_paper_numbers():
    sim = load_scenario(REPO / "sim_configs" / "sim_shelf.yaml")
    assert (sim.shelf.width, sim.shelf.height, sim.shelf.depth) == (0.60, 0.60, 0.60)
    assert sim.target.sizes == [[0.06, 0.06, 0.06]]
    assert sim.target.visibility_threshold == 0.80
    phys = load_scenario(REPO / "sim_configs" / "physical_shelf.yaml")
    assert (phys.shelf.width, phys.shelf.height, phys.shelf.depth) == (0.80, 0.50, 0.50)
    assert phys.target.sizes == [[0.06, 0.06, 0.03]]
    table1 = load_scenario(REPO / "sim_configs" / "table1.yaml")
    assert table1.protocol.densities == [4, 6, 8, 10]
    assert table1.protocol.scenes_per_density == 100
    assert table1.protocol.horizon_per_object == 2
    assert table1.protocol.suction_cost == 1.3


def _write(tmp_path, body: str) -> Path:
    path = tmp_path / "bad.yaml"
    path.write_text(textwrap.dedent(body))
    return path


@pytest.mark.parametrize(
    "body, expected",
    [
        ("shelf:\n  widht: 0.6\n", "widht"),  # unknown key
        ("shelf:\n  width: wide\n", "key 'shelf.width' = 'wide': must be a number"),  # wrong type
        ("camera:\n  width: 640.5\n", "key 'camera.width' = 640.5: must be an integer"),
        ("shelf:\n  widht: 0.6\n", "unknown key 'shelf.widht'"),
        ("shelf:\n  width: -0.6\n", "key 'shelf.width' = -0.6: must be a positive number"),
        ("shelf:\n  depth: 0.0\n", "key 'shelf.depth' = 0.0: must be a positive number"),
        ("objects:\n  max_size: 0.9\n", "key 'objects.max_size' = 0.9: an object this large does not fit"),
        ("objects:\n  min_size: 0.3\n  max_size: 0.2\n", "key 'objects.max_size' = 0.2: must be at least objects.min_size"),
        ("target:\n  sizes: [[0.06, 0.06, 0.9]]\n", "key 'target.sizes[0]' = [0.06, 0.06, 0.9]: the target does not fit"),
        ("target:\n  sizes: [[0.06, 0.06]]\n", "key 'target.sizes[0]'"),
        ("objects:\n  count_range: [2, 500]\n", "key 'objects.count_range' = 500: at most"),
        ("camera:\n  position: [0.0, 0.0, 0.2]\n", "key 'camera.position'"),
        ("protocol:\n  densities: [4, 400]\n", "key 'protocol.densities' = 400"),
        ("camera:\n  horizontal_fov_deg: 200\n", "key 'camera.horizontal_fov_deg' = 200"),
        ("objects:\n  box_yaw: diagonal\n", "key 'objects.box_yaw' = 'diagonal': must be 'random' or 'aligned'"),
    ],
)
def test_bad_config_names_file_key_and_value(tmp_path, body, expected):
    path = _write(tmp_path, body)
    with pytest.raises(ConfigError) as info:
        load_scenario(path)
    message = str(info.value)
    assert message.startswith(str(path)), message
    assert expected in message, message
    assert "\n" not in message


def test_missing_config_file(tmp_path):
    with pytest.raises(ConfigError, match="no such config file"):
        load_scenario(tmp_path / "nope.yaml")
