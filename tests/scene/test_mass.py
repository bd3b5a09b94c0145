"""Object masses (issue 17 item 2; issue 27's decision): the density model is the dataclass's default and the
Table I protocol's (earlier runs reproducible); the shipped simulated shelf uses the household model, which draws each object's mass from its shape's volume class, deterministically per scene seed, kept in
scene JSON, weighed by the action model and the Drake world alike."""

import dataclasses

import numpy as np
import pytest

from slax_drake.config import load_scenario
from slax_drake.errors import ConfigError
from slax_drake.shelf.actions import object_mass as model_mass
from slax_drake.shelf.tool import tool_config
from slax_drake.scene.io import scene_from_dict, scene_to_dict
from slax_drake.scene.mass import mass_range, median_mass, object_mass, volume
from slax_drake.scene.sampling import sample_scene


@pytest.fixture(scope="module")
def household(sim_scenario):
    assert sim_scenario.physics.mass_model == "household"  # the shipped simulated shelf's default
    return sim_scenario


def test_density_model_is_the_table1_default_and_leaves_scenes_as_they_were(paper, density_scenario):
    from slax_drake.config import PhysicsConfig

    assert PhysicsConfig().mass_model == "density" and paper.physics.mass_model == "density"
    scene = sample_scene(density_scenario, 6, seed=11)
    assert all(o.mass is None for o in scene.objects)
    assert all("mass" not in d for d in scene_to_dict(scene)["objects"])
    o = scene.objects[0]
    assert object_mass(o, 400.0) == pytest.approx(400.0 * volume(o.shape, o.size))


def test_household_masses_are_deterministic_per_seed_and_within_their_class(density_scenario, household):
    a, b = sample_scene(household, 8, seed=21), sample_scene(household, 8, seed=21)
    c = sample_scene(household, 8, seed=22)
    assert [o.mass for o in a.objects] == [o.mass for o in b.objects]
    assert [o.mass for o in a.objects] != [o.mass for o in c.objects[:8]]
    # the geometry is the density model's scene for that seed: the masses come from a stream of their own
    plain = sample_scene(density_scenario, 8, seed=21)
    assert [(o.shape, o.size, o.X_SO.tolist()) for o in a.objects] == \
        [(o.shape, o.size, o.X_SO.tolist()) for o in plain.objects]
    for o in a.objects:
        lo, hi = mass_range(o.shape, o.size, household.physics)
        assert lo <= o.mass <= hi
    # kept through scene JSON, and what both the action model and the Drake world weigh
    again = scene_from_dict(scene_to_dict(a))
    assert [o.mass for o in again.objects] == [o.mass for o in a.objects]
    tool = tool_config(household)
    assert [model_mass(o, 400.0, tool.physics) for o in a.objects] == [o.mass for o in a.objects]


def test_household_classes_and_the_median_a_planner_expects(household):
    phys = household.physics
    assert mass_range("box", (0.05, 0.05, 0.05), phys) == (0.05, 0.5)  # 0.125 L
    assert mass_range("box", (0.2, 0.2, 0.2), phys) == (0.15, 1.2)  # 8 L
    assert mass_range("cylinder", (0.2, 0.2, 0.3), phys) == (0.3, 2.1)  # 9.4 L: the last class
    # an object without a recorded mass (a perceived hypothesis) weighs its class's median under household
    hyp = sample_scene(household, 3, seed=5).objects[0]
    hyp = dataclasses.replace(hyp, mass=None)
    expected = median_mass(hyp.shape, hyp.size, phys)
    assert model_mass(hyp, 400.0, tool_config(household).physics) == pytest.approx(expected)
    assert expected == pytest.approx(np.sqrt(np.prod(mass_range(hyp.shape, hyp.size, phys))))


@pytest.mark.parametrize("line, message", [
    ("  mass_model: heavy", "physics.mass_model"),
    ("  box_masses: [[2.0, 0.1, 0.8], [1.0, 0.1, 0.5]]", "physics.box_masses[1]"),
    ("  object_friction: 0.0", "physics.object_friction"),
])
def test_bad_physics_sections_are_refused(tmp_path, line, message):
    path = tmp_path / "s.yaml"
    path.write_text("physics:\n" + line + "\n")
    with pytest.raises(ConfigError, match=message.replace("[", r"\[").replace("]", r"\]")):
        load_scenario(path)


def test_the_drake_world_weighs_the_recorded_masses(household):
    from slax_drake.station.plant import make_station_plant
    from slax_drake.station.scenario import load_station_scenario

    scene = sample_scene(household, 3, seed=8)
    station = make_station_plant(load_station_scenario("sim_configs/station_sim_shelf.yaml"), scene)
    context = station.plant.CreateDefaultContext()
    for o in scene.objects:
        assert station.plant.GetBodyByName(o.name).get_mass(context) == pytest.approx(o.mass)


def test_the_cups_holding_limit_is_derived_from_its_model(tmp_path):
    from slax_drake.station.scenario import load_station_scenario

    station = load_station_scenario("sim_configs/station_sim_shelf.yaml")
    cup = station.suction
    assert cup.max_force == pytest.approx(60000.0 * np.pi * 0.015**2)  # 42.4 N
    assert cup.lip_moment == pytest.approx(cup.max_force * 0.015)  # 0.64 N m
    assert cup.max_held_moment <= cup.lip_moment
    text = open("sim_configs/station_sim_shelf.yaml").read().replace("max_held_moment: 0.4 ", "max_held_moment: 0.9 ")
    bad = tmp_path / "station.yaml"
    bad.write_text(text.replace("scene_config: sim_configs/", "scene_config: " + str(__import__("slax_drake.config",
                                fromlist=["REPO_ROOT"]).REPO_ROOT) + "/sim_configs/"))
    with pytest.raises(ConfigError, match="must not exceed what the cup's model holds"):
        load_station_scenario(bad)
