"""slax-belief's rule for a failed placement's box (belief.py's ``blocked_rule``; ``slax-belief-v4`` sets "risk"),
and the classification of research/belief_missed_reveals.py on hand-built decisions."""

import importlib.util
import sys
from pathlib import Path

import numpy as np
import pytest

from slax_drake.shelf.actions import Suction
from slax_drake.policies.registry import make_policy
from slax_drake.scene import Camera
from slax_drake.scene.model import Scene, SceneObject, Shelf, planar_pose


def lone_block_policy(paper, rule):
    """A policy over a lone 6 cm block at the shelf's centre, with one blocked region (0.15..0.25 m in x,
    0.10..0.30 m in y) where an earlier placement failed; the suction placing the block at (0.20, 0.20) overlaps
    it (its box: 0.17..0.23 in x and y)."""
    block = SceneObject("block", "box", (0.06, 0.06, 0.10), planar_pose(0.0, 0.0, 0.05, 0.0))
    template = Scene(Shelf(0.6, 0.6, 0.6, 0.02), Camera.from_config(paper.camera), (block,), None, 3)
    policy = make_policy("slax-belief", paper, horizon=4, policy_options={"blocked_rule": rule})
    policy.reset(template)
    policy._blocked = [(0.15, 0.25, 0.10, 0.30)]
    return policy, (block,), Suction("block", (0.0, -0.03, 0.05), 0.20, 0.20)


def with_hidden(policy, centers):
    """Sets this decision's possible target placements (x, y; m), as rank() does, and clears the risk caches."""
    policy._hidden_centers = np.array(centers, dtype=float).reshape(-1, 2)
    policy._risk_by_box, policy._risk_cache = {}, {}


@pytest.mark.parametrize("rule", ["box", "hidden", "risk"])
def test_a_blocked_box_seen_since_refuses_only_under_the_box_rule(paper, rule):
    """No possible target placement near the blocked box (the camera has seen that space): "box" (the default)
    still refuses the placement; "hidden" and "risk" allow it, at the risk its box has anyway (none here)."""
    policy, objects, a = lone_block_policy(paper, rule)
    with_hidden(policy, [(-0.20, 0.20)])
    assert policy.placement_allowed(objects, a) == (rule != "box")
    assert policy.placement_risk(objects, a) == 0.0


@pytest.mark.parametrize("rule", ["box", "hidden", "risk"])
def test_a_blocked_box_still_hidden_refuses_or_adds_risk(paper, rule):
    """A possible target placement at (0.20, 0.20), inside the blocked box: "box" and "hidden" refuse the
    placement; "risk" plans it, its risk of failing raised by blocked_risk: 1 - (1 - r)(1 - 0.5)."""
    policy, objects, a = lone_block_policy(paper, rule)
    with_hidden(policy, [(0.20, 0.20), (-0.20, 0.20)])
    alone = policy.box_risk(policy.placement_box(objects, a), policy._hidden_centers)
    assert 0.0 < alone < 1.0
    assert policy.placement_allowed(objects, a) == (rule == "risk")
    expected = 1.0 - (1.0 - alone) * 0.5 if rule == "risk" else alone
    assert policy.placement_risk(objects, a) == pytest.approx(expected)


def test_a_placement_clear_of_every_blocked_box_is_unaffected(paper):
    """A placement whose box does not overlap the blocked region: allowed under every rule, risk unchanged."""
    for rule in ("box", "hidden", "risk"):
        policy, objects, _ = lone_block_policy(paper, rule)
        with_hidden(policy, [(-0.20, 0.20)])
        clear = Suction("block", (0.0, -0.03, 0.05), -0.20, 0.20)  # its box: -0.23..-0.17 in x
        risk = policy.box_risk(policy.placement_box(objects, clear), policy._hidden_centers)
        assert policy.placement_allowed(objects, clear)
        assert policy.placement_risk(objects, clear) == pytest.approx(risk) and risk > 0.0


def test_the_default_takes_the_risk_rule_and_the_earlier_default_keeps_the_box(paper):
    default = make_policy("slax-belief", paper, horizon=4)
    assert default.blocked_rule == "risk" and default.blocked_risk == 0.5 and default.dead_end == "corrections"
    earlier = make_policy("slax-belief-box", paper, horizon=4)
    assert earlier.blocked_rule == "box" and earlier.dead_end == "ignore"
    v4 = make_policy("slax-belief-v4", paper, horizon=4)
    assert v4.blocked_rule == "risk" and v4.blocked_risk == 0.5 and v4.dead_end == "ignore"
    with pytest.raises(ValueError, match="blocked_rule"):
        make_policy("slax-belief", paper, horizon=4, policy_options={"blocked_rule": "never"})
    with pytest.raises(ValueError, match="blocked_risk"):
        make_policy("slax-belief", paper, horizon=4, policy_options={"blocked_risk": 1.5})


# ---- research/belief_missed_reveals.py's classification ------------------------------------------------------
def missed_reveals():
    path = Path(__file__).resolve().parents[2] / "research" / "belief_missed_reveals.py"
    spec = importlib.util.spec_from_file_location("research_belief_missed_reveals", path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # its dataclass resolves its annotations through sys.modules
    spec.loader.exec_module(module)
    return module


def probe(m, **changes):
    """A decision where the oracle's one-move plan was looked at and ranks below the chosen plan (R / G 0.05
    against 0.1), with no placement risk; ``changes`` override fields."""
    base = dict(step=0, truth_kept=True, truth_near=4, truth_weight=1.0, oracle_plan=["suction a dx=+0.050 dz=+0.100"],
                oracle_status="optimal", first_status="first level", in_search=True, oracle_r=0.065, oracle_g=1.3,
                oracle_r_norisk=0.065, chosen_plan=["push b d=+0.100"], chosen_r=0.1, chosen_g=1.0)
    base.update(changes)
    return m.Probe(**base)


def test_missed_reveals_classifies_hand_built_decisions():
    m = missed_reveals()
    assert m.classify(probe(m)) == ("ranked below", "less R / G")
    assert m.classify(probe(m, oracle_plan=None))[0] == "oracle found no plan"
    assert m.classify(probe(m, truth_kept=False, truth_near=0))[0] == "truth left the belief"
    assert m.classify(probe(m, truth_kept=False, truth_near=2)) == ("ranked below", "less R / G")  # a neighbour kept
    assert m.classify(probe(m, first_status="placement in a blocked region")) == \
        ("not a candidate", "placement in a blocked region")
    assert m.classify(probe(m, first_status="pruned: placements_per_object", oracle_r=0.2)) == \
        ("not a candidate", "pruned: placements_per_object; would win")
    assert m.classify(probe(m, plan_unseen=True))[0] == "not a candidate"
    assert m.classify(probe(m, oracle_r=0.05, oracle_r_norisk=0.2)) == ("risk penalty", "")  # 0.15 > 0.1 with no risk
    assert m.classify(probe(m, in_search=False, oracle_r=0.2, oracle_r_norisk=0.2)) == \
        ("ranked below", "by the beam's V, not looked at; would win")
    assert m.classify(probe(m, oracle_r=0.2, oracle_r_norisk=0.2))[0] == "other"
    assert m.classify(probe(m, oracle_r=0.0, oracle_r_norisk=0.0, chosen_r=0.0)) == \
        ("ranked below", "less R / G (reveals no sampled world)")
    assert m.main_cause(["oracle found no plan", "ranked below", "not a candidate", "not a candidate"]) == \
        "not a candidate"
    assert m.main_cause(["ranked below", "not a candidate"]) == "not a candidate"  # a tie: the first in CAUSES
    assert m.main_cause(["oracle found no plan"]) == "oracle found no plan"


def test_missed_reveals_refuses_a_malformed_trial(capsys):
    assert missed_reveals().main(["10-9"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("error: ")
