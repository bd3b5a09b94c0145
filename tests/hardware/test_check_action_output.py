"""What ``check-action`` prints: no Drake INFO lines, refused candidates in the ``kind:object:value`` form of an
action, collisions named with what they meet, and a --help example that is feasible on the default scene."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from slax_drake.cli import main
from slax_drake.hardware.check_action import make_checker, parse_action
from slax_drake.scene.io import load_scene
from slax_drake.scene.model import SceneObject


@pytest.fixture(scope="module")
def default_scene(tmp_path_factory):
    """The scene ``slax-drake scene`` writes with no options."""
    path = tmp_path_factory.mktemp("default_scene") / "scene.json"
    assert main(["scene", "--out", str(path)]) == 0
    return path


def _help_example(capsys) -> str:
    with pytest.raises(SystemExit):
        main(["check-action", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    return text.split("e.g. ")[1].split(",")[0]


def test_the_help_example_is_feasible_on_the_default_scene_without_drake_info_lines(default_scene, capfd):
    example = _help_example(capfd)
    parse_action(example)
    assert main(["check-action", "--scene", str(default_scene), "--action", example]) == 0
    out, err = capfd.readouterr()
    assert out.startswith(f"{example}: feasible, motion ")
    assert "INFO" not in err and "INFO" not in out


def test_refused_candidates_read_like_actions(default_scene):
    checker = make_checker(load_scene(default_scene))
    names = {o.name for o in checker.scene.objects}
    rejected = checker.candidates().rejected
    assert rejected
    for r in rejected:
        kind, name, *values = r.spec().split(":")
        assert kind == r.action_kind and name == r.object_name and name in names
        if kind == "push":
            assert len(values) == 1
            if r.distance is None:
                assert values == ["+x" if r.direction > 0 else "-x"]
            else:
                assert parse_action(r.spec())[2] == pytest.approx(r.distance, abs=1e-4)
        else:
            assert values == ["*", "*"]
    # one refused distance, as this scene has (object_5 would hit object_6 after 0.065 m)
    assert any(r.distance is not None for r in rejected)


def test_a_collision_names_what_the_robot_meets(default_scene):
    from slax_drake.planning.world import PlanningWorld
    from slax_drake.station.scenario import load_station_scenario

    checker = make_checker(load_scene(default_scene))
    station, scene, q = load_station_scenario(checker.station_path), checker.scene, checker.planner.q_observation
    free = PlanningWorld(station, scene)
    assert free.collision_pairs(q) == []
    # a box where the cup's tip is at the observation pose
    X = np.eye(4)
    X[:3, 3] = free.tool_pose_S(q, "cup_tip_frame").translation()
    box = SceneObject("in_the_way", "box", (0.05, 0.05, 0.05), X)
    world = PlanningWorld(station, dataclasses.replace(scene, objects=scene.objects + (box,)))
    pairs = world.collision_pairs(q)
    assert any(other == "in_the_way" for _, other in pairs), pairs
    assert world.first_collision_on(q, q) == pairs


@pytest.mark.slow
def test_all_candidates_show_a_progress_bar_while_planning(default_scene, capfd):
    from slax_drake.hardware.check_action import check_all

    check_all(default_scene, progress=True)
    assert "planning candidates" in capfd.readouterr().err


def test_the_table_names_each_refusals_typed_kind():
    from slax_drake.hardware.check_action import ActionCheck, table
    from slax_drake.planning.failures import FailureKind
    from slax_drake.shelf.actions import RefusalKind

    model_kind, motion_kind = next(iter(RefusalKind)).value, FailureKind.TOOL_COLLIDES.value
    text = table([ActionCheck("push:a:+x", False, "action model", "why", object_name="a", kind=model_kind),
                  ActionCheck("push:b:+0.0500", False, "motion", "insert: ...", kind=motion_kind),
                  ActionCheck("push:c:+0.0500", True, "ok", "", 8.0, {"total_s": 0.1})])
    header, refused, unplanned, feasible = text.splitlines()[:4]
    assert header.split()[:3] == ["action", "verdict", "kind"]
    assert model_kind in refused and motion_kind in unplanned and feasible.split()[2] == "-"
