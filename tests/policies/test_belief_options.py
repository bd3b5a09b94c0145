"""slax-belief's options are one frozen dataclass: the registry's variants are named replacements of the defaults,
a run's settings record what differs from the defaults, and command-line overrides replace fields."""

import dataclasses

import pytest

from slax_drake.evaluation.settings import policy_settings
from slax_drake.policies.belief_options import DEFAULT_BELIEF_OPTIONS, BeliefOptions
from slax_drake.policies.registry import POLICY_TABLE, make_policy


def test_every_field_is_documented_and_the_options_are_frozen():
    with pytest.raises(dataclasses.FrozenInstanceError):
        DEFAULT_BELIEF_OPTIONS.beam = 3
    assert DEFAULT_BELIEF_OPTIONS == BeliefOptions() and DEFAULT_BELIEF_OPTIONS.changed() == {}
    import ast
    import inspect

    from slax_drake.policies import belief_options

    body = next(n for n in ast.parse(inspect.getsource(belief_options)).body
                if isinstance(n, ast.ClassDef) and n.name == "BeliefOptions").body
    documented = {a.target.id for a, d in zip(body, body[1:]) if isinstance(a, ast.AnnAssign)
                  and isinstance(d, ast.Expr) and isinstance(d.value, ast.Constant)}
    assert documented == {f.name for f in dataclasses.fields(BeliefOptions)}


def test_the_registry_variants_are_named_replacements_recorded_as_before():
    assert POLICY_TABLE["slax-belief"].options is DEFAULT_BELIEF_OPTIONS
    settings = policy_settings(["slax-belief", "slax-belief-box", "slax-belief-v4", "slax-belief-camera-depth",
                                "slax-belief-dead-end-risk", "slax-belief-no-camera-memory",
                                "slax-belief-camera-memory", "slax-belief-axis-shuttle"])
    assert settings["slax-belief"]["options"] == {} == settings["slax-belief-camera-memory"]["options"]
    # the variants measured against an earlier default keep its options, recorded as differences from today's
    at_2100fd5 = {"camera_memory": False}
    assert settings["slax-belief-dead-end-risk"]["options"] == at_2100fd5 == settings[
        "slax-belief-no-camera-memory"]["options"]
    assert settings["slax-belief-axis-shuttle"]["options"] == {**at_2100fd5, "shuttle_by_axis": True}
    earlier = {**at_2100fd5, "dead_end": "ignore", "blocked_rule": "box"}
    assert settings["slax-belief-box"]["options"] == earlier
    assert settings["slax-belief-v4"]["options"] == {**at_2100fd5, "dead_end": "ignore"}
    assert settings["slax-belief-camera-depth"]["options"] == {"dead_end": "ignore", "blocked_rule": "box",
                                                               "camera_depth": 0.13, "camera_outcome_tolerance": 0.01,
                                                               "seen_target": False}
    assert settings["slax-belief"]["class"] == "slax_drake.policies.belief:BeliefSearch"


def test_a_policy_gets_its_variant_with_overrides_replaced(paper):
    policy = make_policy("slax-belief-v4", paper, horizon=6, policy_options={"beam": 3, "horizon": 2})
    assert policy.options == dataclasses.replace(DEFAULT_BELIEF_OPTIONS, dead_end="ignore", camera_memory=False,
                                                 beam=3)
    assert policy.beam == 3 and policy.blocked_rule == "risk" and policy.horizon == 2
    assert make_policy("slax-belief", paper).options == DEFAULT_BELIEF_OPTIONS


def test_the_no_shuttle_rule_variant_turns_the_correction_off_and_a_negative_width_is_refused(paper):
    assert make_policy("slax-belief", paper).shuttle_reveal == 0.02
    assert make_policy("slax-belief-no-shuttle-rule", paper).shuttle_reveal is None
    assert policy_settings(["slax-belief-no-shuttle-rule"])["slax-belief-no-shuttle-rule"]["options"] == {
        "camera_memory": False, "dead_end": "ignore", "blocked_rule": "box", "shuttle_reveal": None}
    with pytest.raises(ValueError, match="shuttle_reveal"):
        BeliefOptions(shuttle_reveal=-0.01)
