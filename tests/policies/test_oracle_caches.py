"""The caches that make the oracles' search fast return exactly what the uncached computation returns, and the
oracle replays its plan while the scene is the one it predicted, searching again after a deviation."""

import dataclasses

import numpy as np
import pytest

from action_walks import walk
from slax_drake.shelf.actions import ActionModel, _StateContext, apply_action
from slax_drake.policies.oracle_search import StateKeys
from slax_drake.policies.registry import make_policy
from slax_drake.shelf.tool import tool_config
from slax_drake.scene import Camera
from slax_drake.scene.footprint import Footprint, _axes, clear_of
from slax_drake.scene.model import Scene, SceneObject, Shelf, Target, planar_pose, state_key
from slax_drake.scene.sampling import shelf_of


def box(name, x, y, sx=0.10, sy=0.08, sz=0.15):
    return SceneObject(name, "box", (sx, sy, sz), planar_pose(x, y, sz / 2, 0.0))


def two_blockers(scenario):
    """Two boxes one behind the other on the camera's line to the target (the minimal plan: push both), a
    bystander at the left wall (as in test_oracle_search)."""
    target = Target((0.06, 0.06, 0.06), planar_pose(0.0, 0.22, 0.03, 0.0))
    objects = (box("a", 0.0, -0.15, sx=0.12), box("b", 0.0, 0.05, sx=0.12), box("c", -0.24, 0.20))
    return Scene(Shelf(0.6, 0.6, 0.6, 0.02), Camera.from_config(scenario.camera), objects, target, 0)


class UncachedModel(ActionModel):
    """The action model with its caches bypassed: every pairwise test, push rect, object geometry and suction
    lattice computed."""

    def _pair(self, key, compute):
        return compute()

    def _push_rects(self, fp, sign):
        tool_rects = tuple(self._tool_rects(fp, sign))
        return tool_rects, tuple(self._swept_rects(tool_rects, sign))

    def object_geometry(self, objects, rasters=True, fixed=()):
        self._geometry.clear()
        return super().object_geometry(objects, rasters, fixed)

    def suction_lattice(self, obj, fp, mask):
        return self._make_suction_lattice(obj, fp, mask)


@pytest.mark.parametrize("profile", ["paper", "station"])
def test_a_cached_models_candidates_equal_an_uncached_models(paper, profile):
    """Pairwise collision tests, object geometry and push rects are cached in the model across states: every
    state's feasible and rejected candidates (with their reasons) equal those computed without the caches."""
    warm = ActionModel(shelf_of(paper), paper.camera.position, tool_config(paper, profile))
    uncached = UncachedModel(shelf_of(paper), paper.camera.position, tool_config(paper, profile))
    for n, seed in ((8, 1), (10, 2)):
        states, fixed = walk(paper, warm, n, seed, steps=4)
        assert len(states) >= 3
        for objects in states + states[::-1]:  # the second pass meets every state with all caches warm
            expected = uncached.enumerate(objects, fixed=fixed)
            got = warm.enumerate(objects, fixed=fixed)
            assert got.feasible == expected.feasible
            assert got.rejected == expected.rejected


def test_a_state_contexts_footprint_ids_come_from_one_id_table(paper, monkeypatch):
    """The footprint ids of a state (its objects and the fixed target) name their footprints in the model's id
    table as it stands after the state is read, and differ where the footprints differ, even when the table fills
    up between the objects and the target (the pairwise cache keyed by ids must not mix two numberings)."""
    import slax_drake.shelf.actions as actions

    model = ActionModel(shelf_of(paper), paper.camera.position, tool_config(paper, "paper"))
    states, fixed = walk(paper, model, 8, 1, steps=0)
    objects = states[0]
    moved = tuple(o.moved_to(o.center[0] + 0.001, o.center[1]) for o in objects)  # other instances and footprints
    monkeypatch.setattr(actions, "PAIR_CACHE_SIZE", 2 * len(objects) + 1)  # the target of `moved` overflows it
    _StateContext(model, objects, fixed)
    ctx = _StateContext(model, moved, fixed)
    assert all(model._fp_ids.get(fp) == i for fp, i in zip(ctx.all_fps, ctx.ids))
    assert len(set(ctx.ids)) == len(set(ctx.all_fps))


def test_the_hidden_space_near_an_object_equals_the_whole_rasters_rows(paper):
    model = ActionModel(shelf_of(paper), paper.camera.position, tool_config(paper))
    states, fixed = walk(paper, model, 10, 3, steps=3)
    hidden_rows = 0
    for objects in states:
        ctx = _StateContext(model, tuple(objects), fixed)
        for i in range(len(objects)):
            r0, r1, near = ctx.hidden_others_near(i)
            rows = np.flatnonzero(ctx.masks[i].any(axis=1))
            assert r0 <= rows[0] and rows[-1] < r1
            whole = ctx.hidden_others(i)
            assert np.array_equal(near[rows - r0], whole[rows])
            hidden_rows += int(whole[rows].any(axis=1).sum())
    assert hidden_rows > 0  # the comparison met hidden cells


def test_state_keys_equal_state_key(paper):
    model = ActionModel(shelf_of(paper), paper.camera.position, tool_config(paper))
    states, _ = walk(paper, model, 6, 4, steps=3)
    keys = StateKeys()
    for objects in states + states:
        assert keys.of_state(objects) == state_key(objects)
        assert all(keys.of_object(o) == state_key((o,))[0] for o in objects)


def test_cached_separating_axes_give_the_same_clearances():
    rng = np.random.default_rng(0)
    clear = blocked = 0
    for _ in range(200):
        a = Footprint("box", 0.0, 0.0, float(rng.uniform(-np.pi, np.pi)), *rng.uniform(0.02, 0.1, 2))
        b = Footprint("box", 0.0, 0.0, float(rng.uniform(-np.pi, np.pi)), *rng.uniform(0.02, 0.1, 2))
        centres = rng.uniform(-0.25, 0.25, (50, 2))
        # the separating axis test written out without the cache
        dx, dy = centres[:, 0] - b.x, centres[:, 1] - b.y
        a_axes, b_axes = _axes(a.yaw), _axes(b.yaw)
        expected = np.zeros(len(centres), dtype=bool)
        for u in (*a_axes, *b_axes):
            r_a = a.half_x * abs(a_axes[0] @ u) + a.half_y * abs(a_axes[1] @ u)
            r_b = b.half_x * abs(b_axes[0] @ u) + b.half_y * abs(b_axes[1] @ u)
            expected |= np.abs(dx * u[0] + dy * u[1]) >= r_a + r_b + 0.01
        for _repeat in range(2):  # computed, then from the cache
            got = clear_of("box", centres, a.yaw, (a.half_x, a.half_y), b, 0.01)
            assert np.array_equal(got, expected)
        clear, blocked = clear + int(expected.sum()), blocked + int((~expected).sum())
    assert clear > 0 and blocked > 0


def test_the_oracle_replays_its_plan_and_searches_again_after_a_deviation(paper):
    s = two_blockers(paper)
    oracle = make_policy("oracle-p", paper, horizon=4)
    oracle.reset(s)
    first = oracle.decide(s).best
    assert len(oracle.search_log) == 1 and len(oracle.plan) == 1
    # executed as predicted: the next action comes from the plan, without a search
    as_planned = dataclasses.replace(s, objects=apply_action(s.objects, first))
    second = oracle.decide(as_planned).best
    assert len(oracle.search_log) == 1 and second.name != first.name

    # executed with a deviation (the pushed object stopped 1 cm short): the oracle searches the true scene again
    oracle.reset(s)
    first = oracle.decide(s).best
    short = dataclasses.replace(first, d=first.d - np.sign(first.d) * 0.01)
    deviated = dataclasses.replace(s, objects=apply_action(s.objects, short))
    assert state_key(deviated.objects) != state_key(as_planned.objects)
    again = oracle.decide(deviated)
    assert len(oracle.search_log) == 2
    assert again.best is not None
