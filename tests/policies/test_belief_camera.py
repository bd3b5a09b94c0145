"""slax-belief in camera mode (issue 16, camera-mode drop): the hypotheses' assumed unseen depth
(``camera_depth``), the memory of hypotheses hidden now (``camera_memory``: matched across frames by where they
stand, never acted on) and the outcome evidence's tolerance on estimated poses; the privileged path is untouched."""

import numpy as np
import pytest

from slax_drake.shelf.actions import Push, Suction
from slax_drake.policies.belief import REMEMBERED
from slax_drake.policies.registry import make_policy
from slax_drake.shelf.simulator import CameraObserver, observation_for
from slax_drake.scene import Camera
from slax_drake.scene.footprint import Footprint
from slax_drake.scene.model import Scene, Shelf, Target, planar_pose

from shelf_scenes import TARGET, box


def scene_of(paper, objects):
    return Scene(Shelf(0.6, 0.6, 0.6, 0.02), Camera.from_config(paper.camera), tuple(objects),
                 Target(TARGET, planar_pose(-0.2, 0.22, 0.03, 0.0)), 7)


def observer(scene):
    return CameraObserver(scene.shelf, scene.camera, TARGET, width=160)


def test_camera_depth_makes_every_box_hypothesis_at_least_that_deep(paper):
    """A 0.16 m deep box seen face on and from above its far edge is not seen: the observer's hypothesis is as
    deep as the part the frame shows (at least the smallest depth, 0.06 m); with ``camera_depth`` 0.13 the
    policy's is 0.13 m deep, its front face where the frame shows it."""
    scene = scene_of(paper, [box("deep", 0.05, 0.0, 0.12, 0.16, 0.15)])
    obs, _ = observer(scene).observe(scene)
    policy = make_policy("slax-belief", paper, horizon=2, policy_options={"camera_depth": 0.13})
    deeper = policy.with_camera_hypotheses(obs)
    (seen,), (assumed,) = obs.known, deeper.known
    assert seen.name == assumed.name and deeper.belief.known == deeper.known
    front = lambda o: Footprint.of(o).y - Footprint.of(o).extents()[1]  # noqa: E731
    assert 0.06 - 1e-9 <= seen.size[1] < 0.12 and assumed.size[1] == pytest.approx(0.13, abs=0.002)
    assert front(assumed) == pytest.approx(front(seen), abs=1e-9)
    assert deeper.scene_template.objects == deeper.known
    np.testing.assert_array_equal(deeper.p1d, obs.p1d)
    as_seen = make_policy("slax-belief", paper, horizon=2, policy_options={"camera_depth": None})
    assert as_seen.with_camera_hypotheses(obs) is obs


def test_camera_options_leave_a_privileged_observation_alone(paper):
    scene = scene_of(paper, [box("deep", 0.05, 0.0, 0.12, 0.16, 0.15)])
    policy = make_policy("slax-belief", paper, horizon=2, policy_options={"camera_depth": 0.13,
                                                                          "camera_memory": True})
    policy.reset(scene)
    obs = observation_for(policy, scene)
    assert obs.belief is None and policy.with_camera_hypotheses(obs) is obs


def _hidden_after_push(paper):
    """A tall wide box beside a small one; pushing the tall one in front of the small one hides it wholly."""
    small = box("small", 0.0, 0.05, 0.10, 0.08, 0.12)
    tall = box("tall", 0.2, -0.2, 0.26, 0.06, 0.40)
    return scene_of(paper, [small, tall]), scene_of(paper, [small, tall.moved_to(0.0, -0.2)])


def _remembering_policy(paper):
    """The two frames of :func:`_hidden_after_push`'s scene, the observer, its first frame and names, and a
    slax-belief with ``camera_memory`` that has read that frame (``seen``)."""
    before, after = _hidden_after_push(paper)
    cam = observer(before)
    first, names = cam.observe(before)
    policy = make_policy("slax-belief", paper, horizon=4, policy_options={"camera_memory": True})
    policy.reset(first)
    seen = policy.with_remembered(first)
    return before, after, cam, first, names, {v: k for k, v in names.items()}, policy, seen


def test_camera_memory_keeps_an_untouched_hypothesis_that_a_move_hid(paper):
    before, after, cam, first, names, inverse, policy, seen = _remembering_policy(paper)
    assert {names[o.name] for o in seen.known} == {"small", "tall"}
    policy._executed = (Push(inverse["tall"], (0.2, -0.23, 0.05), -0.2), seen.known)
    second, names2 = cam.observe(after)
    assert set(names2.values()) == {"tall"}  # the small box is hidden now
    kept = policy.with_remembered(second)
    remembered = [o for o in kept.known if o.name.startswith(REMEMBERED)]
    assert len(remembered) == 1 and len(kept.known) == 2
    assert [o.name for o in kept.known if o.remembered] == [remembered[0].name]  # the typed flag decides
    small_then = next(o for o in seen.known if names[o.name] == "small")
    assert np.array_equal(remembered[0].center, small_then.center) and remembered[0].size == small_then.size
    assert remembered[0] in kept.scene_template.objects
    # an obstacle, never acted on: the camera shows no segment of it
    actions = policy.action_model.enumerate(kept.known).feasible
    assert actions and all(not a.name.startswith(REMEMBERED) for a in actions)
    moves = policy.moves(kept.known)
    assert moves and all(not a.name.startswith(REMEMBERED) for a, _, _ in moves)
    # the privileged-mode switch alone does not remember in camera mode (the behaviour before camera_memory)
    old = make_policy("slax-belief", paper, horizon=4, policy_options={"camera_memory": False})
    old.reset(first)
    old.with_remembered(first)
    old._executed = policy._executed
    assert old.with_remembered(second) is second


def test_camera_memory_forgets_the_moved_hypothesis_and_one_the_frame_sees_through(paper):
    before, after, cam, first, names, inverse, policy, seen = _remembering_policy(paper)
    # the small box was the one moved (here: taken away): not remembered
    policy._executed = (Suction(inverse["small"], (0.0, 0.01, 0.06), 0.0, 0.2), seen.known)
    gone = scene_of(paper, [o for o in before.objects if o.name != "small"])
    frame = cam.observe(gone)[0]
    assert [o.name for o in policy.with_remembered(frame).known] == [o.name for o in frame.known]
    # untouched but the frame shows the floor where it was believed to stand: not remembered either
    policy._remembered = {o.name: o for o in seen.known}
    policy._executed = (Push(inverse["tall"], (0.2, -0.23, 0.05), 0.02), seen.known)
    assert all(not o.name.startswith(REMEMBERED) for o in policy.with_remembered(frame).known)


def test_camera_outcome_tolerance_reads_an_estimated_pose_6_mm_off_as_a_completed_push(paper):
    """A push that went as planned, its object seen 6 mm short of where the seen objects predict (an estimated
    pose): within camera_outcome_tolerance (1 cm) on a camera frame it proves the path clear (the placements in it
    leave the belief); on exact poses (3 mm; a privileged observation, or the registry's slax-belief) it reads as a
    push stopped by something unseen."""
    block = box("block", 0.0, 0.0, 0.06, 0.06, 0.10)
    template = Scene(Shelf(0.6, 0.6, 0.6, 0.02), Camera.from_config(paper.camera), (block,), None, 3)
    stopped = {}
    for name, camera in (("slax-belief-camera-depth", True), ("slax-belief-camera-depth", False),
                         ("slax-belief", True)):
        policy = make_policy(name, paper, horizon=4)
        policy.reset(template)
        policy._consistent = {(8, 0), (10, 0), (12, 0), (-20, 20)}
        policy._template = template
        policy._camera_mode = camera
        policy._executed = (Push("block", (-0.04, -0.03, 0.05), 0.15), (block,))
        policy.condition_on_outcome((block.moved_to(0.144, 0.0),))  # 0.15 planned, 0.144 estimated
        stopped[name, camera] = (policy.evidence_log[-1]["stopped"], policy._consistent)
    assert stopped["slax-belief-camera-depth", True] == (False, {(-20, 20)})
    assert stopped["slax-belief-camera-depth", False][0] is True and stopped["slax-belief", True][0] is True


def test_camera_options_reject_values_out_of_range(paper):
    with pytest.raises(ValueError):
        make_policy("slax-belief", paper, horizon=2, policy_options={"camera_outcome_tolerance": 0.0})
    with pytest.raises(ValueError):
        make_policy("slax-belief", paper, horizon=2, policy_options={"camera_depth": -0.1})


def test_maybe_occupied_keeps_placements_in_the_assumed_depth_at_a_lower_weight(paper):
    """Behind a box whose far part the frame does not show: with ``camera_depth`` alone the target's placements
    there are excluded (the deeper hypothesis fills them); with ``maybe_occupied`` they stay possible, and only
    those weigh ``maybe_occupied`` in the draw of the worlds."""
    scene = scene_of(paper, [box("deep", 0.0, -0.1, 0.30, 0.16, 0.30)])
    obs, _ = observer(scene).observe(scene)
    (seen,) = obs.known
    probe = (0.0, round((Footprint.of(seen).y + Footprint.of(seen).extents()[1] + 0.04) / 0.01) * 0.01)
    found = {}
    for weight in (None, 0.5):
        policy = make_policy("slax-belief", paper, horizon=2, policy_options={"camera_depth": 0.13,
                                                                              "maybe_occupied": weight})
        policy.reset(obs)
        policy._camera_mode = True
        deeper = policy.with_camera_hypotheses(obs)
        placements = policy.placements(deeper)
        keys = {(int(round(x / 0.01)), int(round(y / 0.01))) for x, y in placements}
        found[weight] = (keys, set(policy._maybe))
    probe_key = (int(round(probe[0] / 0.01)), int(round(probe[1] / 0.01)))
    assert probe_key not in found[None][0] and not found[None][1]
    assert probe_key in found[0.5][0] and probe_key in found[0.5][1]
    assert found[None][0] < found[0.5][0] and found[0.5][1] == found[0.5][0] - found[None][0]
    with pytest.raises(ValueError):
        make_policy("slax-belief", paper, horizon=2, policy_options={"maybe_occupied": 1.5})


def test_privileged_trials_do_not_read_the_camera_options(paper):
    """The registry's slax-belief-camera-depth (camera options on) and slax-belief (off) take the same actions on a
    privileged trial and log the same decisions: none of the options is read without a camera frame."""
    from slax_drake.shelf.simulator import run_trial
    from slax_drake.scene.sampling import sample_scene

    scene = sample_scene(paper, 6, 11, target_size=TARGET)
    runs = {}
    for name in ("slax-belief-camera-depth", "slax-belief"):
        policy = make_policy(name, paper, horizon=4)
        runs[name] = (run_trial(scene, policy, 4).actions, policy.decision_log)
    assert runs["slax-belief"][0] and runs["slax-belief"][0] == runs["slax-belief-camera-depth"][0]
    strip = lambda logs: [{k: v for k, v in log.items() if k != "seconds"} for log in logs]  # noqa: E731
    assert strip(runs["slax-belief"][1]) == strip(runs["slax-belief-camera-depth"][1])
    on = make_policy("slax-belief-camera-depth", paper, horizon=4)
    assert on.camera_depth == 0.13 and on.camera_memory and on.camera_outcome_tolerance == 0.01
