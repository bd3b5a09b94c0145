"""The reach map and the action model's reach_map rule (issue 17 item 3): conservative lookup, the committed maps
of the shipped stations, the rule refusing what the map shows unreachable, and (slow) agreement with the motion
planner on a seeded sample of poses."""

import numpy as np
import pytest

from slax_drake.shelf.actions import ActionModel
from slax_drake.shelf.reach import LAYERS, ReachMap, load_reach_map
from slax_drake.shelf.tool import tool_config
from slax_drake.scene.model import SceneObject, planar_pose
from slax_drake.scene.sampling import shelf_of

SIM_MAP = "models/reach/station_sim_shelf.json"
PHYSICAL_MAP = "models/reach/station_physical_shelf.json"
SHIPPED_MAPS = pytest.mark.parametrize("map_path", [SIM_MAP, PHYSICAL_MAP])
# the shipped stations with their scenarios' fixtures, for the agreement tests with the planner
SHIPPED_STATIONS = pytest.mark.parametrize("station_file, scenario_fixture", [
    ("sim_configs/station_sim_shelf.yaml", "sim_scenario"),
    ("sim_configs/station_physical_shelf.yaml", "physical_scenario")])


def _station_planner(request, station_file: str, scenario_fixture: str):
    """(station, its reach map, tool, motion planner, empty-shelf scene) of a shipped station, for the agreement
    tests with the planner."""
    from slax_drake.planning.planner import MotionPlanner
    from slax_drake.scene.camera import Camera
    from slax_drake.scene.model import Scene
    from slax_drake.station.scenario import load_station_scenario

    scenario = request.getfixturevalue(scenario_fixture)
    station = load_station_scenario(station_file)
    tool = tool_config(scenario, "station")
    scene = Scene(shelf_of(scenario), Camera.from_config(scenario.camera), (), None, 0)
    return station, load_reach_map(station.reach_map), tool, MotionPlanner(station, tool), scene


def _toy_map():
    xs, ys = np.array([0.0, 0.1, 0.2, 0.3]), np.array([0.0, 0.1, 0.2])
    ok = np.array([[True, True, False, False]] * 3)  # reached left of x = 0.1, not from x = 0.2
    return ReachMap("toy", xs, ys, {layer: ok for layer in LAYERS}, {layer: 0.1 for layer in LAYERS})


def test_the_lookup_refuses_only_where_every_node_around_is_unreached():
    m = _toy_map()
    assert m.refuses("cup", 0.25, 0.05)  # every node of its cell unreached
    assert m.refuses("cup", 0.3, 0.2)  # a corner node: the one cell it touches is unreached
    assert not m.refuses("cup", 0.15, 0.05)  # its cell holds reached nodes (x = 0.1)
    assert not m.refuses("cup", 0.2, 0.1)  # on a node: the cells it touches reach back to x = 0.1
    assert not m.refuses("cup", 0.25, 0.05, margin=0.06)  # the margin takes in the cell from x = 0.1
    assert not m.refuses("cup", 0.5, 0.1) and not m.refuses("cup", 0.25, -0.2)  # off the grid: never refused
    again = ReachMap.from_dict(m.to_dict())
    assert all((again.reach[k] == m.reach[k]).all() for k in LAYERS) and (again.xs == m.xs).all()


@pytest.mark.parametrize("station", ["sim_configs/station_sim_shelf.yaml", "sim_configs/station_physical_shelf.yaml"])
def test_the_shipped_stations_name_their_committed_maps(station):
    from slax_drake.config import load_scenario
    from slax_drake.station.scenario import load_station_scenario
    from slax_drake.systems.trial import station_tool_rules

    st = load_station_scenario(station)
    rmap = load_reach_map(st.reach_map)
    shelf = load_scenario(st.scene_config).shelf
    assert rmap.xs[0] >= -shelf.width / 2 and rmap.xs[-1] <= shelf.width / 2 and rmap.ys[-1] <= shelf.depth / 2
    for layer in LAYERS:  # the front of the bay is reached, somewhere its back is not
        assert rmap.reach[layer][0].any() and not rmap.reach[layer].all()
    assert station_tool_rules(st)["reach_map"] == st.reach_map


def test_the_rule_refuses_a_push_the_map_shows_unreachable(sim_scenario):
    """A box whose +x push puts the blade where the map reached nothing: without the map the action model offers
    the push, with it the push is refused with the reach map's reason; the paper profile has no map."""
    rmap = load_reach_map(SIM_MAP)
    shelf = shelf_of(sim_scenario)

    def pushes(box, **rules):
        model = ActionModel(shelf, (0.0, -0.75, 0.2), tool_config(sim_scenario, "station", **rules))
        return model.enumerate((box,), suctions=False)

    for j, i in np.argwhere(~rmap.reach["push+x"]):
        x, y = float(rmap.xs[i]), float(rmap.ys[j])
        box = SceneObject("b", "box", (0.06, 0.06, 0.10), planar_pose(x + 0.05, y - 0.03, 0.05, 0.0))
        if abs(box.center[0]) > shelf.width / 2 - 0.04 or abs(box.center[1]) > shelf.depth / 2 - 0.04:
            continue
        offered = [a for a in pushes(box).feasible if a.d > 0]
        if offered and rmap.refuses("push+x", offered[0].q[0], offered[0].q[1], 0.015):
            break
    else:
        pytest.fail("no unreached node of the map takes a +x push of a small box")
    with_map = pushes(box, reach_map=SIM_MAP)
    assert not [a for a in with_map.feasible if a.d > 0]
    assert [r.reason for r in with_map.rejected if r.what == "push b +x"][0].endswith("m (reach map)")
    assert tool_config(sim_scenario, "paper").rules.reach_map == ""


@pytest.mark.slow
def test_the_rule_agrees_with_the_planner_on_a_sample_of_poses(sim_scenario):
    """Seeded random tool positions per layer: each one the map refuses has no collision-free IK solution from
    the observation pose; each one in a grid cell whose four nodes were all reached has one."""
    from slax_drake.planning.planner import MotionPlanner
    from slax_drake.planning.reach import layer_waypoint
    from slax_drake.scene.camera import Camera
    from slax_drake.scene.model import Scene
    from slax_drake.station.scenario import load_station_scenario

    station = load_station_scenario("sim_configs/station_sim_shelf.yaml")
    rmap = load_reach_map(station.reach_map)
    tool = tool_config(sim_scenario, "station")
    planner = MotionPlanner(station, tool)
    scene = Scene(shelf_of(sim_scenario), Camera.from_config(sim_scenario.camera), (), None, 0)
    rng = np.random.default_rng(17)
    checked = {"refused": 0, "accepted": 0}
    for layer in LAYERS:
        refused, accepted = [], []
        while len(refused) < 3 or len(accepted) < 3:
            x = rng.uniform(rmap.xs[0], rmap.xs[-1])
            y = rng.uniform(rmap.ys[0], rmap.ys[-1])
            i = min(len(rmap.xs) - 2, int(np.searchsorted(rmap.xs, x)) - 1)
            j = min(len(rmap.ys) - 2, int(np.searchsorted(rmap.ys, y)) - 1)
            if rmap.refuses(layer, x, y, 0.015) and len(refused) < 3:
                refused.append((x, y))
            elif rmap.reach[layer][j:j + 2, i:i + 2].all() and len(accepted) < 3:
                accepted.append((x, y))
        for (x, y), expected in [(p, False) for p in refused] + [(p, True) for p in accepted]:
            assert planner.reaches(scene, layer_waypoint(layer, x, y, scene, tool)) == expected, (layer, x, y)
            checked["refused" if not expected else "accepted"] += 1
    assert checked == {"refused": 9, "accepted": 9}


def _turned_map(refused_layers):
    """The toy grid with every turned-cup layer: the layers in ``refused_layers`` reach nothing, the others all."""
    from slax_drake.shelf.reach import turned_cup_layers, turned_cup_params

    xs, ys = np.array([0.0, 0.1, 0.2]), np.array([0.0, 0.1])
    reach = {n: np.full((2, 3), n not in refused_layers) for n in ("cup",) + turned_cup_layers()}
    reach["push+x"] = reach["push-x"] = np.ones((2, 3), bool)
    heights = {n: (turned_cup_params(n)[1] if n.startswith("cup@") else 0.1) for n in reach}
    return ReachMap("toy", xs, ys, reach, heights)


def test_a_turned_suction_is_refused_only_where_every_layer_around_refuses():
    rad = np.radians
    low = {"cup@-20/3cm", "cup@-30/3cm", "cup@-20/6cm", "cup@-30/6cm"}
    m = _turned_map(low)
    assert m.refuses_cup(0.1, 0.05, 0.045, rad(-25.0))  # the four layers around refuse
    assert m.refuses_cup(0.1, 0.05, 0.03, rad(-20.0))  # on a yaw node and a height node
    assert not m.refuses_cup(0.1, 0.05, 0.045, rad(-15.0))  # cup@-10 reaches
    assert not m.refuses_cup(0.1, 0.05, 0.08, rad(-25.0))  # the 10 cm layers reach
    assert not m.refuses_cup(0.1, 0.05, 0.02, rad(-25.0)) and not m.refuses_cup(0.1, 0.05, 0.15, rad(-25.0))
    assert not m.refuses_cup(0.1, 0.05, 0.045, rad(-35.0))  # beyond the layers' yaws
    assert not m.refuses_cup(0.5, 0.05, 0.045, rad(-25.0))  # off the grid
    # near yaw 0 the cup layer (one height, 10 cm) is a node: below 10 cm there is no yaw-0 layer to agree
    assert not _turned_map(low | {"cup", "cup@-10/3cm", "cup@-10/6cm"}).refuses_cup(0.1, 0.05, 0.045, rad(-5.0))
    assert _turned_map({"cup", "cup@-10/10cm"}).refuses_cup(0.1, 0.05, 0.10, rad(-5.0))
    assert _turned_map({"cup"}).refuses_cup(0.1, 0.05, 0.045, 0.0)  # yaw 0 reads the cup layer, as before
    plain = _toy_map()  # no turned layers: a turned suction is never refused
    assert not plain.refuses_cup(0.25, 0.05, 0.1, rad(-25.0)) and plain.refuses_cup(0.25, 0.05, 0.1, 0.0)
    again = ReachMap.from_dict(m.to_dict())
    assert again.refuses_cup(0.1, 0.05, 0.045, rad(-25.0)) and not again.refuses_cup(0.1, 0.05, 0.045, rad(-15.0))


@SHIPPED_MAPS
def test_the_shipped_maps_hold_the_turned_cup_layers(map_path):
    from slax_drake.shelf.reach import turned_cup_layers

    rmap = load_reach_map(map_path)
    for name in turned_cup_layers():
        layer = rmap.reach[name]
        assert layer.shape == rmap.reach["cup"].shape and layer[0].any() and not layer.all()


@pytest.mark.slow
@SHIPPED_STATIONS
def test_the_turned_cup_layers_agree_with_the_planner_on_a_sample_of_poses(request, station_file, scenario_fixture):
    """Seeded random contacts, heights and yaws (within the tool's 30 deg): each one the turned layers refuse has
    no collision-free IK solution of the cup at the seal from the observation pose; each one whose four grid
    nodes are reached in every layer around it has one."""
    from slax_drake.planning.reach import cup_waypoint
    from slax_drake.shelf.reach import TURNED_CUP_HEIGHTS, TURNED_CUP_YAWS_DEG, turned_cup_layer

    _, rmap, tool, planner, scene = _station_planner(request, station_file, scenario_fixture)
    yaws, heights = TURNED_CUP_YAWS_DEG, TURNED_CUP_HEIGHTS
    rng = np.random.default_rng(23)
    refused, accepted = [], []
    for _ in range(20000):
        if len(refused) >= 6 and len(accepted) >= 6:
            break
        x, y = rng.uniform(rmap.xs[0], rmap.xs[-1]), rng.uniform(rmap.ys[0], rmap.ys[-1])
        deg, z = rng.uniform(-30.0, 30.0), rng.uniform(heights[0], heights[-1])
        if abs(deg) < 10.0:  # the accepted ones need turned layers on both sides
            continue
        i = min(len(rmap.xs) - 2, int(np.searchsorted(rmap.xs, x)) - 1)
        j = min(len(rmap.ys) - 2, int(np.searchsorted(rmap.ys, y)) - 1)
        layers = [turned_cup_layer(d, h) for d in {max(n for n in yaws if n <= deg), min(n for n in yaws if n >= deg)}
                  for h in {max(n for n in heights if n <= z), min(n for n in heights if n >= z)}]
        if rmap.refuses_cup(x, y, z, np.radians(deg), 0.015):
            if len(refused) < 6:
                refused.append((x, y, z, deg))
        elif all(rmap.reach[k][j:j + 2, i:i + 2].all() for k in layers) and len(accepted) < 6:
            accepted.append((x, y, z, deg))
    assert len(refused) == 6 and len(accepted) == 6
    for (x, y, z, deg), expected in [(p, False) for p in refused] + [(p, True) for p in accepted]:
        got = planner.reaches(scene, cup_waypoint(x, y, np.radians(deg), scene, tool, z))
        assert got == expected, (x, y, z, deg)


def test_a_map_whose_turned_layer_has_the_wrong_shape_is_one_config_error(tmp_path):
    """A hand-edited map with a truncated turned-cup layer is refused by name, not with a traceback later."""
    import json

    from slax_drake.config import REPO_ROOT
    from slax_drake.errors import ConfigError

    data = json.loads((REPO_ROOT / "models/reach/station_sim_shelf.json").read_text())
    turned = next(k for k in data["reach"] if k not in LAYERS)
    data["reach"][turned] = data["reach"][turned][:-1]  # one row short
    path = tmp_path / "bad_map.json"
    path.write_text(json.dumps(data))
    with pytest.raises(ConfigError, match=f"layer '{turned}' is"):
        load_reach_map(str(path))


def test_a_release_is_refused_where_the_back_off_or_the_retract_layer_refuses():
    m = _toy_map()
    assert not m.refuses_release(0.25, 0.05)  # no release layers: nothing refused
    ok, bad = np.ones((3, 4), bool), np.array([[True, True, False, False]] * 3)
    with_back = ReachMap("toy", m.xs, m.ys, {**m.reach, "back off": bad, "retract": ok}, m.heights)
    assert with_back.refuses_release(0.25, 0.05) and not with_back.refuses_release(0.05, 0.05)
    with_retract = ReachMap("toy", m.xs, m.ys, {**m.reach, "back off": ok, "retract": bad}, m.heights)
    assert with_retract.refuses_release(0.25, 0.05) and not with_retract.refuses_release(0.15, 0.05)


@SHIPPED_MAPS
def test_the_shipped_maps_hold_the_release_layers(map_path):
    from slax_drake.shelf.reach import RELEASE_LAYERS

    rmap = load_reach_map(map_path)
    for name in RELEASE_LAYERS:
        layer = rmap.reach[name]
        assert layer.shape == rmap.reach["cup"].shape and layer.any()
    assert not rmap.reach["back off"].all()  # the back-left corner, deep in the bay
    assert (rmap.reach["retract"] == rmap.reach["retract"][0]).all()  # in front of the opening: the same for every y


def test_the_action_model_keeps_no_placement_the_release_layers_refuse(sim_scenario):
    """With the station's map, no yaw-0 suction it offers releases where the back-off or retract layer refuses."""
    from slax_drake.scene.sampling import sample_scene
    from slax_drake.shelf.actions import REACH_MARGIN, Suction

    rmap = load_reach_map(SIM_MAP)
    tool = tool_config(sim_scenario, "station", reach_map=SIM_MAP, max_suction_moment=float("inf"))
    offered = 0
    for seed in range(3):
        scene = sample_scene(sim_scenario, 4, seed)
        model = ActionModel(shelf_of(sim_scenario), scene.camera.position, tool)
        for a in model.enumerate(scene.objects).feasible:
            if isinstance(a, Suction) and a.yaw == 0.0:
                obj = next(o for o in scene.objects if o.name == a.name)
                x, y = a.q[0] + a.dx, a.q[1] + (a.dz - float(obj.center[1]))
                assert not rmap.refuses_release(x, y, REACH_MARGIN), a
                offered += 1
    assert offered


@pytest.mark.slow
@SHIPPED_STATIONS
def test_the_release_layers_agree_with_the_planner_on_a_sample_of_poses(request, station_file, scenario_fixture):
    """Seeded random release contacts: each one the back-off (or retract) layer refuses has no collision-free IK
    solution of that waypoint from the observation pose (the retract at neither approach margin); each one in a
    cell whose four nodes were reached has one."""
    from slax_drake.planning.reach import release_waypoint
    from slax_drake.planning.waypoints import APPROACH_MARGINS

    _, rmap, tool, planner, scene = _station_planner(request, station_file, scenario_fixture)
    rng = np.random.default_rng(29)
    for layer in ("back off", "retract"):
        refused, accepted = [], []
        want = 0 if rmap.reach[layer].all() else 3  # the sim map's retract layer reaches everywhere
        for _ in range(20000):
            if len(refused) >= want and len(accepted) >= 3:
                break
            x, y = rng.uniform(rmap.xs[0], rmap.xs[-1]), rng.uniform(rmap.ys[0], rmap.ys[-1])
            i = min(len(rmap.xs) - 2, int(np.searchsorted(rmap.xs, x)) - 1)
            j = min(len(rmap.ys) - 2, int(np.searchsorted(rmap.ys, y)) - 1)
            if rmap.refuses(layer, x, y, 0.015):
                if len(refused) < want:
                    refused.append((x, y))
            elif rmap.reach[layer][j:j + 2, i:i + 2].all() and len(accepted) < 3:
                accepted.append((x, y))
        assert len(refused) == want and len(accepted) == 3, layer
        margins = APPROACH_MARGINS if layer == "retract" else (None,)
        for (x, y), expected in [(p, False) for p in refused] + [(p, True) for p in accepted]:
            got = any(planner.reaches(scene, release_waypoint(layer, x, y, scene, tool, m)) for m in margins)
            assert got == expected, (layer, x, y)


def _hold_map(refused_layers=(), refuse_x_above=None):
    """The toy grid with every hold layer on hold rows y = -0.4 .. 0.2: the layers in ``refused_layers`` reach
    nothing (or, with ``refuse_x_above``, nothing beyond that x), the others everything."""
    from slax_drake.shelf.reach import hold_layers

    m = _toy_map()
    hold_ys = np.array([-0.4, -0.2, 0.0, 0.2])
    hold = {}
    for name in hold_layers():
        ok = np.ones((len(hold_ys), len(m.xs)), bool)
        if name in refused_layers:
            ok[:] = False if refuse_x_above is None else (m.xs <= refuse_x_above)[None, :]
        hold[name] = ok
    return ReachMap("toy", m.xs, m.ys, m.reach, m.heights, hold_ys, hold)


def test_a_hold_pose_is_refused_only_where_every_layer_around_its_yaw_and_heights_refuses():
    from slax_drake.shelf.reach import hold_layer

    rad = np.radians
    low = {hold_layer(d, h) for d in (0, 15) for h in (0.03, 0.11)}
    m = _hold_map(low)
    assert m.refuses_hold(0.1, -0.3, 0.05, 0.08, rad(5.0))  # yaw nodes 0 and 15, heights 3 and 11 cm: all refuse
    assert m.refuses_hold(0.1, -0.3, 0.03, 0.03, 0.0)  # on a yaw node and a height node
    assert not m.refuses_hold(0.1, -0.3, 0.05, 0.15, rad(5.0))  # the 20 cm layers reach
    assert not m.refuses_hold(0.1, -0.3, 0.05, 0.08, rad(-5.0))  # the -15 deg layers reach
    assert not m.refuses_hold(0.1, -0.3, 0.05, 0.40, rad(5.0))  # above the highest node: not refused
    assert not m.refuses_hold(0.1, -0.3, 0.02, 0.05, rad(5.0))  # below the lowest node
    assert not m.refuses_hold(0.1, -0.3, 0.05, 0.08, rad(35.0))  # beyond the yaw nodes
    assert not m.refuses_hold(0.1, -0.5, 0.05, 0.08, rad(5.0))  # off the hold grid (in front of its first row)
    # a layer missing from the map refuses nothing: drop one of the four
    missing = ReachMap("toy", m.xs, m.ys, m.reach, m.heights, m.hold_ys,
                       {k: v for k, v in m.hold.items() if k != hold_layer(15, 0.11)})
    assert not missing.refuses_hold(0.1, -0.3, 0.05, 0.08, rad(5.0))
    again = ReachMap.from_dict(m.to_dict())
    assert again.refuses_hold(0.1, -0.3, 0.05, 0.08, rad(5.0)) and (again.hold_ys == m.hold_ys).all()
    # the vectorised verdicts agree with the scalar lookup
    xs, ys = np.meshgrid(np.linspace(-0.1, 0.4, 11), np.linspace(-0.5, 0.3, 9))
    many = m.hold_refusals(xs, ys, rad(5.0), 0.015)
    for idx in np.ndindex(xs.shape):
        assert (many[idx] == m.hold_refusals(float(xs[idx]), float(ys[idx]), rad(5.0), 0.015)).all()


def test_a_map_without_hold_layers_loads_and_refuses_no_hold_pose(tmp_path):
    import json

    m = _toy_map()
    assert not m.hold and not m.refuses_hold(0.25, 0.05, 0.05, 0.05, 0.0)
    data = m.to_dict()
    assert "hold" not in data and "hold_ys" not in data  # an older map's keys, no more
    path = tmp_path / "old_map.json"
    path.write_text(json.dumps(data))
    loaded = load_reach_map(str(path))
    assert not loaded.hold and not loaded.refuses_hold(0.25, 0.05, 0.05, 0.05, 0.0)


def test_a_map_whose_hold_layer_has_the_wrong_shape_is_one_config_error(tmp_path):
    import json

    from slax_drake.errors import ConfigError

    import re

    data = _hold_map().to_dict()
    name = next(iter(data["hold"]))
    data["hold"][name] = data["hold"][name][:-1]
    path = tmp_path / "bad_hold.json"
    path.write_text(json.dumps(data))
    with pytest.raises(ConfigError, match=re.escape(f"hold layer '{name}' is 3 x 4, not 4 x 4")):
        load_reach_map(str(path))


@SHIPPED_MAPS
def test_the_shipped_maps_hold_the_hold_layers(map_path):
    from slax_drake.shelf.reach import hold_layers

    rmap = load_reach_map(map_path)
    assert rmap.hold_ys[0] < -0.5 and rmap.hold_ys[-1] == rmap.ys[-1]  # from well in front of the opening to the back
    for name in hold_layers():
        layer = rmap.hold[name]
        assert layer.shape == (len(rmap.hold_ys), len(rmap.xs)) and layer.any() and not layer.all(), name


@SHIPPED_MAPS
def test_the_shipped_maps_hold_the_pre_approach_layers(map_path):
    from slax_drake.shelf.reach import hold_layers

    rmap = load_reach_map(map_path)
    assert max(rmap.approach_ys) < rmap.ys[0]  # in front of the bay's first row of nodes
    layers = [rmap.approach[name] for name in hold_layers("approach")]
    for name, layer in zip(hold_layers("approach"), layers):
        assert layer.shape == (len(rmap.approach_ys), len(rmap.approach_xs)) and layer.any(), name
    assert not all(layer.all() for layer in layers)  # far to the side the arm does not reach


def _hold_tool(sim_scenario, tmp_path, rmap):
    import json

    path = tmp_path / "hold_map.json"
    path.write_text(json.dumps(rmap.to_dict()))
    load_reach_map.cache_clear()
    return tool_config(sim_scenario, "station", reach_map=str(path), max_suction_moment=float("inf"))


def test_the_action_model_refuses_the_carries_the_hold_layers_refuse(sim_scenario, tmp_path):
    """A box near the front, suctioned: with hold layers that reach everything the action model offers what it
    offers without them; with layers that refuse every cup pose right of x = 0 it keeps only the placements whose
    carry stays left of it; with layers that refuse everything the suction is refused, typed REACH_MAP."""
    import dataclasses

    from slax_drake.shelf.actions import RefusalKind, Suction
    from slax_drake.shelf.reach import hold_layers

    shelf = shelf_of(sim_scenario)
    sim = load_reach_map(SIM_MAP)
    box = SceneObject("b", "box", (0.08, 0.08, 0.10), planar_pose(-0.12, -0.18, 0.05, 0.0))

    def suctions(rmap):
        model = ActionModel(shelf, (0.0, -0.75, 0.2), _hold_tool(sim_scenario, tmp_path, rmap))
        c = model.enumerate((box,), pushes=False)
        return [a for a in c.feasible if isinstance(a, Suction)], c.rejected

    hold_ys = np.linspace(-0.57, 0.25, 15)
    shape = (len(hold_ys), len(sim.xs))

    def with_hold(hold):
        return dataclasses.replace(sim, hold_ys=hold_ys, hold=hold)

    everywhere = {k: np.ones(shape, bool) for k in hold_layers()}
    none_held, _ = suctions(dataclasses.replace(sim, hold_ys=np.zeros(0), hold={}))
    all_held, _ = suctions(with_hold(everywhere))
    assert none_held and all_held == none_held
    left = {k: np.broadcast_to(sim.xs <= 0.0, shape).copy() for k in hold_layers()}
    kept, _ = suctions(with_hold(left))
    assert kept and len(kept) < len(none_held)
    assert all(a.q[0] + a.dx <= 0.0 + 0.05 for a in kept)  # the cup across stays within a cell of x = 0
    assert [a for a in none_held if a.q[0] + a.dx > 0.1] and not [a for a in kept if a.q[0] + a.dx > 0.1]
    nowhere = {k: np.zeros(shape, bool) for k in hold_layers()}
    gone, rejected = suctions(with_hold(nowhere))
    assert not gone
    why = [r for r in rejected if r.what == "suction b"]
    assert why and why[0].kind is RefusalKind.REACH_MAP and "carry" in why[0].reason
    load_reach_map.cache_clear()


@pytest.mark.slow
@SHIPPED_STATIONS
def test_a_carry_pose_the_hold_layers_refuse_has_no_ik_solution(request, station_file, scenario_fixture):
    """Seeded random cup poses of a carry (x across the bay, y from in front of the opening to its back, height
    3-36 cm, tool yaw within +-30 deg): each one the hold layers refuse has no collision-free IK solution from the
    observation pose; each one whose grid cells are reached in every layer around it has one."""
    from slax_drake.planning.reach import hold_waypoint
    from slax_drake.shelf.reach import HOLD_HEIGHTS, HOLD_YAWS_DEG, hold_layer

    _, rmap, _, planner, scene = _station_planner(request, station_file, scenario_fixture)
    yaws, heights, xs, ys = HOLD_YAWS_DEG, HOLD_HEIGHTS, rmap.xs, rmap.hold_ys
    rng = np.random.default_rng(31)
    refused, accepted = [], []
    for _ in range(20000):
        if len(refused) >= 8 and len(accepted) >= 4:
            break
        x, y = rng.uniform(xs[0], xs[-1]), rng.uniform(ys[0], ys[-1])
        deg, z = rng.uniform(yaws[0], yaws[-1]), rng.uniform(heights[0], heights[-1])
        if rmap.refuses_hold(x, y, z, z, np.radians(deg), 0.015):
            if len(refused) < 8:
                refused.append((x, y, z, deg))
            continue
        i = min(len(xs) - 2, int(np.searchsorted(xs, x)) - 1)
        j = min(len(ys) - 2, int(np.searchsorted(ys, y)) - 1)
        layers = [hold_layer(d, h) for d in {max(n for n in yaws if n <= deg), min(n for n in yaws if n >= deg)}
                  for h in {max(n for n in heights if n <= z), min(n for n in heights if n >= z)}]
        if all(rmap.hold[k][j:j + 2, i:i + 2].all() for k in layers) and len(accepted) < 4:
            accepted.append((x, y, z, deg))
    assert len(refused) == 8 and len(accepted) == 4
    for (x, y, z, deg), expected in [(p, False) for p in refused] + [(p, True) for p in accepted]:
        assert planner.reaches(scene, hold_waypoint(x, y, z, np.radians(deg))) == expected, (x, y, z, deg)


def test_the_hold_waypoint_is_the_translate_waypoint_of_a_carry():
    """The hold layers are computed at the pose the planner's carry puts the cup at: a suction's translate
    waypoint (turned carry included) is :func:`hold_waypoint` at its position and the tool's yaw."""
    from slax_drake.planning.reach import hold_waypoint
    from slax_drake.planning.waypoints import action_waypoints
    from slax_drake.shelf.actions import Suction
    from slax_drake.config import load_scenario

    shelf = shelf_of(load_scenario("sim_configs/sim_shelf.yaml"))
    box = SceneObject("b", "box", (0.08, 0.08, 0.10), planar_pose(-0.12, -0.18, 0.05, 0.0))
    action = Suction("b", (-0.12, -0.22, 0.06), 0.2, -0.1, np.radians(10.0))
    for carry_yaw in (0.0, np.radians(30.0)):
        wps = {w.label: w for w in action_waypoints(action, (box,), shelf, carry_yaw=carry_yaw)}
        for label, yaw in (("translate", action.yaw + carry_yaw), ("lower", action.yaw)):
            w, h = wps[label], hold_waypoint(*wps[label].position, yaw)
            assert np.allclose(w.X_SF, h.X_SF) and (w.frame, w.shaft, w.suction) == (h.frame, h.shaft, h.suction)


def test_a_pre_approach_is_refused_only_where_every_layer_around_it_refuses():
    from slax_drake.shelf.reach import hold_layer, hold_layers

    rad = np.radians
    m = _toy_map()
    xs, ys = np.linspace(-0.6, 0.6, 25), np.array([-0.35, -0.31])
    far_right = np.broadcast_to(xs < 0.3, (2, 25))
    from slax_drake.shelf.reach import APPROACH_YAWS_DEG

    turned = {hold_layer(d, h, "approach") for d in APPROACH_YAWS_DEG if d <= -15 for h in (0.03, 0.11)}
    approach = {k: (far_right.copy() if k in turned else np.ones((2, 25), bool)) for k in hold_layers("approach")}
    m = ReachMap("toy", m.xs, m.ys, m.reach, m.heights, approach_xs=xs, approach_ys=ys, approach=approach)
    assert m.refuses_approach(0.45, -0.35, 0.06, rad(-20.0))  # right of x = 0.3, yaw -30..-15, 3..11 cm
    assert m.refuses_approach(0.45, -0.35, 0.06, rad(-17.0))  # between the nodes -20 and -15, both refuse
    assert not m.refuses_approach(0.2, -0.35, 0.06, rad(-20.0))  # left of it
    assert not m.refuses_approach(0.45, -0.35, 0.15, rad(-20.0))  # the 20 cm layers reach
    assert not m.refuses_approach(0.45, -0.35, 0.06, rad(-12.0))  # the -10 deg layers reach
    assert not m.refuses_approach(0.7, -0.35, 0.06, rad(-20.0))  # off the grid
    assert not _toy_map().refuses_approach(0.45, -0.35, 0.06, rad(-20.0))  # a map without the layers
    again = ReachMap.from_dict(m.to_dict())
    assert again.refuses_approach(0.45, -0.35, 0.06, rad(-20.0)) and np.allclose(again.approach_xs, xs)


def test_the_action_model_refuses_a_suction_whose_pre_approach_the_map_refuses(sim_scenario, tmp_path):
    """A box turned 20 deg near the bay's left wall, suctioned with the tool turned: offered with pre-approach
    layers that reach everything, refused (typed REACH_MAP) with layers that reach nothing."""
    import dataclasses

    from slax_drake.shelf.actions import RefusalKind, Suction
    from slax_drake.shelf.reach import hold_layers

    shelf = shelf_of(sim_scenario)
    sim = load_reach_map(SIM_MAP)
    box = SceneObject("b", "box", (0.08, 0.08, 0.10), planar_pose(-0.2, 0.0, 0.05, np.radians(-20.0)))
    xs, ys = np.linspace(-0.6, 0.6, 25), np.array([-0.35, -0.31])

    def suctions(value):
        rmap = dataclasses.replace(sim, approach_xs=xs, approach_ys=ys,
                                   approach={k: np.full((2, 25), value) for k in hold_layers("approach")})
        model = ActionModel(shelf, (0.0, -0.75, 0.2), _hold_tool(sim_scenario, tmp_path, rmap))
        c = model.enumerate((box,), pushes=False)
        return [a for a in c.feasible if isinstance(a, Suction)], [r for r in c.rejected if r.what == "suction b"]

    offered, _ = suctions(True)
    assert offered and offered[0].yaw != 0.0
    gone, why = suctions(False)
    assert not gone and why[0].kind is RefusalKind.REACH_MAP and "in front of the opening" in why[0].reason
    load_reach_map.cache_clear()


@pytest.mark.slow
@SHIPPED_STATIONS
def test_a_pre_approach_the_layers_refuse_has_no_ik_solution(request, station_file, scenario_fixture):
    """Seeded random pre-approach poses (x across the layers' width, at either approach margin, 3-20 cm high, the
    tool turned within +-30 deg): each one the pre-approach layers refuse has no collision-free IK solution from
    the observation pose."""
    from slax_drake.planning.reach import hold_waypoint
    from slax_drake.shelf.reach import APPROACH_HEIGHTS as HEIGHTS, HOLD_YAWS_DEG

    _, rmap, _, planner, scene = _station_planner(request, station_file, scenario_fixture)
    rng = np.random.default_rng(37)
    refused = []
    for _ in range(20000):
        if len(refused) >= 8:
            break
        x, y = rng.uniform(rmap.approach_xs[0], rmap.approach_xs[-1]), float(rng.choice(rmap.approach_ys))
        deg, z = rng.uniform(HOLD_YAWS_DEG[0], HOLD_YAWS_DEG[-1]), rng.uniform(HEIGHTS[0], HEIGHTS[-1])
        if rmap.refuses_approach(x, y, z, np.radians(deg), 0.015):
            refused.append((x, y, z, deg))
    assert len(refused) == 8
    for x, y, z, deg in refused:
        assert not planner.reaches(scene, hold_waypoint(x, y, z, np.radians(deg), suction=False)), (x, y, z, deg)


def test_adding_floor_layers_to_a_map_keeps_its_hold_and_pre_approach_layers(tmp_path):
    """``python -m slax_drake.planning.reach --add-release`` (or ``--add-turned-cup``) on a map that already holds the
    hold and pre-approach layers writes them back unchanged (they were dropped, and an hour of layers with them)."""
    import json
    import shutil

    from slax_drake.config import REPO_ROOT
    from slax_drake.planning.reach import main

    path = tmp_path / "map.json"
    shutil.copy(REPO_ROOT / SIM_MAP, path)
    before = json.loads(path.read_text())
    assert before["hold"] and before["approach"]
    assert main(["--station", "sim_configs/station_sim_shelf.yaml", "--out", str(path), "--add-release"]) == 0
    assert json.loads(path.read_text()) == before  # every release layer was there: nothing to add, nothing lost


def test_adding_layers_to_a_malformed_map_is_one_error_line_and_exit_2(tmp_path, capsys):
    """``--add-*`` on a file that is not a reach map: one line naming it, exit code 2, the file left as it was."""
    from slax_drake.planning.reach import main

    path = tmp_path / "map.json"
    path.write_text('{"bad": 1}\n')
    assert main(["--station", "sim_configs/station_sim_shelf.yaml", "--out", str(path), "--add-release"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("error: ") and "not a reach map" in err and "\n" not in err
    assert path.read_text() == '{"bad": 1}\n'
