"""slax-belief's fast per-world distances (slax_drake/policies/belief.py) equal a plain, world-by-world computation
of the same definition, on a seeded 10-object Table I scene and on children of it that the search looks at; and the
helpers they rest on (OR-accumulated counts, the half-plane hull test, the popcount) equal their plain forms. These
guard the speed-ups of slax-belief, whose trials must stay identical (benchmarks/compare_trial_outputs.py)."""

import numpy as np
import pytest
from shapely.geometry import MultiPoint, box

from slax_drake.config import load_scenario
from slax_drake.policies.belief import PackedWorlds, _at_least, _ConvexRegion, _popcount
from slax_drake.policies.hindsight import Worlds
from slax_drake.policies.registry import make_policy
from slax_drake.shelf.simulator import observation_for
from slax_drake.scene.sampling import sample_scene

TARGET = (0.06, 0.06, 0.06)


def plain_distances(raw: Worlds, objects, threshold: float, failure_cost: float) -> np.ndarray:
    """The definition, one world at a time on unpacked masks: 0 when the target is seen at v; 1 or 2 when removing
    some one or two objects shows it; else the count of a greedy cover (each time the object, among those hiding
    something in some world, whose removal shows the most, the first on a tie), at least 3; ``failure_cost`` when
    the empty shelf shows none of the target."""
    masks = [m for m in (raw.hidden_by(o) for o in objects) if m.any()]
    out = np.zeros(raw.count)
    for k in range(raw.count):
        shown, need = raw.shown[k], threshold * raw.n_shown[k] - 1e-9
        per = [m[k] for m in masks]

        def seen_without(removed) -> int:
            hidden = np.zeros_like(shown)
            for i, m in enumerate(per):
                if i not in removed:
                    hidden |= m
            return int((shown & ~hidden).sum())

        if raw.n_shown[k] == 0:
            out[k] = failure_cost
        elif seen_without(set()) >= need:
            out[k] = 0
        elif any(seen_without({i}) >= need for i in range(len(per))):
            out[k] = 1
        elif any(seen_without({i, j}) >= need for i in range(len(per)) for j in range(i + 1, len(per))):
            out[k] = 2
        else:
            removed: list = []
            while seen_without(set(removed)) < need:
                gains = [seen_without(set(removed) | {i}) if i not in removed else -1 for i in range(len(per))]
                removed.append(int(np.argmax(gains)))
            out[k] = max(3, len(removed))
    return out


@pytest.fixture(scope="module")
def ten_objects():
    paper = load_scenario("sim_configs/table1.yaml")
    scene = sample_scene(paper, 10, 100070, target_size=TARGET)
    policy = make_policy("slax-belief", paper, horizon=20)
    policy.reset(scene)
    obs = observation_for(policy, scene)
    raw = Worlds(obs.scene_template, policy.draw(policy.placements(obs), 0), TARGET, policy.threshold)
    return policy, raw, tuple(obs.known)


def test_distances_of_a_state_and_its_children_equal_the_plain_definition(ten_objects):
    policy, raw, known = ten_objects
    packed = PackedWorlds(raw)
    children = [after for _, after, _ in policy.moves(known)][::7][:8]
    assert len(children) == 8
    seen_values = set()
    for objects in (known, *children):
        fast = policy.distances(packed, objects)
        assert np.array_equal(fast, plain_distances(raw, objects, policy.threshold, policy.failure_cost))
        assert policy.distances(packed, objects) is fast  # cached
        seen_values |= set(fast.tolist())
    assert {0.0, 1.0, 2.0} & seen_values and max(seen_values) >= 3  # the scene exercises the greedy cover too


def test_distances_of_many_arrangements_at_once_equal_one_at_a_time(ten_objects):
    """:meth:`prefetch_distances` (every arrangement's worlds side by side, objects hiding nothing as absent rows)
    gives each arrangement exactly its own :meth:`distances`."""
    policy, raw, known = ten_objects
    arrangements = [known] + [after for _, after, _ in policy.moves(known)]
    one_by_one = []
    for objects in arrangements:
        policy._distance_cache = {}
        one_by_one.append(policy.distances(PackedWorlds(raw), objects))
    policy._distance_cache = {}
    packed = PackedWorlds(raw)
    policy.prefetch_distances(packed, arrangements)
    assert len(policy._distance_cache) == len(arrangements)
    assert all(np.array_equal(policy.distances(packed, o), d) for o, d in zip(arrangements, one_by_one))
    rows = [sum(packed.mask(o) is None for o in objects) for objects in arrangements]
    assert min(rows) < max(rows)  # the batch mixes arrangements with different objects hiding nothing


def test_cached_blocks_and_placement_risks_equal_fresh_ones(ten_objects):
    policy, raw, known = ten_objects
    packed = PackedWorlds(raw)
    policy._hidden_centers = raw.centers
    policy._risk_by_box, policy._risk_cache = {}, {}
    suctions = [(a, after) for a, after, _ in policy.moves(known) if a.kind == "suction"]
    assert len(suctions) > 10
    risks = set()
    for _ in range(2):  # the second round is answered from the caches
        for a, after in suctions:
            assert np.array_equal(packed.blocks(after, a.name), raw.blocks(after, a.name))
            risk = policy.placement_risk(known, a)
            assert risk == policy.box_risk(policy.placement_box(known, a), raw.centers)
            risks.add(risk)
    assert len(risks) > 1


def test_masks_cached_by_pose_equal_fresh_ones(ten_objects):
    """An equal object rebuilt (a new instance at the same pose) gets the same mask as a fresh PackedWorlds'."""
    policy, raw, known = ten_objects
    packed = PackedWorlds(raw)
    rebuilt = tuple(o.moved_to(float(o.center[0]), float(o.center[1])) for o in known)
    for a, b in zip(known, rebuilt):
        first, again = packed.mask(a), packed.mask(b)
        fresh = PackedWorlds(raw).mask(b)
        hidden = raw.hidden_by(b)
        assert (first is None) == (again is None) == (fresh is None) == (not hidden.any())
        if fresh is not None:
            assert np.array_equal(again, fresh) and np.array_equal(fresh, PackedWorlds.pack(hidden))


def test_at_least_counts_equal_a_running_count():
    rng = np.random.default_rng(5)
    for n in range(0, 9):
        masks = rng.integers(0, 2 ** 63, size=(n, 6, 2), dtype=np.uint64) & rng.integers(
            0, 2 ** 63, size=(n, 6, 2), dtype=np.uint64)
        bits = np.unpackbits(masks.view(np.uint8), axis=-1).reshape(n, 6, 128)
        count = bits.sum(axis=0) if n else np.zeros((6, 128), int)
        for level, got in enumerate(_at_least(masks, 3), start=1):
            expected = np.packbits(count >= level, axis=-1).view(np.uint64)
            assert np.array_equal(got, expected)
        assert np.array_equal(_popcount(masks), bits.sum(axis=-1))


def test_hull_test_never_misses_a_box_that_meets_the_hull():
    """The half-plane test answers "no" only where shapely finds the box and the hull apart."""
    rng = np.random.default_rng(3)
    apart = 0
    for _ in range(40):
        hull = MultiPoint([tuple(p) for p in rng.uniform(-0.3, 0.3, size=(rng.integers(3, 10), 2))]).convex_hull
        region = _ConvexRegion(hull)
        for _ in range(50):
            (x, y), (hx, hy) = rng.uniform(-0.5, 0.5, 2), rng.uniform(0.005, 0.1, 2)
            meets = hull.intersects(box(x - hx, y - hy, x + hx, y + hy))
            assert region.may_meet_box(x - hx, x + hx, y - hy, y + hy) == meets
            apart += not meets
    assert apart > 100  # the boxes do fall outside often
    touching = _ConvexRegion(box(0.0, 0.0, 1.0, 1.0))
    assert touching.may_meet_box(1.0, 2.0, 0.0, 1.0)  # a box touching an edge meets it
