"""The object tracker on hand-built frame sequences: names kept across a push, across being hidden and seen
again, and the state carried between processes."""

import dataclasses

import numpy as np

from slax_drake.perception.tracking import ObjectTracker
from slax_drake.scene.model import SceneObject, planar_pose
from slax_drake.shelf.actions import Push, Suction


def box(name, x, y, sx=0.08, sy=0.08, sz=0.12, yaw=0.0):
    return SceneObject(name, "box", (sx, sy, sz), planar_pose(x, y, sz / 2, yaw))


def frame(*objects):
    """A frame's hypotheses, named by segment as a segmentation numbers them (in the order given)."""
    return [dataclasses.replace(o, name=f"segment_{k + 1}") for k, o in enumerate(objects)]


def names_at(tracked, xs):
    """{x of the object (rounded to cm): its tracked name}."""
    return {round(float(o.center[0]), 2): o.name for o in tracked if round(float(o.center[0]), 2) in xs}


def test_a_pushed_object_keeps_its_name_and_so_do_the_others():
    t = ObjectTracker()
    first = t.update(frame(box("a", -0.15, -0.1), box("b", 0.0, -0.1), box("c", 0.15, 0.05)))
    assert [o.name for o in first] == ["track_1", "track_2", "track_3"]
    # track_2 pushed right by 0.07 m; the segmentation numbers the segments in another order
    push = Push("track_2", (-0.04, -0.1, 0.05), 0.07)
    second = t.update(frame(box("c", 0.152, 0.051), box("b", 0.07, -0.1), box("a", -0.149, -0.1)), push)
    assert names_at(second, {-0.15, 0.07, 0.15}) == {-0.15: "track_1", 0.07: "track_2", 0.15: "track_3"}
    assert not t.hidden()


def test_a_push_stopped_early_still_keeps_the_name():
    t = ObjectTracker()
    t.update(frame(box("a", -0.15, -0.1), box("b", 0.0, -0.1)))
    push = Push("track_2", (-0.04, -0.1, 0.05), 0.12)  # stops after 0.05 m on something unseen
    after = t.update(frame(box("b", 0.05, -0.1), box("a", -0.15, -0.1)), push)
    assert [o.name for o in after] == ["track_2", "track_1"]


def test_a_pushed_box_that_turned_and_went_deeper_keeps_its_name_and_an_object_off_its_path_is_new():
    """Table I 10:15 in Drake: a box pushed 0.255 m left slid 0.155 m, went 4.7 cm deeper and turned 9 deg; its
    front came out 5.5 cm from the commanded path (the gate is 4 cm) and it was named anew."""
    t = ObjectTracker()
    pushed = box("p", 0.02725, -0.16969, 0.0974, 0.1442, 0.1768, yaw=0.286)
    t.update(frame(pushed, box("q", 0.2, 0.15)))
    push = Push("track_1", (0.08, -0.2, 0.05), -0.255)
    landed = box("p", -0.12787, -0.1232, 0.1543, 0.094, 0.1768, yaw=0.44)
    after = t.update(frame(box("q", 0.2, 0.15), landed), push)
    assert [o.name for o in after] == ["track_2", "track_1"]
    # a box that turns up far behind the pushed one's path (and the pushed one not seen) is another object
    t = ObjectTracker()
    t.update(frame(pushed, box("q", 0.2, 0.15)))
    behind = t.update(frame(box("q", 0.2, 0.15), box("r", -0.15, 0.12)), push)
    assert [o.name for o in behind] == ["track_2", "track_3"] and [h.name for h in t.hidden()] == ["track_1"]


def test_a_hidden_object_is_remembered_and_named_the_same_when_seen_again():
    t = ObjectTracker()
    t.update(frame(box("front", -0.1, -0.2), box("back", 0.1, 0.1)))
    # track_1 carried in front of track_2 (a suction): track_2 is hidden now
    carry = Suction("track_1", (-0.1, -0.24, 0.06), 0.2, -0.2)
    hidden = t.update(frame(box("front", 0.1, -0.2)), carry)
    assert [o.name for o in hidden] == ["track_1"]
    (remembered,) = t.hidden()
    assert remembered.name == "track_2" and remembered.remembered
    np.testing.assert_allclose(remembered.center[:2], (0.1, 0.1))
    # carried away again: track_2 is seen where it was; a new object seen for the first time gets a new name
    back = Suction("track_1", (0.1, -0.24, 0.06), -0.2, -0.2)
    again = t.update(frame(box("new", 0.2, 0.2), box("back", 0.101, 0.099), box("front", -0.1, -0.2)), back)
    assert [o.name for o in again] == ["track_3", "track_2", "track_1"]
    assert not t.hidden()


def test_shapes_do_not_match_and_far_objects_are_new():
    t = ObjectTracker()
    t.update(frame(box("a", 0.0, 0.0)))
    cyl = SceneObject("c", "cylinder", (0.08, 0.08, 0.1), planar_pose(0.0, 0.0, 0.05, 0.0))
    (o,) = t.update(frame(cyl))
    assert o.name == "track_2"
    assert [h.name for h in t.hidden()] == ["track_1"]
    (far,) = t.update(frame(box("a", 0.2, 0.0)))
    assert far.name == "track_3"  # 0.2 m from where track_1 stood, nothing commanded it there


def test_the_state_round_trips_through_plain_data():
    import json

    t = ObjectTracker()
    t.update(frame(box("a", -0.15, -0.1), box("b", 0.0, -0.1)))
    t.update(frame(box("a", -0.15, -0.1)))  # b hidden
    restored = ObjectTracker.from_dict(json.loads(json.dumps(t.to_dict())))
    push = Push("track_1", (-0.19, -0.1, 0.05), 0.05)
    a = t.update(frame(box("b", 0.0, -0.1), box("a", -0.10, -0.1)), push)
    b = restored.update(frame(box("b", 0.0, -0.1), box("a", -0.10, -0.1)), push)
    assert [o.name for o in a] == [o.name for o in b] == ["track_2", "track_1"]


def test_an_estimate_that_changed_its_yaw_keeps_the_name():
    """Seen from another angle the estimator may fit another yaw and front: the footprints still overlap."""
    t = ObjectTracker()
    t.update(frame(box("a", 0.0, 0.08, sx=0.16, sy=0.14, yaw=1.36), box("b", -0.2, -0.1)))
    (o, b) = t.update(frame(box("a", 0.02, 0.175, sx=0.12, sy=0.06), box("b", -0.2, -0.1)))
    assert (o.name, b.name) == ("track_1", "track_2") and not t.hidden()


def test_a_weighed_object_carries_its_mass_in_every_later_frame_hidden_or_seen_and_across_processes():
    t = ObjectTracker()
    t.update(frame(box("a", -0.15, -0.1), box("b", 0.1, -0.1)))
    t.weighed("track_2", 1.25)
    lift = Suction("track_2", (0.1, -0.14, 0.06), 0.0, -0.1)  # put back: it stands where it stood
    second = t.update(frame(box("a", -0.15, -0.1), box("b", 0.1, -0.1)), lift)
    assert {o.name: o.mass for o in second} == {"track_1": None, "track_2": 1.25}
    t.update(frame(box("a", -0.15, -0.1)))  # track_2 hidden: remembered with its mass
    assert [(o.name, o.mass) for o in t.hidden()] == [("track_2", 1.25)]
    again = ObjectTracker.from_dict(t.to_dict())
    seen = again.update(frame(box("b", 0.1, -0.1), box("a", -0.15, -0.1)))
    assert {o.name: o.mass for o in seen} == {"track_1": None, "track_2": 1.25}


def test_fuse_extents_keeps_what_an_earlier_frame_showed_of_an_unmoved_box():
    t = ObjectTracker(fuse_extents=True)
    t.update(frame(box("a", -0.15, -0.1, sx=0.12), box("b", 0.1, -0.1)))
    # an object placed in front now hides the right half of "a": the frame shows it 0.06 m wide
    narrow = box("a", -0.18, -0.1, sx=0.06)
    fused = {o.name: o for o in t.update(frame(narrow, box("b", 0.1, -0.1)))}
    assert abs(fused["track_1"].size[0] - 0.12) < 1e-9
    assert abs(float(fused["track_1"].center[0]) + 0.15) < 1e-9
    # once moved, it is what the new frame shows
    push = Push("track_1", (-0.25, -0.1, 0.05), 0.05)
    moved = {o.name: o for o in t.update(frame(box("a", -0.13, -0.1, sx=0.06), box("b", 0.1, -0.1)), push)}
    assert abs(moved["track_1"].size[0] - 0.06) < 1e-9


def test_without_fuse_extents_the_frame_is_what_it_shows():
    t = ObjectTracker()
    t.update(frame(box("a", -0.15, -0.1, sx=0.12)))
    (only,) = t.update(frame(box("a", -0.18, -0.1, sx=0.06)))
    assert abs(only.size[0] - 0.06) < 1e-9
