"""A sideways drag weighed along its pull in the shelf simulator (the ``weigh_drag_pull`` rule): a drag whose slide
across would twist its true object off the cup (``max_drag_twist`` reckoned with the true mass) is pushed back where
it stood, and the camera mode's tracker reckons the object with that mass from then on, so that the action model
drags it straight out and in only. The Drake trial's weighing: tests/systems/test_drag_weigh.py and
tests/systems/test_drag_pull_weigh_drake.py."""

import dataclasses

import pytest

from slax_drake.scene.camera import Camera
from slax_drake.scene.model import Scene, SceneObject, planar_pose
from slax_drake.scene.sampling import shelf_of
from slax_drake.shelf.actions import ActionModel, Suction
from slax_drake.shelf.simulator import PULL_PUT_BACK, CameraObserver, drag_over_twist, execute
from slax_drake.shelf.tool import tool_config

RULES = dict(max_suction_moment=0.4, drag_grasp=True, max_drag_pull=42.412, max_drag_twist=0.6362)


def _scene(sim_scenario, mass):
    box = SceneObject("object_0", "box", (0.10, 0.16, 0.10), planar_pose(0.0, -0.10, 0.05, 0.0), mass=mass)
    return Scene(shelf_of(sim_scenario), Camera.from_config(sim_scenario.camera), (box,), None, 0)


def _model(sim_scenario, **rules):
    tool = tool_config(sim_scenario, "station", **{**RULES, **rules})
    return ActionModel(shelf_of(sim_scenario), Camera.from_config(sim_scenario.camera).position, tool)


@pytest.fixture(scope="module")
def model(sim_scenario):
    return _model(sim_scenario, weigh_drag_pull=True)


def _drag(dx):  # sealed on the front face, 8 cm in front of the centre, slid dx across and back to its depth
    return Suction("object_0", (0.0, -0.18, 0.03), dx, -0.10, drag=True)


def test_a_sideways_drag_that_would_twist_off_the_cup_is_pushed_back_and_a_light_one_slides(sim_scenario, model):
    heavy = _scene(sim_scenario, 2.0)  # 1.5 x 0.44 x 2.0 x 9.81 x 0.08 = 1.04 N m > 0.64
    assert drag_over_twist(heavy.objects[0], _drag(0.15), model) == pytest.approx(1.5 * 0.44 * 2.0 * 9.81 * 0.08)
    after, note = execute(heavy, _drag(0.15), model)
    assert after is heavy and note.startswith(PULL_PUT_BACK) and "1.04 N m > 0.64 N m" in note
    light = _scene(sim_scenario, 1.0)  # 0.52 N m
    assert drag_over_twist(light.objects[0], _drag(0.15), model) is None
    after, note = execute(light, _drag(0.15), model)
    assert note == "" and after.objects[0].center[0] == pytest.approx(0.15)


def test_a_straight_drag_and_a_drag_without_the_rule_are_not_weighed(sim_scenario, model):
    heavy = _scene(sim_scenario, 2.0)
    assert drag_over_twist(heavy.objects[0], _drag(0.0), model) is None  # out and back in: no twist
    after, note = execute(heavy, dataclasses.replace(_drag(0.0), dz=-0.15), model)
    assert note == "" and after.objects[0].center[1] == pytest.approx(-0.15)
    # the drag after a weighed lift: its mass known, its pull is not weighed again
    after, note = execute(heavy, _drag(0.15), model, weigh_pull=False)
    assert note == "" and after.objects[0].center[0] == pytest.approx(0.15)
    rule_off = _model(sim_scenario)
    assert not rule_off.tool.rules.weigh_drag_pull  # off in the station profile's default
    after, note = execute(heavy, _drag(0.15), rule_off)
    assert note == "" and after.objects[0].center[0] == pytest.approx(0.15)


def test_the_camera_mode_tracker_takes_the_mass_and_the_model_drags_it_straight_only(density_scenario):
    # a lower lift limit, so that the camera's hypothesis (its class's density mass, 0.5 kg) is dragged, not lifted
    model = _model(density_scenario, weigh_drag_pull=True, max_suction_moment=0.2)
    scene = _scene(density_scenario, 2.0)
    observer = CameraObserver(scene.shelf, scene.camera, (0.05, 0.05, 0.10), source="depth", width=160)
    observer.start()
    observation, _ = observer.observe(scene)
    (hyp,) = observation.known
    sideways = [a for a in model.enumerate(observation.known, pushes=False).feasible if a.drag and a.dx != 0.0]
    assert sideways  # at the mass it is believed to have, its twist is under the limit
    observer.executed(sideways[0])
    assert observer.weighed_pull(sideways[0], scene.objects[0], model) == pytest.approx(2.0)
    again, _ = observer.observe(scene)
    (weighed,) = again.known
    assert weighed.mass == pytest.approx(2.0)
    drags = [a for a in model.enumerate(again.known, pushes=False).feasible if a.drag]
    assert drags and all(a.dx == 0.0 for a in drags)


def test_a_flat_face_may_be_asked_more_twist_under_the_flat_factor(sim_scenario):
    """``drag_twist_flat_factor``: a box (a flat face to the cup) may be slid across up to that factor times
    ``max_drag_twist``; a cylinder's curved face keeps the limit."""
    from slax_drake.shelf.rules import drag_twist_limit

    flat = _model(sim_scenario, weigh_drag_pull=True, drag_twist_flat_factor=1.2)
    assert drag_twist_limit(flat.tool.rules, "box") == pytest.approx(1.2 * 0.6362)
    assert drag_twist_limit(flat.tool.rules, "cylinder") == pytest.approx(0.6362)
    box = _scene(sim_scenario, 1.4)  # 1.5 x 0.44 x 1.4 x 9.81 x 0.08 = 0.73 N m: over 0.64, under 0.76
    assert drag_over_twist(box.objects[0], _drag(0.15), _model(sim_scenario, weigh_drag_pull=True)) is not None
    assert drag_over_twist(box.objects[0], _drag(0.15), flat) is None

    def sideways(model):
        return [a for a in model.enumerate(box.objects, pushes=False).feasible if a.drag and a.dx != 0.0]

    assert sideways(flat) and not sideways(_model(sim_scenario))
