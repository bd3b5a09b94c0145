"""How deep the camera sees per column (slax_drake.policies.sight), and the no-shuttle correction's "sight" rule:
a move back passes when it shows space no observed arrangement showed, judged on every seen object."""

import math

import numpy as np
import pytest

from slax_drake.policies.sight import DeepestView, SightDepths
from slax_drake.policies.trial_memory import TrialMemory
from slax_drake.scene import Camera
from slax_drake.shelf.actions import Push, Suction, apply_action

from shelf_scenes import box


@pytest.fixture()
def sight(paper):
    return SightDepths(Camera.from_config(paper.camera), 160)


def test_the_view_stops_at_the_nearest_front_face(sight):
    near, far = box("near", 0.0, -0.1, 0.1, 0.1, 0.15), box("far", 0.0, 0.15, 0.3, 0.1, 0.15)
    alone = sight.of([far])
    both = sight.of([near, far])
    covered = np.isfinite(alone)
    assert covered.sum() > 10 and np.isinf(alone[~covered]).all()  # beside the far box the back panel is seen
    hidden = np.isfinite(sight.of([near]))
    assert (both[hidden & covered] < alone[hidden & covered] - 0.2).all()  # the near box stops the view 0.25 m sooner
    assert np.array_equal(both[~hidden], alone[~hidden])


def _memories(sight, arrangements):
    memory, view = TrialMemory(), DeepestView(sight)
    for objects in arrangements:
        memory.observe(objects)
        view.observe(objects)
    return memory, view


def test_a_move_back_in_front_of_a_wide_object_shows_nothing_new(sight):
    """A pushed right in front of a wide box B shows B's face where A stood; pushing it back shows B's face where A
    stood then, which the first arrangement showed: both rules refuse it."""
    wide = box("B", 0.0, 0.15, 0.5, 0.1, 0.15)
    first = (box("A", 0.0, -0.15, 0.1, 0.1, 0.15), wide)
    second = apply_action(first, Push("A", (0.0, -0.2, 0.05), 0.15))
    memory, view = _memories(sight, [first, second])
    back = Push("A", (0.2, -0.2, 0.05), -0.15)
    assert view.newly_shown(apply_action(second, back)) == 0.0
    assert memory.vacates_unseen(second, back) < 0.02


def test_an_object_placed_behind_another_then_uncovered_shows_new_space_when_moved_back(sight):
    """A is carried from the left to stand behind E; E is pushed away, so A's front is seen; the space behind A
    was hidden in every arrangement (by E, then by A). Moving A back to the left shows it: the sight rule lets the
    move pass, the footprint-width rule refuses it (A stood elsewhere in the first arrangement, so no width was
    covered by it in every one)."""
    first = (box("A", -0.2, -0.15, 0.1, 0.1, 0.15), box("E", 0.1, -0.15, 0.12, 0.1, 0.15))
    second = apply_action(first, Suction("A", (-0.2, -0.2, 0.1), 0.3, 0.0))  # A now behind E, at x = 0.1
    third = apply_action(second, Push("E", (0.04, -0.2, 0.05), 0.15))  # E pushed right: A's front is seen
    memory, view = _memories(sight, [first, second, third])
    back = Suction("A", (0.1, -0.05, 0.1), -0.3, -0.15)
    moved = apply_action(third, back)
    assert view.newly_shown(moved) >= 0.02
    assert memory.vacates_unseen(third, back) == 0.0
    memory.moves["A"] = (0.3, 0.15)  # its last executed move (as TrialMemory.outcome records it)
    assert memory.undoes(third, back)  # a move back, which only the sight rule lets through


def test_the_sight_rule_is_an_option_of_slax_belief_and_the_corrected_policies(paper):
    from slax_drake.policies.registry import make_policy

    assert make_policy("slax-belief-sight", paper, horizon=4).shuttle_rule == "sight"
    assert make_policy("slax-belief", paper, horizon=4).shuttle_rule == "width"
    with pytest.raises(ValueError, match="shuttle_rule"):
        make_policy("slax-belief", paper, horizon=4, policy_options={"shuttle_rule": "far"})
    assert math.isinf(DeepestView(None).newly_shown(()))  # before any frame everything is new


def test_an_object_hidden_now_is_taken_to_stand_where_it_was_last_seen(sight):
    """B stands behind A. A pushed right shows B; A pushed back hides it again, and a frame that lists only what it
    sees then has no B. Pushing A right again shows nothing new: B is remembered where it was seen, so the space it
    stands in does not count as newly shown."""
    a, b = box("A", 0.0, -0.15, 0.1, 0.1, 0.15), box("B", 0.0, 0.15, 0.08, 0.1, 0.15)
    view = DeepestView(sight)
    view.observe([a])  # B hidden behind A
    view.observe([box("A", 0.15, -0.15, 0.1, 0.1, 0.15), b])  # A moved: B seen
    view.observe([a])  # A back: B hidden again, not listed
    again = [box("A", 0.15, -0.15, 0.1, 0.1, 0.15)]
    assert view.newly_shown(again) < 0.02
    forgetful = DeepestView(sight)
    forgetful.observe([a])
    forgetful.observe([box("A", 0.15, -0.15, 0.1, 0.1, 0.15), b])
    forgetful.last_seen.pop("B")  # what the view would do without its memory of B
    assert forgetful.newly_shown(again) >= 0.02
