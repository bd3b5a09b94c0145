"""Object masses: from a density (the default) or drawn from household goods' published masses.

A scene's objects weigh ``density x volume`` unless the scenario's ``physics.mass_model`` is "household": then
:func:`sample_masses` draws each object's mass, log-uniformly between the lightest and the heaviest of its
shape's volume class (``physics.box_masses`` / ``physics.cylinder_masses``, sources in slax_drake/config.py),
from a random stream of its own seeded by the scene seed (the scene's geometry draws are unchanged, so a scene
seed gives the same shelf under both mass models). The mass is stored on the object (``SceneObject.mass``,
kept in scene JSON); an object without one (a perceived hypothesis, an older scene file) weighs what
:func:`object_mass` says: its recorded mass, else the class's median mass (the geometric mean of its range) under
"household", else density x volume. Masses in kilograms, volumes of the solid box or cylinder.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

MASS_STREAM = 17  # the second seed word of the masses' random stream (numpy SeedSequence([seed, MASS_STREAM]))


def volume(shape: str, size) -> float:
    """The solid box's or upright cylinder's volume (m^3)."""
    sx, sy, sz = size
    return math.pi * (sx / 2.0) ** 2 * sz if shape == "cylinder" else sx * sy * sz


def mass_range(shape: str, size, physics) -> tuple[float, float]:
    """(lightest, heaviest) kg of the household class of an object of ``shape`` and ``size`` (``physics``: a
    PhysicsConfig): the first class whose largest volume holds it, else the last."""
    table = physics.cylinder_masses if shape == "cylinder" else physics.box_masses
    litres = volume(shape, size) * 1000.0
    row = next((r for r in table if litres <= r[0]), table[-1])
    return float(row[1]), float(row[2])


def median_mass(shape: str, size, physics) -> float:
    """The median of the log-uniform class distribution (kg): what a planner that does not know the object
    expects it to weigh."""
    return quantile_mass(shape, size, physics, 0.5)


def quantile_mass(shape: str, size, physics, quantile: float) -> float:
    """The mass (kg) that a share ``quantile`` (0-1) of the log-uniform class distribution does not exceed:
    lightest x (heaviest / lightest) ** quantile (0.5: the median, the geometric mean of the range)."""
    lo, hi = mass_range(shape, size, physics)
    return math.sqrt(lo * hi) if quantile == 0.5 else lo * (hi / lo) ** quantile


def sample_masses(objects, physics, seed: int) -> tuple:
    """``objects`` with ``mass`` drawn for each (household model; in order, one draw per object) from the stream
    seeded by (``seed``, MASS_STREAM); unchanged under the density model."""
    if physics.mass_model != "household":
        return tuple(objects)
    rng = np.random.default_rng([int(seed), MASS_STREAM])
    out = []
    for obj in objects:
        lo, hi = mass_range(obj.shape, obj.size, physics)
        u = float(rng.random())
        out.append(dataclasses.replace(obj, mass=round(lo * (hi / lo) ** u, 4)))
    return tuple(out)


def object_mass(obj, density: float, physics=None, quantile: float = 0.5) -> float:
    """The mass (kg) of ``obj``: its recorded ``mass``; else, with a household ``physics`` (PhysicsConfig), its
    class's ``quantile`` (:func:`quantile_mass`; 0.5: the median); else ``density`` (kg/m^3) x volume."""
    recorded = getattr(obj, "mass", None)
    if recorded is not None:
        return float(recorded)
    if physics is not None and physics.mass_model == "household":
        return quantile_mass(obj.shape, obj.size, physics, quantile)
    return density * volume(obj.shape, obj.size)


def mass_model_words(mass_model: str | None) -> str:
    """A report's words for a scenario's ``physics.mass_model`` (None: a record from before it was kept)."""
    return {"household": "household goods' masses by shape and volume (physics.mass_model: household)",
            "density": "objects.density x volume (physics.mass_model: density)"}.get(
        mass_model, "not recorded (a run from before the mass model was; see its scenario)")
