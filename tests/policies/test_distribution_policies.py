"""Distribution policies: deterministic rollouts, history encoding, and they only act on seen objects."""

import numpy as np
import pytest

from slax_drake.shelf.distribution import entropy, history_min, support
from slax_drake.policies.registry import make_policy
from slax_drake.shelf.simulator import observe, run_trial
from slax_drake.scene import sample_scene


def test_support_entropy_and_history():
    p = np.array([0.0, 0.5, 0.5, 0.0])
    q = np.array([0.2, 0.0, 0.8, 0.0])
    h = history_min(q, p)
    assert support(h) == 1 and np.allclose(h, [0, 0, 0.5, 0])
    assert entropy(p) == pytest.approx(np.log(2))
    assert entropy(np.zeros(3)) == 0.0


@pytest.mark.parametrize("name", ["dar", "bluction-dar", "der-3"])
def test_rollouts_are_deterministic(sim_scenario, name):
    scene = sample_scene(sim_scenario, 4, 7, target_size=(0.06, 0.06, 0.06))
    a = run_trial(scene, make_policy(name, sim_scenario, horizon=3), 3)
    b = run_trial(scene, make_policy(name, sim_scenario, horizon=3), 3)
    assert a.actions == b.actions and a.success == b.success and a.steps == b.steps
    assert a.steps >= 1 or a.reason != "horizon"


def test_policies_act_only_on_seen_objects(sim_scenario):
    scene = sample_scene(sim_scenario, 8, 3, target_size=(0.06, 0.06, 0.06))
    policy = make_policy("bluction-dar", sim_scenario, horizon=16)
    obs = observe(scene, policy.distribution)
    assert set(o.name for o in obs.known) <= set(o.name for o in scene.objects)
    policy.reset(scene)
    action = policy.decide(obs).best
    if action is not None:
        assert action.name in {o.name for o in obs.known}


def test_unknown_policy_and_unknown_perception_are_user_errors(sim_scenario):
    from slax_drake.errors import UserError

    with pytest.raises(UserError, match="unknown policy"):
        make_policy("nope", sim_scenario)
    with pytest.raises(UserError, match="unknown perception 'psychic'"):
        make_policy("dar", sim_scenario, perception="psychic")


def test_learned_perception_plugs_into_the_policies(sim_scenario):
    """--perception learned: the shipped network predicts the 1D distribution of a believed scene."""
    from slax_drake.perception.distribution_model import LearnedDistribution
    from slax_drake.shelf.distribution import make_distribution_model

    model = make_distribution_model("learned", (0.06, 0.06, 0.06))
    assert isinstance(model, LearnedDistribution)
    scene = sample_scene(sim_scenario, 6, 2)
    p = model.distribution(scene)
    assert p.ndim == 1 and np.all(p >= 0) and p.sum() == pytest.approx(1.0, abs=1e-4)
    assert (p > 0).sum() < p.size  # the network's support is cut, not the whole image width


def test_lookahead_policy_is_deterministic(sim_scenario):
    scene = sample_scene(sim_scenario, 6, 11, target_size=(0.06, 0.06, 0.06))
    a = run_trial(scene, make_policy("bluction-la2", sim_scenario, horizon=4), 4)
    b = run_trial(scene, make_policy("bluction-la2", sim_scenario, horizon=4), 4)
    assert a.actions == b.actions and a.success == b.success
    assert a.steps >= 1 or a.reason != "horizon"
