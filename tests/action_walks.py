"""Seeded random walks of feasible actions from Table I scenes: the states the cache and lattice tests compare on."""

from __future__ import annotations

import numpy as np

from slax_drake.evaluation.table1 import scene_seed
from slax_drake.shelf.actions import apply_action
from slax_drake.scene.sampling import sample_scene


def walk(scenario, model, n, seed, steps):
    """The states of a seeded random walk of ``steps`` feasible actions from a Table I scene of n objects, and the
    fixed objects (the target) the action model must keep clear of."""
    s = sample_scene(scenario, n, scene_seed(0, n, seed), target_size=(0.06, 0.06, 0.06))
    fixed = (s.target.as_object(),)
    rng = np.random.default_rng(seed)
    states = [s.objects]
    for _ in range(steps):
        feasible = model.enumerate(states[-1], fixed=fixed).feasible
        if not feasible:
            break
        states.append(apply_action(states[-1], feasible[int(rng.integers(len(feasible)))]))
    return states, fixed
