"""The placement search over reach maps (issue 17 item 3): the ranking picks the better of two measured
candidates, bad grids are refused with one line, and (slow) the search with Drake IK on a tiny grid picks the
placement whose reach map covers more of the bay."""

import numpy as np
import pytest

from slax_drake.planning.placement import Candidate, Evaluated, choose, main, subgrid
from slax_drake.shelf.reach import LAYERS

STATION = "sim_configs/station_sim_shelf.yaml"


def _measured(candidate, reached_rows, n_x=3, n_y=3):
    """An Evaluated whose nodes of rows j < reached_rows are reached in every layer."""
    nodes = {(layer, i, j): j < reached_rows for layer in LAYERS for i in range(n_x) for j in range(n_y)}
    return Evaluated(candidate, np.zeros(9), nodes=nodes)


def test_subgrid_keeps_every_stride_th_node_and_the_last():
    assert subgrid(5, 4, 2) == [(i, j) for j in (0, 2, 3) for i in (0, 2, 4)]
    assert len(subgrid(5, 4, 1)) == 20


def test_the_ranking_picks_the_candidate_that_reaches_more_and_breaks_ties_by_nearness():
    here = Candidate(0.45, 0.20, 0.03)
    near, far = Candidate(0.40, 0.20, 0.05), Candidate(0.30, 0.10, 0.25)
    nodes = subgrid(3, 3, 1)
    assert choose([_measured(near, 2), _measured(far, 3)], nodes, here).candidate == far
    assert choose([_measured(far, 2), _measured(near, 2)], nodes, here).candidate == near
    # the worst layer decides between equal means
    a, b = _measured(near, 2), _measured(far, 2)
    for i in range(3):
        a.nodes[("cup", i, 2)], a.nodes[("push+x", i, 1)] = True, False  # same mean, worst layer lower
    assert choose([a, b], nodes, here).candidate == far


@pytest.mark.parametrize("args, message", [
    (["--torso", "0.5"], "outside the torso's travel"),
    (["--camera-x"], None),  # argparse: nargs="+" needs a value (exit 2 by argparse)
    (["--top", "0"], "at least 1"),
    (["--step", "-0.1"], "positive number of metres"),
])
def test_a_bad_grid_is_one_line_and_exit_2(args, message, capsys):
    if message is None:
        with pytest.raises(SystemExit) as e:
            main(["--station", STATION, *args])
        assert e.value.code == 2
        return
    assert main(["--station", STATION, *args, "--no-progress"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0]


def test_the_winners_map_holds_the_heights_of_its_own_layers_only():
    """The map --out-map writes has the three measured layers and their heights (not the turned-cup layers' heights,
    which it does not hold)."""
    from types import SimpleNamespace

    from slax_drake.planning.placement import PlacementSearch
    from slax_drake.config import load_scenario
    from slax_drake.shelf.tool import tool_config

    tool = tool_config(load_scenario("sim_configs/table1.yaml"), "station")
    fake = SimpleNamespace(station_path=STATION, xs=np.array([0.0, 0.1, 0.2]), ys=np.array([0.0, 0.1, 0.2]), tool=tool)
    rmap = PlacementSearch.reach_map(fake, _measured(Candidate(0.4, 0.2, 0.05), 2))
    assert set(rmap.reach) == set(rmap.heights) == set(LAYERS)
    assert rmap.reach["cup"][:2].all() and not rmap.reach["cup"][2].any()  # rows j < 2 reached


def test_a_missing_station_is_one_line_and_exit_2(capsys, tmp_path):
    assert main(["--station", str(tmp_path / "none.yaml"), "--no-progress"]) == 2
    assert "no such station file" in capsys.readouterr().err


@pytest.mark.slow
def test_the_search_picks_the_placement_that_reaches_deeper():
    """Two candidates on a 0.25 m grid: the camera 0.35 m in front of the base and 0.60 m (the bay 0.25 m farther
    away, its back out of reach). The search picks the near one, whose observation pose is collision-free and puts
    the camera where asked, and it covers at least as much of every layer as the far one."""
    from slax_drake.planning.placement import PlacementSearch, search, with_observation
    from slax_drake.planning.world import PlanningWorld
    from slax_drake.station.plant import camera_pose_at

    winner, evaluated, own, ps = search(STATION, [0.35, 0.60], [0.20], [0.10], coarse_stride=1, top=2,
                                        progress=False, step=0.25)
    assert winner.candidate == Candidate(0.35, 0.20, 0.10)
    far = next(e for e in evaluated if e.candidate.camera_x == 0.60)
    assert far.q_obs is not None
    full = subgrid(len(ps.xs), len(ps.ys), 1)
    cw, cf = winner.coverage(full), far.coverage(full)
    assert all(cw[k][0] >= cf[k][0] for k in LAYERS) and sum(cw[k][0] for k in LAYERS) > sum(cf[k][0] for k in LAYERS)
    station = with_observation(ps.station, winner.q_obs)
    p = camera_pose_at(station, winner.q_obs).translation()
    assert np.allclose(p[:2], [0.35, 0.20], atol=1e-3)
    assert PlanningWorld(station, ps.scene).config_free(winner.q_obs)
    again = PlacementSearch(STATION, seed=0, step=0.25).evaluate(winner.candidate)
    assert np.array_equal(again.q_obs, winner.q_obs)  # deterministic
