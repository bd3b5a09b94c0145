"""The Policy protocol (issue 18.2): every registered policy implements it, the oracles included; an excluded
candidate is not proposed again; history is read-only; the registry is a table; the planner system keeps its
trial in the Drake context, so Simulator.Initialize on a reset context replays the same trial."""

import numpy as np
import pytest

from slax_drake.policies.protocol import Decision, Policy
from slax_drake.policies.registry import POLICY_NAMES, POLICY_TABLE, PolicyEntry, make_policy
from slax_drake.shelf.simulator import observation_for, run_trial
from slax_drake.scene.sampling import sample_scene

TARGET = (0.06, 0.06, 0.06)


@pytest.fixture
def scene(sim_scenario):
    return sample_scene(sim_scenario, 6, 5, target_size=TARGET)


@pytest.mark.parametrize("name", POLICY_NAMES)
def test_every_registered_policy_implements_the_protocol(sim_scenario, scene, name):
    policy = make_policy(name, sim_scenario, horizon=12)
    assert isinstance(policy, Policy)
    assert policy.needs_true_scene == name.startswith("oracle")
    policy.reset(scene)
    decision = policy.decide(observation_for(policy, scene))
    assert isinstance(decision, Decision)
    assert decision.candidates or decision.stop_reason
    assert len(set(decision.candidates)) == len(decision.candidates)
    assert policy.exclusions == ()


@pytest.mark.parametrize("name", ["dar", "der-3", "bluction-dar", "bluction-la2", "oracle-p+s"])
def test_an_excluded_candidate_is_not_proposed_again_and_is_recorded(sim_scenario, scene, name):
    policy = make_policy(name, sim_scenario, horizon=12)
    policy.reset(scene)
    obs = observation_for(policy, scene)
    first = policy.decide(obs).best
    assert first is not None
    policy.exclude(first, "approach: in collision")
    again = policy.decide(obs)
    assert first not in again.candidates
    assert policy.exclusions == ((first, "approach: in collision"),)
    policy.reset(scene)  # a new trial forgets its exclusions
    assert policy.exclusions == () and policy.decide(observation_for(policy, scene)).best == first


def test_a_group_exclusion_removes_the_objects_actions_in_that_direction(sim_scenario, scene):
    from slax_drake.policies.protocol import action_group

    policy = make_policy("bluction-dar", sim_scenario, horizon=12)
    policy.reset(scene)
    obs = observation_for(policy, scene)
    first = policy.decide(obs).best
    policy.exclude(first, "pre-approach: unreachable", whole_group=True)
    assert all(action_group(a) != action_group(first) for a in policy.decide(obs).candidates)


def test_history_is_read_only_and_follows_the_observations(sim_scenario, scene):
    policy = make_policy("dar", sim_scenario, horizon=12)
    policy.reset(scene)
    assert policy.history is None
    obs = observation_for(policy, scene)
    policy.decide(obs)
    h = policy.history
    np.testing.assert_array_equal(h, obs.p1d)
    with pytest.raises(ValueError):
        h[0] = 1.0
    with pytest.raises(AttributeError):
        policy.history = None


def readme_example_policy():
    """The example policy of the docs' "Add a policy" page, executed from the page's text."""
    from pathlib import Path

    section = Path(__file__).resolve().parents[2].joinpath("docs", "how-to", "add-a-policy.md").read_text()
    code = section[section.index("```python") + len("```python"):section.index("```", section.index("```python") + 3)]
    namespace = {"__name__": "readme_example"}
    exec(compile(code, "docs/how-to/add-a-policy.md", "exec"), namespace)
    return namespace["PushFirst"]


def test_a_new_policy_is_one_class_and_one_table_line(sim_scenario, scene, monkeypatch):
    """The docs' example policy, registered by one table row, runs in the shelf simulator like any other."""
    import sys
    import types

    import slax_drake.policies.registry as registry

    module = types.ModuleType("readme_example")
    module.PushFirst = readme_example_policy()
    monkeypatch.setitem(sys.modules, "readme_example", module)
    monkeypatch.setitem(registry.POLICY_TABLE, "push-first", PolicyEntry("readme_example:PushFirst"))
    policy = make_policy("push-first", sim_scenario, horizon=12)
    assert isinstance(policy, Policy) and isinstance(policy, module.PushFirst)
    result = run_trial(scene, policy, 12)
    assert result.policy == "push-first" and result.steps >= 1
    assert all(a.startswith("push ") for a in result.actions)


def test_the_registry_is_a_table():
    assert set(POLICY_TABLE) == set(POLICY_NAMES)
    for entry in POLICY_TABLE.values():
        assert isinstance(entry.load(), type)


@pytest.mark.slow
def test_initialize_after_a_context_reset_replays_the_same_trial():
    """The planner system's plan, log, result and cost are in the context: reset it, Initialize, and the same
    trial runs again."""
    from pydrake.systems.analysis import Simulator

    from slax_drake.systems.trial import TrialOptions, build_trial

    trial = build_trial(TrialOptions(objects=2, seed=7))
    simulator = Simulator(trial.diagram)
    simulator.set_target_realtime_rate(0.0)
    default = trial.diagram.CreateDefaultContext()

    def run():
        simulator.get_mutable_context().SetTimeStateAndParametersFrom(default)
        simulator.Initialize()
        context = simulator.get_mutable_context()
        while not trial.planner_system.trial_state(context).done and context.get_time() < 60.0:
            simulator.AdvanceTo(context.get_time() + 1.0)
        s = trial.planner_system.trial_state(context)
        return s.result, s.steps, s.cost, [e.get("action") for e in s.log], [e["time"] for e in s.log]

    first = run()
    assert first[0] == "revealed" and first[1] >= 1
    assert trial.planner_system.trial_state(default).log == ()  # the default context holds no trial
    assert run() == first


def test_in_camera_mode_an_exclusion_holds_while_the_estimated_object_stands_within_the_tolerance():
    """Estimated poses, and the contact points and placements named by the actions, move by millimetres from frame to
    frame: a push blocked at once (excluded with its group) was proposed again at every step to the horizon
    (Table I 10:52, depth-only with noise). Tolerant exclusions match it; exact ones keep the privileged behaviour."""
    from slax_drake.policies.protocol import Exclusions
    from slax_drake.scene.model import SceneObject, planar_pose
    from slax_drake.shelf.actions import Push, Suction

    def box(x, y, yaw=0.0):
        return SceneObject("track_3", "box", (0.1, 0.1, 0.15), planar_pose(x, y, 0.075, yaw))

    then, now, moved = (box(0.0, 0.0),), (box(0.004, -0.003, 0.02),), (box(0.03, 0.0),)
    blocked = Push("track_3", (0.05, -0.05, 0.07), 0.225)
    again = Push("track_3", (0.054, -0.053, 0.07), 0.150)  # same direction, another contact point and d
    back = Push("track_3", (-0.046, -0.053, 0.07), -0.100)
    put_back = Suction("track_3", (0.0, -0.05, 0.1), -0.2, 0.15)
    retry = Suction("track_3", (0.004, -0.053, 0.1), -0.2, 0.155)
    elsewhere = Suction("track_3", (0.004, -0.053, 0.1), -0.2, 0.25)
    exclusions = Exclusions()
    exclusions.add(blocked, "executed: moved nothing", True, then)
    exclusions.add(put_back, "executed: put back", False, then)
    candidates = [again, back, retry, elsewhere]
    assert exclusions.allowed(candidates, now) == candidates  # exact: nothing matches the new estimates
    exclusions.tolerant = True
    assert exclusions.allowed(candidates, now) == [back, elsewhere]
    assert exclusions.allowed(candidates, moved) == candidates  # the object moved 3 cm: everything may work now


def test_a_suction_lane_exclusion_refuses_every_placement_depth_at_that_dx_while_the_object_stands_there():
    """A suction that left its object where it stood failed before its placement depth mattered (way out blocked,
    outside the walls at that x, or put back at the front of the bay): with ``lane`` its object's suctions by the
    same dx are excluded at every dz, exactly and (camera mode) within the tolerances; other dx, drags and pushes
    stay allowed, and everything is allowed again once the object has moved."""
    from slax_drake.policies.protocol import Exclusions, suction_lane
    from slax_drake.scene.model import SceneObject, planar_pose
    from slax_drake.shelf.actions import Push, Suction

    def box(x, y):
        return SceneObject("track_3", "box", (0.1, 0.1, 0.15), planar_pose(x, y, 0.075, 0.0))

    then, noisy, moved = (box(0.0, 0.0),), (box(0.004, -0.003),), (box(0.05, 0.0),)
    put_back = Suction("track_3", (0.0, -0.05, 0.1), -0.1, -0.031)
    deeper = Suction("track_3", (0.0, -0.05, 0.1), -0.1, 0.069)
    shallower = Suction("track_3", (0.0, -0.05, 0.1), -0.1, -0.081)
    other_x = Suction("track_3", (0.0, -0.05, 0.1), -0.15, -0.031)
    drag = Suction("track_3", (0.0, -0.05, 0.1), -0.1, 0.069, drag=True)
    push = Push("track_3", (0.05, -0.05, 0.07), -0.1)
    assert suction_lane(push) is None and suction_lane(deeper) == suction_lane(shallower) != suction_lane(drag)
    candidates = [deeper, shallower, other_x, drag, push]

    single = Exclusions()
    single.add(put_back, "executed: moved nothing", False, then)
    assert single.allowed(candidates, then) == candidates  # only the very action: dz 0.10 m away is not it

    lane = Exclusions()
    lane.add(put_back, "executed: moved nothing", False, then, lane=True)
    assert lane.allowed(candidates, then) == [other_x, drag, push]
    assert lane.allowed(candidates, noisy) == candidates  # exact comparison: the estimate moved by 5 mm
    lane.tolerant = True
    assert lane.allowed(candidates, noisy) == [other_x, drag, push]
    assert lane.allowed(candidates, moved) == candidates
    assert lane.records == ((put_back, "executed: moved nothing"),)
