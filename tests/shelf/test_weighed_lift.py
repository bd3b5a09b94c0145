"""A lift weighed at the cup in the shelf simulator: an object that hangs more off the cup than the lift was
planned for is put back where it stood, and the camera mode's tracker reckons it with the weighed mass from then
on, so that the action model drags it instead (the Drake trial's weighing: tests/systems/test_weigh.py)."""

import dataclasses

import pytest

from slax_drake.scene.camera import Camera
from slax_drake.scene.model import Scene, SceneObject, planar_pose
from slax_drake.scene.sampling import shelf_of
from slax_drake.shelf.actions import GRAVITY, ActionModel, Suction
from slax_drake.shelf.simulator import WEIGHED_PUT_BACK, CameraObserver, execute
from slax_drake.shelf.tool import tool_config


def _scene(sim_scenario, mass):
    box = SceneObject("object_0", "box", (0.08, 0.16, 0.10), planar_pose(0.0, -0.12, 0.05, 0.0), mass=mass)
    return Scene(shelf_of(sim_scenario), Camera.from_config(sim_scenario.camera), (box,), None, 0)


@pytest.fixture(scope="module")
def model(sim_scenario):
    tool = tool_config(sim_scenario, "station", max_suction_moment=0.4, drag_grasp=True)
    return ActionModel(shelf_of(sim_scenario), Camera.from_config(sim_scenario.camera).position, tool)


def test_a_lift_heavier_than_planned_is_put_back_and_a_light_one_is_carried(sim_scenario, model):
    lift = Suction("object_0", (0.0, -0.20, 0.05), 0.15, -0.10)  # the contact 8 cm in front of the centre
    heavy = _scene(sim_scenario, 0.6)  # 0.6 x 9.81 x 0.08 = 0.47 N m > 0.4
    after, note = execute(heavy, lift, model)
    assert after is heavy and note.startswith(WEIGHED_PUT_BACK) and "0.47 N m" in note
    light = _scene(sim_scenario, 0.4)  # 0.31 N m
    after, note = execute(light, lift, model)
    assert note == "" and after.objects[0].center[0] == pytest.approx(0.15)


def test_the_camera_mode_tracker_takes_the_weighed_mass_and_the_lift_is_refused_then(sim_scenario, model):
    scene = _scene(sim_scenario, 0.6)
    observer = CameraObserver(scene.shelf, scene.camera, (0.05, 0.05, 0.10), source="depth", width=160)
    observer.start()
    observation, names = observer.observe(scene)
    (hyp,) = observation.known
    assert hyp.mass is None and names == {hyp.name: "object_0"}
    lifts = [a for a in model.enumerate(observation.known, pushes=False).feasible if not a.drag]
    assert lifts  # the median mass of its class hangs under the limit at the believed lever
    observer.executed(lifts[0])
    observer.weighed(lifts[0], observation.known, scene.objects[0], model)
    again, _ = observer.observe(scene)
    (weighed,) = again.known
    lever = ((hyp.center[0] - lifts[0].q[0]) ** 2 + (hyp.center[1] - lifts[0].q[1]) ** 2) ** 0.5
    true_moment = 0.6 * GRAVITY * (scene.objects[0].center[1] - lifts[0].q[1])
    assert weighed.mass == pytest.approx(max(0.6, true_moment / (GRAVITY * lever)))
    assert model.held_moment(weighed, lifts[0].q[:2]) == pytest.approx(max(true_moment, 0.6 * GRAVITY * lever))
    assert not [a for a in model.enumerate(again.known, pushes=False).feasible if not a.drag]


@pytest.fixture(scope="module")
def model_dragging(sim_scenario):
    tool = tool_config(sim_scenario, "station", max_suction_moment=0.4, drag_grasp=True, max_drag_pull=42.412)
    return ActionModel(shelf_of(sim_scenario), Camera.from_config(sim_scenario.camera).position, tool)


def _lift_to(model, objects, dx, dz):
    return next(a for a in model.enumerate(objects, pushes=False).feasible
                if not a.drag and a.dx == pytest.approx(dx) and a.dz == pytest.approx(dz))


def test_the_drag_instead_of_a_put_back_lift_puts_the_object_where_the_lift_would_have(sim_scenario, model_dragging):
    assert model_dragging.tool.rules.drag_after_weighing  # the station profile's default
    scene = _scene(sim_scenario, 0.4)
    lift = _lift_to(model_dragging, scene.objects, 0.10, -0.12)
    drag, why = model_dragging.drag_instead(scene.objects, lift, 0.6)
    assert why == "" and drag.drag and not drag.guarded and drag.name == "object_0"
    assert (drag.dx, drag.dz) == (lift.dx, lift.dz)
    assert drag.q[2] <= lift.q[2]  # sealed no higher than the lift (a drag seals low: it must not tip the box)
    # light enough to lift at the weighed mass: no drag (nothing to do instead); too heavy to slide: none either
    assert model_dragging.drag_instead(scene.objects, lift, 0.3) == (None, "still lifted at 0.30 kg")
    drag, why = model_dragging.drag_instead(scene.objects, lift, 10.0)
    assert drag is None and why.startswith("no drag of it: ") and "pull" in why  # 98 N > the cup's 42.4 N


def test_no_drag_instead_where_the_lift_passed_over_an_object_the_drag_would_slide_through(sim_scenario,
                                                                                            model_dragging):
    box = _scene(sim_scenario, 0.4).objects[0]
    low = SceneObject("object_1", "box", (0.06, 0.06, 0.03), planar_pose(0.10, -0.16, 0.015, 0.0), mass=0.2)
    objects = (box, low)
    lifts = [a for a in model_dragging.enumerate(objects, pushes=False).feasible
             if a.name == "object_0" and not a.drag and a.dx == pytest.approx(0.10) and a.dz > -0.05]
    assert lifts  # carried over the low box, put down behind it
    for lift in lifts:
        drag, why = model_dragging.drag_instead(objects, lift, 0.6)
        assert drag is None and why.startswith("no drag to that placement"), why


def test_the_shelf_simulator_drags_after_weighing_only_under_the_rule(sim_scenario, model_dragging):
    from slax_drake.shelf.simulator import DRAGGED_INSTEAD, drag_after_weighing

    believed = _scene(sim_scenario, 0.4).objects  # what the lift was chosen on: liftable
    scene = _scene(sim_scenario, 0.6)  # 0.47 N m off the cup at the lift: put back
    lift = _lift_to(model_dragging, believed, 0.10, -0.12)
    after, note = execute(scene, lift, model_dragging)
    assert after is scene and note.startswith(WEIGHED_PUT_BACK)
    dragged, dragged_note = drag_after_weighing(after, note, model_dragging, believed, lift, 0.6, "object_0")
    assert dragged_note == f"{note}; {DRAGGED_INSTEAD}"
    assert tuple(dragged.objects[0].center[:2]) == pytest.approx((0.10, -0.12))
    rule_off = model_dragging.with_tool(dataclasses.replace(
        model_dragging.tool, rules=dataclasses.replace(model_dragging.tool.rules, drag_after_weighing=False)))
    same, same_note = drag_after_weighing(after, note, rule_off, believed, lift, 0.6, "object_0")
    assert same is after and same_note == note
