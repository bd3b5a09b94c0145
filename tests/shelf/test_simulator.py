"""The first-order shelf simulator never creates overlaps, and stops on the target's visibility."""

import numpy as np
from hypothesis import example, given, settings, strategies as st

from slax_drake.shelf.actions import Push, Suction
from slax_drake.policies.registry import make_policy
from slax_drake.shelf.simulator import execute, objects_overlap
from slax_drake.scene import sample_scene
from slax_drake.scene.footprint import Footprint, inside_shelf
from slax_drake.scene.model import SceneObject, planar_pose


@settings(max_examples=12, deadline=None, derandomize=True)
@given(seed=st.integers(0, 10_000), n=st.sampled_from([4, 6, 8]))
@example(seed=56, n=4)  # a placement stopped by the unseen target at the opening left the object hanging out
def test_random_rollouts_never_overlap(sim_scenario, seed, n):
    scene = sample_scene(sim_scenario, n, seed, target_size=(0.06, 0.06, 0.06))
    model = make_policy("oracle-p+s", sim_scenario).action_model
    rng = np.random.default_rng(seed)
    clearance = model.tool.physics.clearance
    assert objects_overlap(scene, clearance - 1e-9) == []
    for _ in range(5):
        feasible = model.enumerate(scene.objects).feasible  # full state: sometimes moves beside the target
        if not feasible:
            break
        scene, _ = execute(scene, feasible[int(rng.integers(len(feasible)))], model)
        assert objects_overlap(scene, clearance - 1e-9) == []
        for o in scene.objects:
            assert inside_shelf(Footprint.of(o), scene.shelf, clearance - 1e-9)


def test_unseen_obstacle_stops_a_push(sim_scenario):
    scene = sample_scene(sim_scenario, 4, 1, target_size=(0.06, 0.06, 0.06))
    model = make_policy("oracle-p", sim_scenario).action_model
    box = SceneObject("a", "box", (0.08, 0.08, 0.1), planar_pose(-0.15, -0.2, 0.05, 0.0))
    wall = SceneObject("b", "box", (0.08, 0.08, 0.1), planar_pose(0.05, -0.2, 0.05, 0.0))
    s = scene.with_objects((box, wall))
    s = s.__class__(s.shelf, s.camera, s.objects, None, 0)
    moved, note = execute(s, Push("a", (-0.2225, -0.21, 0.0375), 0.30), model)
    assert "unseen obstacle" in note
    assert objects_overlap(moved, model.tool.physics.clearance - 1e-9) == []
    assert moved.objects[0].center[0] > -0.15


def test_suction_moves_the_object_to_its_placement(sim_scenario):
    scene = sample_scene(sim_scenario, 4, 1, target_size=(0.06, 0.06, 0.06))
    model = make_policy("oracle-p+s", sim_scenario).action_model
    sucs = [a for a in model.enumerate(scene.objects, fixed=(scene.target.as_object(),)).feasible
            if isinstance(a, Suction)]
    assert sucs
    a = sucs[0]
    after, note = execute(scene, a, model)
    assert note == ""
    o0 = scene.object_named(a.name)
    o1 = after.object_named(a.name)
    assert np.allclose(o1.center[:2], (o0.center[0] + a.dx, a.dz))


def test_a_placement_over_a_low_object_backs_out_to_the_last_landing_spot(sim_scenario):
    """The way in passes over a low object and is stopped by a tall one behind it; lowered anywhere over the low
    one the object would land on it, so it backs out to the nearest spot before it, within one grid step."""
    scene = sample_scene(sim_scenario, 4, 1, target_size=(0.06, 0.06, 0.06))
    model = make_policy("oracle-p+s", sim_scenario).action_model
    moved = SceneObject("a", "box", (0.06, 0.06, 0.10), planar_pose(-0.15, -0.10, 0.05, 0.0))
    low = SceneObject("low", "box", (0.08, 0.08, 0.03), planar_pose(0.15, 0.0, 0.015, 0.0))
    height = 0.9 * scene.shelf.height
    tall = SceneObject("tall", "box", (0.10, 0.06, height), planar_pose(0.15, 0.12, height / 2, 0.0))
    s = scene.with_objects((moved, low, tall))
    s = s.__class__(s.shelf, s.camera, s.objects, None, 0)
    assert model.passes_over(moved, 0.03) and not model.passes_over(moved, height)
    after, note = execute(s, Suction("a", (-0.15, -0.13, 0.05), 0.30, 0.15), model)
    assert note == "placement stopped early by an unseen obstacle"
    end = after.object_named("a")
    clearance, cell = model.tool.physics.clearance, model.tool.grid.cell
    assert objects_overlap(after, clearance - 1e-9) == []
    assert abs(end.center[0] - 0.15) < 1e-12
    in_front_of_low = -0.04 - 0.03 - clearance  # the largest y where it stands clear of the low object
    assert in_front_of_low - cell - 1e-9 <= end.center[1] <= in_front_of_low + 1e-9


def test_a_step_note_splits_back_into_its_step_and_text():
    from slax_drake.shelf.simulator import split_note, step_note

    note = step_note(4, "push stopped after -0.085 m by an unseen obstacle: 12 s")
    assert note == "step 4: push stopped after -0.085 m by an unseen obstacle: 12 s"
    assert split_note(note) == (4, "push stopped after -0.085 m by an unseen obstacle: 12 s")
    assert split_note("stopped: no feasible action") == (None, "stopped: no feasible action")
    assert split_note("step x: text") == (None, "step x: text")
