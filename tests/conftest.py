"""Shared fixtures: the shipped scenarios and a few sampled scenes (sampled once per session)."""

from pathlib import Path

import pytest

from slax_drake.config import load_scenario

REPO = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def paper():
    """The Table I scenario (the paper profile), loaded once per test module."""
    return load_scenario(REPO / "sim_configs" / "table1.yaml")


@pytest.fixture(scope="session")
def sim_scenario():
    return load_scenario(REPO / "sim_configs" / "sim_shelf.yaml")


@pytest.fixture(scope="session")
def density_scenario(sim_scenario):
    """The simulated shelf with the density mass model (objects.density x volume), as the shipped scenario was
    before household masses became its default (table1.yaml keeps it)."""
    import dataclasses

    return dataclasses.replace(sim_scenario, physics=dataclasses.replace(sim_scenario.physics, mass_model="density"))


@pytest.fixture(scope="session")
def physical_scenario():
    return load_scenario(REPO / "sim_configs" / "physical_shelf.yaml")
