"""The action model's suction placements (ActionModel._suctions: per-object lattices cached by identity, pairwise
(A, B) masks AND-ed, the hidden-space rules on the whole lattice at once) equal a plain computation of the same
definition, one lattice point at a time, on the states of seeded random walks from Table I scenes, in both profiles
with the "path" hidden-space rule (slax-hindsight's safe suctions) and with objects lifted only slightly (every
other object stops the way in). These guard a speed-up that must not change
any candidate (benchmarks/compare_trial_outputs.py)."""

import dataclasses
import math

import numpy as np
import pytest

from action_walks import walk
from slax_drake.shelf.actions import ActionModel, Suction, _StateContext
from slax_drake.shelf.floor import column_extents
from slax_drake.shelf.tool import tool_config
from slax_drake.scene.footprint import Footprint, clear_of
from slax_drake.scene.sampling import shelf_of


def model_for(scenario, profile: str, **rules) -> ActionModel:
    """The action model of ``profile`` with single ``rules`` replaced."""
    tool = tool_config(scenario, profile)
    tool = dataclasses.replace(tool, rules=dataclasses.replace(tool.rules, **rules))
    return ActionModel(shelf_of(scenario), scenario.camera.position, tool)


def plain_placements(model: ActionModel, objects, fixed, i: int) -> list[tuple[float, float]]:
    """(dx, dz) of object i's suction placements by the definition, one lattice point (a, b) at a time, in the
    order a, then b: the object, lifted, goes straight in at x' = x + a res from outside the shelf, and every step
    of that way in (``cell`` apart, up to the first step at or past the placement's depth y' = y + b res) keeps
    ``clearance`` from each object it cannot pass over; placed, it keeps ``clearance`` from each object it passes
    over; its footprint, shifted to the placement, lies partly on the raster; and the hidden-space rule holds:
    "placement", no hidden cell (the state's hidden space less the object's own cells) under the shifted
    footprint; "path", none in its columns in front of the shifted footprint's last row."""
    t, shelf, cell = model.tool, model.shelf, model.tool.grid.cell
    obj, fp = objects[i], Footprint.of(objects[i])
    every = tuple(objects) + tuple(fixed)
    others = [k for k in range(len(every)) if k != i]
    blocking = [k for k in others if not model.passes_over(obj, every[k].size[2])]
    ex, ey = fp.extents()
    res = t.grid.suction_resolution
    cells_per = int(round(res / cell))
    x_lim = shelf.width / 2 - t.physics.clearance - ex
    y_lim = shelf.depth / 2 - t.physics.clearance - ey
    a_lo, a_hi = int(math.floor((-x_lim - fp.x) / res + 1e-9)), int(math.floor((x_lim - fp.x) / res + 1e-9))
    a_all = [a for a in range(a_lo, a_hi + 1) if abs(fp.x + a * res) <= x_lim + 1e-12]
    b_all = list(range(int(math.ceil((-y_lim - fp.y) / res - 1e-9)), int(math.floor((y_lim - fp.y) / res + 1e-9)) + 1))
    y_out = -shelf.depth / 2 - ey - cell
    y_deep = fp.y + b_all[-1] * res
    n_in = int(math.ceil((y_deep - y_out) / cell)) + 1
    steps = y_out + np.arange(n_in) * cell
    steps[-1] = min(steps[-1], y_deep)
    ctx = _StateContext(model, tuple(objects), tuple(fixed))
    mask = ctx.masks[i]
    hidden = ctx.hidden_all & ~mask if t.rules.suction_hidden_rule != "none" else None
    rows, cols = np.nonzero(mask)
    half = (fp.half_x, fp.half_y)
    out = []
    for a in a_all:
        x_new = fp.x + a * res
        c_new = cols + a * cells_per
        if not ((c_new >= 0) & (c_new < model.grid.nx)).any():
            continue
        way_clear = np.ones(n_in, dtype=bool)  # each step of the way in at this column, past the blocking objects
        for k in blocking:
            way_clear &= clear_of(fp.shape, np.column_stack([np.full(n_in, x_new), steps]), fp.yaw, half,
                                  Footprint.of(every[k]), t.physics.clearance)
        for b in b_all:
            if a == 0 and b == 0:
                continue
            y_new = fp.y + b * res
            last_step = int(np.flatnonzero(y_new <= steps + 1e-9)[0])
            if not way_clear[:last_step + 1].all():
                continue
            centre = np.array([[x_new, y_new]])
            if not all(clear_of(fp.shape, centre, fp.yaw, half, Footprint.of(every[k]), t.physics.clearance)[0]
                       for k in others if k not in blocking):
                continue
            if hidden is not None and not hidden_rule_holds(model, hidden, mask, a * cells_per, b * cells_per):
                continue
            out.append((round(float(a * res), 6), round(float(y_new), 6)))
    return out


def hidden_rule_holds(model: ActionModel, hidden, mask, dc: int, dr: int) -> bool:
    """Whether the footprint ``mask`` shifted by ``dc`` columns and ``dr`` rows meets the hidden-space rule (cells
    off the raster count as not hidden)."""
    ny, nx = hidden.shape
    cols, first, last = column_extents(mask)
    for c, r0, r1 in zip(cols + dc, first + dr, last + dr):
        if not 0 <= c < nx:
            continue
        lo = 0 if model.tool.rules.suction_hidden_rule == "path" else max(0, r0)
        if hidden[lo:max(0, min(ny, r1 + 1)), c].any():
            return False
    return True


@pytest.mark.parametrize("profile,rules", [
    ("paper", {}), ("station", {}),
    ("paper", {"suction_hidden_rule": "path"}),  # slax-hindsight's safe suctions
    ("paper", {"suction_lift": "slight"}),  # every object stops the way in: the way-in masks decide
])
def test_suction_placements_equal_the_plain_definition(paper, profile, rules):
    model = model_for(paper, profile, **rules)
    compared = placements = 0
    for n, seed in ((6, 5), (10, 6)):
        states, fixed = walk(paper, model, n, seed, steps=3)
        assert len(states) >= 3
        for objects in states + states[:1]:  # the last pass with every cache warm
            got = model.enumerate(objects, fixed=fixed, pushes=False)
            for i, obj in enumerate(objects):
                reasons = [r.reason for r in got.rejected if r.what == f"suction {obj.name}"]
                if reasons and not reasons[0].startswith("no collision-free placement"):
                    continue  # refused before its placements are looked at (the same code path as before)
                mine = [(a.dx, a.dz) for a in got.feasible if isinstance(a, Suction) and a.name == obj.name]
                assert mine == plain_placements(model, objects, fixed, i), (profile, rules, n, seed, obj.name)
                compared += 1
                placements += len(mine)
    assert compared >= 20 and placements > 0
