"""slax-belief-extents in camera mode: hypotheses widened along their extent range, and a partly seen target
collapsing the belief onto the placements that hold it."""

import numpy as np
import pytest

from slax_drake.policies.registry import make_policy
from slax_drake.scene import Camera
from slax_drake.scene.footprint import Footprint
from slax_drake.scene.model import Scene, Shelf, Target, planar_pose
from slax_drake.shelf.simulator import CameraObserver

from shelf_scenes import TARGET, box


def scene_of(paper, objects, target_xy=(-0.2, 0.22)):
    return Scene(Shelf(0.6, 0.6, 0.6, 0.02), Camera.from_config(paper.camera), tuple(objects),
                 Target(TARGET, planar_pose(*target_xy, 0.03, 0.0)), 7)


def observe(scene):
    return CameraObserver(scene.shelf, scene.camera, TARGET, width=160).observe(scene)[0]


def test_extents_widen_a_hidden_depth_toward_its_bound_and_contain_the_truth(paper):
    """A tall 0.16 m deep box seen face on: the observer assumes the shallow prior; the range reaches past the
    true back face, and the variant's hypothesis lies between the two, its front face where the frame shows it."""
    deep = box("deep", 0.05, 0.0, 0.12, 0.16, 0.15)
    obs = observe(scene_of(paper, [deep]))
    (h,) = obs.belief.hypotheses
    extent = h.uncertainty.extent
    assert extent.contains(Footprint.of(deep), 0.005)
    policy = make_policy("slax-belief-extents", paper, horizon=2)
    (seen,), (assumed,) = obs.known, policy.with_camera_hypotheses(obs).known
    front = lambda o: Footprint.of(o).y - Footprint.of(o).extents()[1]  # noqa: E731
    assert front(assumed) == pytest.approx(front(seen), abs=1e-9)
    assert seen.size[1] < assumed.size[1] < extent.most().half_y * 2 + 1e-9


def test_a_partly_seen_target_collapses_the_belief_onto_it(paper):
    """A wide box hides the target wholly; pushed 8 cm left, it shows half the target. Every placement the
    belief keeps then holds the seen target points, the true placement is among them; slax-belief without the
    option keeps placements far from it too."""
    hidden = observe(scene_of(paper, [box("front", 0.0, -0.05, 0.2, 0.08, 0.16)], target_xy=(0.02, 0.12)))
    assert not hidden.belief.observation.target_mask.any()
    obs = observe(scene_of(paper, [box("front", -0.08, -0.05, 0.2, 0.08, 0.16)], target_xy=(0.02, 0.12)))
    assert obs.belief.observation.target_mask.any()
    on = make_policy("slax-belief", paper, horizon=4, policy_options={"seen_target": True})
    off = make_policy("slax-belief", paper, horizon=4, policy_options={"seen_target": False})
    kept = {}
    for name, policy in (("on", on), ("off", off)):
        policy.reset(hidden)
        policy.placements(policy.with_camera_hypotheses(hidden))
        kept[name] = policy.placements(policy.with_camera_hypotheses(obs))
    assert 0 < len(kept["on"]) < len(kept["off"])
    truth = np.array([0.02, 0.12])
    assert np.min(np.hypot(*(kept["on"] - truth).T)) <= on.grid_step
    assert np.max(np.hypot(*(kept["on"] - truth).T)) <= 0.10  # within the target's size of the seen part
    assert on.consistent_placements == frozenset(on.lattice_keys(kept["on"]))
    assert on._target_seen_now and not off._target_seen_now
    assert np.max(np.hypot(*(kept["off"] - truth).T)) > 0.2
