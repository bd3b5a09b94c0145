"""Scenario files layered as Drake's loaders layer them: an overlay names its base (``base:``, relative to the
file) and sets only what it changes; every shipped scenario loads to exactly the dataclass it loaded to as one
flat file, and a malformed overlay is one clear ConfigError (one line on stderr, exit code 2)."""

import dataclasses
import hashlib
import json

import pytest

from slax_drake.cli import main
from slax_drake.config import REPO_ROOT, Scenario, ShelfCameraConfig, load_scenario
from slax_drake.errors import ConfigError

# SHA-256 of json.dumps(dataclasses.asdict(scenario), sort_keys=True) of each shipped scenario, as it loaded when
# every file was written out flat (types included: 1 and 1.0 differ).
FLAT_DIGESTS = {
    "sim_configs/physical_shelf.yaml": "aae8d26c73120cf62deec269b5e443045b2168710de6ab2ed2b1a02cab7efca6",
    "sim_configs/sim_shelf.yaml": "0ae367567db4a43e47b1e6d38fa2ed8b35b54f0b4cb0fe37bdf1c612f9468daf",
    "sim_configs/table1.yaml": "c66db8a0a01852b49fd245de1bec68c8d8d8db8367b3768e0beaa69dea1c0402",
    "sim_configs/table1_aligned.yaml": "19fdef14a94e5067fd7f91a59268893cdd43e5f88c2e910d6b18c4f266fe5774",
    "sim_configs/table1_household.yaml": "0979e36b316968b36aa92413dc87e6e9cd7bdfd4a5ec2a192ae1c7d99c151e75",
    "sim_configs/table2.yaml": "928f496014b137dbccadacb93f13b7234d9ecf67200d1f69da0520af967c6e16",
}


# What was changed on purpose since: the simulated shelves draw household masses (issue 27's decision on masses for
# Drake trials); table1.yaml keeps the density model by naming it, so the Table I protocol is unchanged.
MASS_MODEL_SINCE = {"sim_configs/sim_shelf.yaml": "household", "sim_configs/physical_shelf.yaml": "household"}


def digest(scenario: Scenario) -> str:
    return hashlib.sha256(json.dumps(dataclasses.asdict(scenario), sort_keys=True).encode()).hexdigest()


@pytest.mark.parametrize("path", sorted(FLAT_DIGESTS))
def test_each_shipped_scenario_loads_to_what_it_loaded_before(path):
    scenario = load_scenario(path)
    if path in MASS_MODEL_SINCE:
        assert scenario.physics.mass_model == MASS_MODEL_SINCE[path]
        scenario = dataclasses.replace(scenario, physics=dataclasses.replace(scenario.physics, mass_model="density"))
    assert digest(scenario) == FLAT_DIGESTS[path]


def test_the_shipped_scenarios_are_covered():
    shipped = {f"sim_configs/{p.name}" for p in (REPO_ROOT / "sim_configs").glob("*.yaml")
               if not p.name.startswith("station_")}
    assert shipped == set(FLAT_DIGESTS)


def test_an_overlay_changes_only_its_keys():
    table1, aligned = load_scenario("sim_configs/table1.yaml"), load_scenario("sim_configs/table1_aligned.yaml")
    assert aligned == dataclasses.replace(table1, objects=dataclasses.replace(table1.objects, box_yaw="aligned"))
    assert isinstance(aligned.camera, ShelfCameraConfig)


def write(folder, name, text):
    path = folder / name
    path.write_text(text)
    return path


def test_layers_stack_in_order_and_lists_replace(tmp_path):
    write(tmp_path, "a.yaml", "shelf:\n  width: 0.7\nobjects:\n  count_range: [3, 9]\n")
    write(tmp_path, "b.yaml", "base: a.yaml\nshelf:\n  depth: 0.5\n")
    sub = tmp_path / "sub"
    sub.mkdir()
    c = write(sub, "c.yaml", "base: ../b.yaml\nobjects:\n  count_range: [4, 8]\n")
    s = load_scenario(c)
    assert (s.shelf.width, s.shelf.depth, s.shelf.height) == (0.7, 0.5, Scenario().shelf.height)
    assert s.objects.count_range == [4, 8]
    assert load_scenario(tmp_path / "a.yaml").shelf.depth == Scenario().shelf.depth  # the base is not changed


@pytest.mark.parametrize("text, says", [
    ("base: missing.yaml\n", "no such config file"),
    ("base: [a.yaml]\n", "must be the path of a scenario file"),
    ("base: self.yaml\n", "cycle"),
    ("base: a.yaml\nshelf:\n  widht: 0.5\n", "unknown key 'shelf.widht'"),
    ("base: a.yaml\nshelf:\n  width: wide\n", "must be a number"),
    ("base: a.yaml\nshelf:\n  width: 5.0\nobjects:\n  max_size: 0.9\n", "objects.max_size"),
    ("base: a.yaml\nshelf: [\n", "not valid YAML"),
])
def test_a_malformed_overlay_is_one_config_error(tmp_path, text, says):
    write(tmp_path, "a.yaml", "shelf:\n  width: 0.7\n")
    path = write(tmp_path, "self.yaml", text)
    with pytest.raises(ConfigError, match=says) as e:
        load_scenario(path)
    assert "\n" not in str(e.value) and str(path) in str(e.value)


def test_a_cycle_of_two_files_is_refused(tmp_path):
    write(tmp_path, "a.yaml", "base: b.yaml\n")
    write(tmp_path, "b.yaml", "base: a.yaml\n")
    with pytest.raises(ConfigError, match="cycle"):
        load_scenario(tmp_path / "a.yaml")


def test_the_command_line_reports_a_bad_overlay_in_one_line(tmp_path, capsys):
    path = write(tmp_path, "bad.yaml", "base: nowhere.yaml\n")
    assert main(["scene", "--config", str(path), "--out", str(tmp_path / "scene.json")]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "nowhere.yaml" in err


def test_the_household_overlay_changes_only_the_mass_model():
    table1, household = load_scenario("sim_configs/table1.yaml"), load_scenario("sim_configs/table1_household.yaml")
    assert household == dataclasses.replace(table1, physics=dataclasses.replace(table1.physics,
                                                                                mass_model="household"))
