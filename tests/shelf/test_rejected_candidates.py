"""The action model's rejected candidates say which object and which push direction they are, as fields: the
action checker finds an object's refusals by them, not by reading the description."""

from slax_drake.config import load_scenario
from slax_drake.policies.registry import make_policy
from slax_drake.scene.sampling import sample_scene


def test_each_rejected_candidate_names_its_object_and_direction():
    paper = load_scenario("sim_configs/table1.yaml")
    scene = sample_scene(paper, 8, 3, target_size=(0.06, 0.06, 0.06))
    model = make_policy("dar", paper, horizon=2).action_model
    rejected = model.enumerate(scene.objects).rejected
    assert rejected
    names = {o.name for o in scene.objects}
    for r in rejected:
        assert r.object_name in names
        if r.direction:
            assert r.what.split()[:3] == ["push", r.object_name, "+x" if r.direction > 0 else "-x"]
        else:
            assert r.what.split()[:2] == ["suction", r.object_name]
    only = model.enumerate(scene.objects, only={rejected[0].object_name}).rejected
    assert only and {r.object_name for r in only} == {rejected[0].object_name}


def test_every_rejected_candidate_has_a_typed_kind():
    """Each refusal says why as a RefusalKind, under the paper's and the station's rules (reach map included)."""
    from slax_drake.shelf.actions import RefusalKind

    for config, tool_rules in (("sim_configs/table1.yaml", None),
                               ("sim_configs/table1.yaml", {"profile": "station", "reach_map": "models/reach/station_sim_shelf.json",
                                                            "max_seal_angle_deg": 10.0, "max_suction_moment": 0.4})):
        paper = load_scenario(config)
        kinds = set()
        for seed in range(3):
            scene = sample_scene(paper, 10, seed, target_size=(0.06, 0.06, 0.06))
            rules = dict(tool_rules or {})
            profile = rules.pop("profile", None)
            model = make_policy("dar", paper, horizon=2, profile=profile, tool_overrides=rules).action_model
            for r in model.enumerate(scene.objects).rejected:
                assert isinstance(r.kind, RefusalKind), r
                kinds.add(r.kind)
        assert len(kinds) >= 2
