"""An object carried across inside the bay stays out of space the camera has not seen (the ``carry_hidden_check``
rule): the planner leaves out the shallower ways across whose swept footprint meets a hidden cell, and the action
model's reach check of the ways across refuses exactly the same ones."""

import numpy as np
import pytest

from slax_drake.planning.waypoints import SEAL_PRESS, pull_out_options
from slax_drake.scene.footprint import Footprint
from slax_drake.scene.model import SceneObject, planar_pose
from slax_drake.scene.sampling import sample_scene, shelf_of
from slax_drake.shelf.actions import ActionModel, Suction, _StateContext
from slax_drake.shelf.floor import FloorGrid, band_crosses_hidden
from slax_drake.shelf.tool import tool_config


def _box(name, x, y, size):
    return SceneObject(name, "box", tuple(size), planar_pose(x, y, size[2] / 2.0, 0.0))


def _cells_in(grid, hidden, x_lo, x_hi, y_lo, y_hi) -> bool:
    """The plain reading: a hidden cell's centre lies in the rectangle."""
    c = grid.centers[hidden.ravel()]
    return bool(((c[:, 0] >= x_lo) & (c[:, 0] <= x_hi) & (c[:, 1] >= y_lo) & (c[:, 1] <= y_hi)).any())


def test_band_crosses_hidden_reads_the_cells_in_the_rectangle(sim_scenario):
    grid = FloorGrid(shelf_of(sim_scenario))
    hidden = np.zeros((grid.ny, grid.nx), dtype=bool)
    hidden[70:80, 50:60] = True  # x in [-0.0475, -0.0025], y in [0.0525, 0.0975] (cell centres)
    x_lo = np.array([-0.20, -0.20, 0.00, -0.0026, -0.30])
    x_hi = np.array([-0.05, -0.04, 0.20, 0.10, 0.30])
    got = band_crosses_hidden(grid, hidden, 0.0, 0.06, x_lo, x_hi)
    assert got.tolist() == [False, True, False, True, True]
    assert got.tolist() == [_cells_in(grid, hidden, a, b, 0.0, 0.06) for a, b in zip(x_lo, x_hi)]
    # rows in front of the hidden block, and a band wholly in front of the bay, hold none
    assert not band_crosses_hidden(grid, hidden, -0.2, 0.05, x_lo, x_hi).any()
    assert not band_crosses_hidden(grid, hidden, -0.5, -0.35, x_lo, x_hi).any()


@pytest.fixture(scope="module")
def hidden_carry(sim_scenario):
    """A deep box A right, carried 0.3 m to the left across the space a tall box B in the front row hides."""
    scene = sample_scene(sim_scenario, 2, seed=0)
    a = _box("object_0", 0.15, 0.10, (0.08, 0.08, 0.12))
    b = _box("object_1", -0.05, -0.20, (0.14, 0.06, 0.16))
    scene = scene.with_objects((a, b))
    model = ActionModel(shelf_of(sim_scenario), scene.camera.position, tool_config(sim_scenario))
    q = model.suction_contact(a)
    return scene, model, a, Suction(a.name, q, -0.30, 0.10)


def test_the_planner_leaves_out_the_ways_across_hidden_space(hidden_carry):
    scene, model, a, action = hidden_carry
    hidden = model.hidden_by_others(scene.objects, a.name)
    assert hidden.any()  # B hides the space behind it
    every = pull_out_options(action, a, scene.shelf)
    kept = pull_out_options(action, a, scene.shelf, hidden=(model.grid, hidden))
    assert kept[0] == every[0]  # pulled all the way out, the object crosses in front of the bay
    assert set(kept) < set(every)  # some shallower ways are left out, none added
    ex, ey = Footprint.of(a).extents()
    ox, oy = float(a.center[0]), float(a.center[1])
    y_seal = action.q[1] + SEAL_PRESS * action.axis[1]
    for y in every:
        y_c = oy + (y - y_seal)
        crosses = _cells_in(model.grid, hidden, ox + action.dx - ex, ox + ex, y_c - ey, y_c + ey)
        assert (y not in kept) == crosses, y
    # with nothing to hide the way, every depth stays
    alone = scene.with_objects((a,))
    nothing = model.hidden_by_others(alone.objects, a.name)
    assert not nothing.any()
    assert pull_out_options(action, a, scene.shelf, hidden=(model.grid, nothing)) == every


def test_the_action_model_refuses_the_same_ways_as_the_planner(hidden_carry):
    """The reach check's ways across (:meth:`ActionModel.carry_cup_ys`, the planner's at every approach margin)
    that the rule refuses are exactly those the planner leaves out, for several placements along x."""
    scene, model, a, action = hidden_carry
    hidden = model.hidden_by_others(scene.objects, a.name)
    fp = Footprint.of(a)
    lat = model.suction_lattice(a, fp, model.grid.footprint_mask(fp))
    ways = model.carry_cup_ys(lat, a, fp)
    dxs = np.array([-0.30, -0.10, 0.0, 0.10])
    pre = {"dxs": dxs, "way_ys": np.array([y for y, _ in ways]), "py": action.q[1] + SEAL_PRESS * action.axis[1]}
    ctx = _StateContext(model, scene.objects, ())
    refused = model._ways_through_hidden(ctx, 0, pre, a, fp)
    assert refused.shape == (len(dxs), len(ways)) and refused.any() and not refused.all()
    for k, dx in enumerate(dxs):
        moved = Suction(a.name, action.q, float(dx), action.dz)
        planner_ways = {round(y, 9) for y in pull_out_options(moved, a, scene.shelf)}
        planner_kept = {round(y, 9) for y in pull_out_options(moved, a, scene.shelf, hidden=(model.grid, hidden))}
        compared = 0
        for o, (y, turn) in enumerate(ways):
            if turn == 0.0 and round(y, 9) in planner_ways:
                assert refused[k, o] == (round(y, 9) not in planner_kept), (dx, y)
                compared += 1
            if turn != 0.0:
                assert not refused[k, o]  # turned ways are pulled all the way out
        assert compared == len(planner_ways)  # every way the planner tries at the first margin is among them
