"""A station YAML is refused at load, with one line naming the key, when its observation configuration lies outside
the robot's joint limits or when it names a model file or reach map that does not exist."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml

from slax_drake.cli import main
from slax_drake.config import REPO_ROOT
from slax_drake.errors import ConfigError
from slax_drake.station.scenario import load_station_scenario

SHIPPED = REPO_ROOT / "sim_configs" / "station_sim_shelf.yaml"


def _station(tmp_path: Path, change) -> Path:
    data = yaml.safe_load(SHIPPED.read_text())
    change(data)
    path = tmp_path / "station.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


def test_the_shipped_stations_load():
    for path in sorted((REPO_ROOT / "sim_configs").glob("station_*.yaml")):
        load_station_scenario(path)


def test_an_observation_configuration_beyond_the_joint_limits_is_refused(tmp_path):
    path = _station(tmp_path, lambda d: d["observation_configuration"].update(elbow_flex_joint=3.0))
    with pytest.raises(ConfigError, match=r"observation_configuration\.elbow_flex_joint.*limits \[-2\.251, 2\.251\]"):
        load_station_scenario(path)


def test_a_missing_robot_model_file_is_refused(tmp_path):
    def change(d):
        d["directives"][0]["add_model"]["file"] = "package://slax_drake_models/no_such_robot.urdf"

    with pytest.raises(ConfigError, match="no_such_robot.urdf, which does not exist"):
        load_station_scenario(_station(tmp_path, change))


def test_a_missing_reach_map_is_refused(tmp_path):
    path = _station(tmp_path, lambda d: d.update(reach_map="models/reach/no_such_map.json"))
    with pytest.raises(ConfigError, match="reach_map"):
        load_station_scenario(path)


def test_the_command_line_says_it_in_one_line(tmp_path, capsys):
    path = _station(tmp_path, lambda d: d["observation_configuration"].update(torso_lift_joint=0.5))
    assert main(["diagram", "--station", str(path), "--out", str(tmp_path / "d")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "torso_lift_joint" in err[0] and err[0].startswith("slax-drake diagram: error:")
