"""slax-belief's camera-mode options ``aim_visible`` (no action on a hypothesis whose segment shows no cup-sized
patch) and ``deepen_failed`` (an object whose placement failed is assumed as deep as the frame allows)."""

import dataclasses

import pytest

from slax_drake.policies.registry import make_policy
from slax_drake.scene import Camera
from slax_drake.scene.model import Scene, Shelf, Target, planar_pose
from slax_drake.shelf.simulator import CameraObserver

from shelf_scenes import TARGET, box


def _observe(paper, objects):
    scene = Scene(Shelf(0.6, 0.6, 0.6, 0.02), Camera.from_config(paper.camera), tuple(objects),
                  Target(TARGET, planar_pose(0.2, 0.22, 0.03, 0.0)), 7)
    obs, names = CameraObserver(scene.shelf, scene.camera, TARGET, width=160).observe(scene)
    return scene, obs, names


def _sliver_scene(paper):
    """A wide box in front and, behind it, a box 1 cm taller: the frame shows the far box only as a strip of its
    top above the near one."""
    return [box("near", -0.05, -0.15, 0.30, 0.10, 0.20), box("far", -0.05, 0.12, 0.20, 0.12, 0.21),
            box("free", 0.22, -0.15, 0.08, 0.08, 0.15)]


def test_aim_visible_takes_no_action_on_a_sliver_and_keeps_it_an_obstacle(paper):
    scene, obs, names = _observe(paper, _sliver_scene(paper))
    by_true = {names[h.object.name]: h for h in obs.belief.hypotheses}
    assert set(by_true) == {"near", "far", "free"}
    sliver = by_true["far"].object.name
    policy = make_policy("slax-belief", paper, horizon=4, policy_options={"aim_visible": True})
    policy.reset()
    unaimable = policy.unaimable(obs)
    assert unaimable == {sliver}, (unaimable, {n: h.pixels for n, h in by_true.items()})
    decision = policy.decide(obs)
    assert decision.candidates and all(a.name != sliver for a in decision.candidates)
    feasible = policy.action_model.enumerate(obs.known).feasible
    assert feasible and all(a.name != sliver for a in feasible)
    assert sliver in {o.name for o in obs.known}  # still an obstacle of the plans
    plain = make_policy("slax-belief", paper, horizon=4)
    plain.reset()
    plain.decide(obs)
    assert any(a.name == sliver for a in plain.action_model.enumerate(obs.known).feasible)


def test_deepen_failed_assumes_the_object_of_a_failed_placement_as_deep_as_the_frame_allows(paper):
    """A 0.16 m deep box seen face on: its hypothesis is as deep as the frame shows. After a suction of it whose
    placement failed (the next frame shows it where it was), the policy plans on it deeper, its front face kept."""
    scene, obs, names = _observe(paper, [box("deep", 0.05, 0.0, 0.12, 0.16, 0.15)])
    (seen,) = obs.known
    policy = make_policy("slax-belief", paper, horizon=4, policy_options={"deepen_failed": True})
    policy.reset()
    assert policy.with_camera_hypotheses(obs) is obs  # nothing failed yet
    policy._camera_mode = True
    policy._last = ((-0.2, -0.08, -0.05, 0.05), seen.name)  # the placement box the suction predicted
    policy.note_outcome(obs.known)  # the object stands where it stood: the placement failed
    deeper = policy.with_camera_hypotheses(obs)
    (assumed,) = deeper.known
    assert assumed.name == seen.name
    assert assumed.size[1] > seen.size[1] + 0.05
    front = lambda o: o.center[1] - o.size[1] / 2  # noqa: E731 (square to the walls)
    assert front(assumed) == pytest.approx(front(seen), abs=0.005)
    off = make_policy("slax-belief", paper, horizon=4)
    off.reset()
    off._camera_mode = True
    off._last = ((-0.2, -0.08, -0.05, 0.05), seen.name)
    off.note_outcome(obs.known)
    assert off.with_camera_hypotheses(obs) is obs


def test_put_back_group_excludes_the_objects_other_suctions_after_one_left_it_in_place(paper):
    """Camera mode with ``put_back_group``: a suction after which the object stands where it stood (put back)
    excludes that object's other suctions while it stands there; by default only that suction is excluded."""
    from slax_drake.shelf.actions import Suction

    scene, obs, names = _observe(paper, [box("deep", 0.05, 0.0, 0.12, 0.16, 0.15)])
    (seen,) = obs.known
    tried = Suction(seen.name, (0.05, -0.08, 0.1), -0.2, -0.15)
    other = Suction(seen.name, (0.05, -0.08, 0.1), 0.15, 0.1)
    outcome = {}
    for option in (True, False):
        policy = make_policy("slax-belief", paper, horizon=4, policy_options={"put_back_group": option})
        policy.reset()
        policy._exclusions.tolerant = True  # as decide() sets it on a camera frame
        policy.memory.propose(tried, obs.known)
        policy.learn(obs)  # the next frame shows the object where it stood
        assert [a for a, _ in policy.exclusions] == [tried]
        outcome[option] = policy._exclusions.allowed([tried, other], obs.known)
    assert outcome == {True: [], False: [other]}


def _put_back_scene():
    """A 0.16 m deep box seen face on (its hypothesis as deep as the frame shows) and, to its left, a box standing
    0.11 m behind the shelf's front, too tall to be passed over: carried over there, the deep box cannot get past
    that box's front face before it is inside the bay (put back), where its hypothesis would fit in front of it."""
    return [box("deep", 0.05, 0.0, 0.12, 0.16, 0.25), box("front", -0.18, -0.15, 0.10, 0.08, 0.45)]


@pytest.mark.parametrize("rule", ["carried", "any"])
def test_explain_failed_assumes_the_least_share_of_the_extent_range_that_explains_a_put_back(paper, rule):
    from slax_drake.shelf.actions import Suction
    from slax_drake.shelf.simulator import PUT_BACK, execute

    scene, obs, names = _observe(paper, _put_back_scene())
    by_true = {names[o.name]: o for o in obs.known}
    seen = by_true["deep"]
    suction = Suction(seen.name, (0.05, -0.08, 0.1), -0.23, 0.1)
    policy = make_policy("slax-belief", paper, horizon=4, policy_options={"explain_failed": rule})
    truth = scene.with_objects(tuple(dataclasses.replace(o, name=next(h for h, t in names.items() if t == o.name))
                                     for o in scene.objects))
    assert execute(truth, suction, policy.action_model)[1] == PUT_BACK  # the true object is put back
    placed, _ = execute(obs.scene_template.with_objects(obs.known), suction, policy.action_model)
    assert placed.object_named(seen.name).center[0] != seen.center[0]  # its hypothesis would have been placed
    policy.reset()
    policy._camera_mode = True
    policy._template = obs.scene_template
    policy._last = (policy.placement_box(obs.known, suction), seen.name)
    policy._executed = (suction, tuple(obs.known))
    policy.explain_put_back(obs)  # the next frame shows it where it stood
    assert policy._explained is not None and policy._explained[0] == seen.name
    share = policy._explained[1]
    assert share < 1.0  # the least share that explains it, not the farthest
    assumed = next(o for o in policy.with_camera_hypotheses(obs).known if o.name == seen.name)
    assert assumed.size[1] > seen.size[1] + 0.03
    put_back, _ = execute(obs.scene_template.with_objects(
        tuple(assumed if o.name == seen.name else o for o in obs.known)), suction, policy.action_model)
    assert put_back.object_named(seen.name).center[0] == pytest.approx(seen.center[0])  # explained
    assert policy._deepened == {seen.name: share}


def test_explain_failed_changes_nothing_when_the_cause_is_not_in_the_frame(paper):
    """The same put-back seen without the box that caused it (it is not in the frame): no share of the carried
    object's range explains it (a share that would also block the way out or in on its own is not this case)."""
    from slax_drake.shelf.actions import Suction

    scene, obs, names = _observe(paper, _put_back_scene()[:1])
    (seen,) = obs.known
    suction = Suction(seen.name, (0.05, -0.08, 0.1), -0.23, 0.1)
    policy = make_policy("slax-belief", paper, horizon=4, policy_options={"explain_failed": "any"})
    policy.reset()
    policy._camera_mode = True
    policy._template = obs.scene_template
    policy._last = (policy.placement_box(obs.known, suction), seen.name)
    policy._executed = (suction, tuple(obs.known))
    policy.explain_put_back(obs)
    assert policy._explained is None and policy._deepened == {}
    assert policy.with_camera_hypotheses(obs) is obs
