"""slax-drake export: trial.json -> per-motion JointTrajectory messages in three formats, strict parsing back."""

import json

import numpy as np
import pytest
from trial_records import fake_trial

from slax_drake.cli import main
from slax_drake.hardware.export import export_trial
from slax_drake.hardware.fetch_limits import FETCH_JOINTS
from slax_drake.errors import TrajectoryFileError
from slax_drake.hardware.trajectory_file import load_trajectory, save_trajectory


@pytest.fixture(scope="module")
def trial():
    return fake_trial()


def _same(a, b, time_tol=0.0):
    assert len(a.motions) == len(b.motions)
    for m1, m2 in zip(a.motions, b.motions):
        assert m1.start_time == m2.start_time
        np.testing.assert_allclose(m2.times, m1.times, rtol=0, atol=time_tol)
        for x in ("q", "v", "a"):
            np.testing.assert_array_equal(getattr(m2, x), getattr(m1, x))
        assert [(pytest.approx(t, abs=time_tol), on) for t, on in m1.suction_events] == m2.suction_events
        assert m2.action == m1.action


@pytest.mark.parametrize("ext,time_tol", [(".json", 0.0), (".yaml", 1e-9), (".csv", 0.0)])
def test_every_format_parses_back(trial, tmp_path, ext, time_tol):
    traj = export_trial(trial)
    path = tmp_path / f"traj{ext}"
    save_trajectory(traj, path)
    back = load_trajectory(path)
    assert back.joint_names == FETCH_JOINTS
    _same(traj, back, time_tol)


def test_motions_cut_at_decision_times_with_exact_end_points(trial):
    traj = export_trial(trial)
    full = trial["full_trajectory"]
    assert [m.start_time for m in traj.motions] == [e["time"] for e in trial["steps_log"]]
    for m, action in zip(traj.motions, trial["actions"]):
        assert m.duration == pytest.approx(action["motion"]["duration_s"], abs=1e-9)
        # every point equals the 1 ms trajectory at its time (records rounded to 1e-6)
        k = np.rint((m.times + m.start_time) / 0.001).astype(int)
        np.testing.assert_allclose(m.q, full.q[k], atol=1e-6, rtol=0)
        np.testing.assert_allclose(m.v[[0, -1]], 0.0, atol=1e-6)
    assert traj.motions[1].suction_events == [(0.27, True), (0.63, False)]
    assert traj.motions[0].suction_events == []


def test_rate_resamples_on_a_uniform_clock_and_keeps_records(trial):
    native = export_trial(trial)
    for rate in (100.0, 1000.0):
        traj = export_trial(trial, rate=rate)
        full = trial["full_trajectory"]
        for m0, m in zip(native.motions, traj.motions):
            assert m.times[-1] == m0.times[-1]
            np.testing.assert_allclose(np.diff(m.times[:-1]), 1.0 / rate, atol=1e-12)
            k = np.rint((m.times + m.start_time) / 0.001).astype(int)
            # quintic positions: within 2e-6 of the exact 1 ms profile (the records are rounded to 1e-6)
            np.testing.assert_allclose(m.q, full.q[k], atol=2e-6, rtol=0)
        if rate == 100.0:  # the 10 ms records themselves, except where the start was not on a record
            np.testing.assert_allclose(traj.motions[0].q, native.motions[0].q, atol=1e-12, rtol=0)


def test_yaml_is_a_follow_joint_trajectory_goal(trial, tmp_path):
    import yaml

    path = tmp_path / "t.yaml"
    save_trajectory(export_trial(trial), path)
    doc = yaml.safe_load(path.read_text())
    goal = doc["motions"][0]["goal"]
    assert set(goal) == {"trajectory", "path_tolerance", "goal_tolerance", "goal_time_tolerance"}
    assert goal["trajectory"]["joint_names"] == list(FETCH_JOINTS)
    p = goal["trajectory"]["points"][1]
    assert p["time_from_start"] == {"secs": 0, "nsecs": 10_000_000}
    assert len(p["positions"]) == len(p["velocities"]) == len(p["accelerations"]) == 9


def _write_bad(tmp_path, name, text):
    p = tmp_path / name
    p.write_text(text)
    return p


@pytest.mark.parametrize("ext", [".json", ".yaml", ".csv"])
def test_truncated_files_give_clear_errors(trial, tmp_path, ext):
    good = tmp_path / f"good{ext}"
    save_trajectory(export_trial(trial), good)
    text = good.read_text()
    for cut in (0.3, 0.6, 0.95):
        bad = _write_bad(tmp_path, f"bad{ext}", text[: int(len(text) * cut)])
        with pytest.raises(TrajectoryFileError, match="bad"):
            load_trajectory(bad)


def test_corrupt_content_errors(trial, tmp_path):
    doc = json.loads(json.dumps(json.loads(_json(trial, tmp_path))))
    cases = {
        "wrong joint names": lambda d: d["joint_names"].__setitem__(0, "torso_joint"),
        "wrong message joints": lambda d: d["motions"][0]["trajectory"]["joint_names"].reverse(),
        "non-monotonic": lambda d: d["motions"][0]["trajectory"]["points"][5].__setitem__("time_from_start", 0.01),
        "nan": lambda d: d["motions"][0]["trajectory"]["points"][3].__setitem__("positions", [None] * 9),
        "short vector": lambda d: d["motions"][1]["trajectory"]["points"][3]["velocities"].pop(),
        "overlap": lambda d: d["motions"][1].__setitem__("start_time", 0.6),
        "format": lambda d: d.__setitem__("format", "other"),
    }
    messages = {}
    for name, edit in cases.items():
        d = json.loads(json.dumps(doc))
        edit(d)
        p = _write_bad(tmp_path, "c.json", json.dumps(d))
        with pytest.raises(TrajectoryFileError) as e:
            load_trajectory(p)
        messages[name] = str(e.value)
    assert "torso_joint" in messages["wrong joint names"]
    assert "not strictly increasing" in messages["non-monotonic"]
    assert "not monotonic" in messages["overlap"]
    with pytest.raises(TrajectoryFileError, match="no such file"):
        load_trajectory(tmp_path / "missing.json")
    with pytest.raises(TrajectoryFileError, match="extension"):
        load_trajectory(_write_bad(tmp_path, "x.txt", "1"))


def _json(trial, tmp_path):
    p = tmp_path / "ref.json"
    save_trajectory(export_trial(trial), p)
    return p.read_text()


def test_cli_export_and_bad_input_exit_codes(trial, tmp_path, capsys):
    data = {k: v for k, v in trial.items() if k != "full_trajectory"}
    src = tmp_path / "trial.json"
    src.write_text(json.dumps(data))
    scene = tmp_path / "scene.json"
    from slax_drake.config import load_scenario
    from slax_drake.scene.io import save_scene
    from slax_drake.scene.sampling import sample_scene

    save_scene(sample_scene(load_scenario("sim_configs/sim_shelf.yaml"), 2, seed=3), scene)
    for fmt, ext in (("ros-json", "json"), ("ros-yaml", "yaml"), ("csv", "csv")):
        out = tmp_path / f"t.{ext}"
        assert main(["export", str(src), "--format", fmt, "--rate", "100", "--scene", str(scene), "--out", str(out)]) == 0
        assert len(load_trajectory(out).motions) == 2
    # the trial's folder names its trial.json, as for view-trial
    assert main(["export", str(tmp_path), "--scene", str(scene), "--out", str(tmp_path / "f.json")]) == 0
    assert len(load_trajectory(tmp_path / "f.json").motions) == 2
    empty = tmp_path / "empty"
    empty.mkdir()
    capsys.readouterr()
    assert main(["export", str(empty), "--out", str(tmp_path / "e.json")]) == 2
    assert f"{empty / 'trial.json'}: no such file" in capsys.readouterr().err
    src.write_text(json.dumps(data)[:-200])
    capsys.readouterr()
    assert main(["export", str(src), "--out", str(tmp_path / "u.json")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "not valid JSON" in err[0]
    bad = _write_bad(tmp_path, "b.csv", "# something else\n")
    assert main(["check-trajectory", str(bad), "--no-collision"]) == 2
    assert main(["replay", str(bad)]) == 2


def test_a_guard_stopped_suction_exports_as_its_motion_up_to_the_stop_and_the_stop_motion():
    """A guarded suction whose push-in the trial's guard stopped: two motions, the first ending at the stop (its
    action's guarded_push_in.stopped_at_s), the suction on until then; the stop motion after it, starting at the stop
    on the trial clock. A guarded suction that completed keeps one motion with its window; a malformed stop record
    is refused."""
    import pytest

    from slax_drake.errors import TrialFileError
    from slax_drake.hardware.export import _segments, guarded_window

    motion = {"duration_s": 12.0, "suction_intervals": [[3.0, 8.0]],
              "waypoint_times": [["pre-approach", 2.0], ["seal", 3.0], ["pull", 4.0], ["push in", 8.0],
                                 ["release", 8.0], ["retract", 12.0]]}
    action = {"type": "suction", "object": "track_1", "guarded": True, "motion": motion,
              "guard": {"guarded": True, "stopped": True, "threshold_n": 5.0, "stop_time": 15.0,
                        "stop_motion": {"duration_s": 3.5, "suction_intervals": [[0.0, 0.3]]}}}
    assert guarded_window(action) == (4.0, 8.0)
    (t0, d0, on0, act0, stop0), (t1, d1, on1, act1, stop1) = _segments({"time": 10.0}, action, {"type": "suction"}, None)
    assert (t0, d0, on0, stop0) == (10.0, 5.0, [(3.0, 5.0)], False)
    assert act0["guarded_push_in"] == {"t_start_s": 4.0, "t_end_s": 8.0, "stop_force_n": 5.0, "stopped_at_s": 5.0}
    assert (t1, d1, on1, stop1) == (15.0, 3.5, [(0.0, 0.3)], True) and act1["guard_stop_motion"]
    completed = {**action, "guard": {"guarded": True, "stopped": False, "threshold_n": 5.0}}
    ((_, d, _, act, _),) = _segments({"time": 10.0}, completed, {"type": "suction"}, None)
    assert d == 12.0 and "stopped_at_s" not in act["guarded_push_in"]
    plain = {**action, "guarded": False}
    assert _segments({"time": 10.0}, plain, {"type": "suction"}, None)[0][3] == {"type": "suction"}
    with pytest.raises(TrialFileError, match="guard stop's record is malformed"):
        _segments({"time": 10.0}, {**action, "guard": {"stopped": True, "stop_time": 15.0}}, {}, "t.json")
    with pytest.raises(TrialFileError, match="a guard stop replaced a motion at 20.000 s of its 12.000 s"):
        _segments({"time": 10.0}, {**action, "guard": {**action["guard"], "stop_time": 30.0}}, {}, "t.json")


def test_a_push_in_retried_at_the_boards_edge_exports_as_its_motion_up_to_the_edge_and_the_retry():
    """A lift's push-in stopped at the board's front edge and pushed in again higher (guard.edge_stop): its motion
    up to that stop, then the retry (it starts where the arm stopped, with its own guarded push-in window, from its
    waypoint times); when the guard stopped the retry too, the retry is cut there and its stop motion follows."""
    import pytest

    from slax_drake.errors import TrialFileError
    from slax_drake.hardware.export import _segments

    motion = {"duration_s": 12.0, "suction_intervals": [[3.0, 9.0]],
              "waypoint_times": [["seal", 3.0], ["lift", 4.0], ["translate", 6.0], ["push in", 8.0],
                                 ["lower", 9.0], ["release", 9.0], ["retract", 12.0]]}
    retry = {"duration_s": 8.0, "suction_intervals": [[0.0, 4.0]],
             "waypoint_times": [["stop", 0.0], ["hold", 0.2], ["raise", 0.5], ["push in", 3.5], ["lower", 4.0],
                                ["release", 4.0], ["retract", 6.0]]}
    edge = {"guarded": True, "stopped": True, "edge": True, "threshold_n": 4.4, "stop_time": 16.2,
            "stop_motion": retry}
    action = {"type": "suction", "object": "track_3", "guarded": True, "motion": motion,
              "guard": {"guarded": True, "stopped": False, "threshold_n": 4.4, "edge_stop": edge}}
    (t0, d0, on0, act0, after0), (t1, d1, on1, act1, after1) = _segments({"time": 10.0}, action, {"type": "suction"},
                                                                         None)
    assert (t0, d0, on0, after0) == (10.0, pytest.approx(6.2), [(3.0, pytest.approx(6.2))], False)
    assert act0["guarded_push_in"]["stopped_at_s"] == pytest.approx(6.2) and "edge_retry_motion" not in act0
    assert (t1, d1, on1, after1) == (16.2, 8.0, [(0.0, 4.0)], True) and act1["edge_retry_motion"]
    assert act1["guarded_push_in"] == {"t_start_s": 0.5, "t_end_s": 3.5, "stop_force_n": 4.4}
    stopped = {**action, "guard": {**action["guard"], "stopped": True, "stop_time": 18.2,
                                   "stop_motion": {"duration_s": 3.0, "suction_intervals": [[0.0, 0.5]]}}}
    first, cut, stop = _segments({"time": 10.0}, stopped, {"type": "suction"}, None)
    assert cut[:2] == (16.2, pytest.approx(2.0)) and cut[3]["guarded_push_in"]["stopped_at_s"] == pytest.approx(2.0)
    assert cut[4] and cut[3]["edge_retry_motion"]
    assert stop[:3] == (pytest.approx(18.2), 3.0, [(0.0, 0.5)]) and stop[3]["guard_stop_motion"]
    assert "edge_retry_motion" not in stop[3]
    no_push_in = {**edge, "stop_motion": {**retry, "waypoint_times": [["stop", 0.0], ["lower", 4.0]]}}
    with pytest.raises(TrialFileError, match="retried at the board's edge has no 'push in'"):
        _segments({"time": 10.0}, {**action, "guard": {**action["guard"], "edge_stop": no_push_in}}, {}, "t.json")


def test_an_unguarded_lift_retried_at_the_boards_edge_exports_as_its_motion_up_to_the_edge_and_the_retry():
    """An unguarded lift's push-in, watched only at the board's edge (guard.edge_only), stopped there: its motion up
    to the stop carries edge_watch (not guarded_push_in: the checker must not excuse a collision in that window as a
    guard's stop), the push-in again after it; the checker reads the stop from edge_watch."""
    from types import SimpleNamespace

    import pytest

    from slax_drake.hardware.check import _stopped_by_guard
    from slax_drake.hardware.export import _segments

    motion = {"duration_s": 12.0, "suction_intervals": [[3.0, 9.0]],
              "waypoint_times": [["seal", 3.0], ["lift", 4.0], ["translate", 6.0], ["push in", 8.0],
                                 ["lower", 9.0], ["release", 9.0], ["retract", 12.0]]}
    retry = {"duration_s": 8.0, "suction_intervals": [[0.0, 4.0]],
             "waypoint_times": [["stop", 0.0], ["hold", 0.2], ["raise", 0.5], ["push in", 3.5], ["lower", 4.0]]}
    edge = {"guarded": True, "stopped": True, "edge": True, "threshold_n": 2.4, "stop_time": 16.2,
            "stop_motion": retry}
    action = {"type": "suction", "object": "track_1", "guarded": False, "motion": motion,
              "guard": {"guarded": False, "edge_only": True, "stopped": False, "edge_stop": edge}}
    (t0, d0, on0, act0, after0), (t1, d1, on1, act1, after1) = _segments({"time": 10.0}, action, {"type": "suction"},
                                                                         None)
    assert (t0, d0, after0) == (10.0, pytest.approx(6.2), False) and "guarded_push_in" not in act0
    assert act0["edge_watch"] == {"t_start_s": 6.0, "t_end_s": 8.0, "stopped_at_s": pytest.approx(6.2)}
    assert (t1, d1, on1, after1) == (16.2, 8.0, [(0.0, 4.0)], True) and act1["edge_retry_motion"]
    assert "guarded_push_in" not in act1 and "edge_watch" not in act1
    assert _stopped_by_guard(SimpleNamespace(action=act0, duration=d0))
    assert not _stopped_by_guard(SimpleNamespace(action={"type": "suction"}, duration=d0))
    # an unguarded lift that was not stopped exports as one motion, with nothing to watch
    plain = {**action, "guard": {"guarded": False, "edge_only": True, "stopped": False}}
    ((_, d, _, act, _),) = _segments({"time": 10.0}, plain, {"type": "suction"}, None)
    assert d == 12.0 and act == {"type": "suction"}


def test_a_lift_put_back_exports_as_its_motion_up_to_the_weighing_and_the_put_back():
    from slax_drake.errors import TrialFileError
    from slax_drake.hardware.export import _segments

    motion = {"duration_s": 12.0, "suction_intervals": [[2.5, 8.0]],
              "waypoint_times": [["pre-approach", 2.0], ["approach", 2.5], ["seal", 3.0], ["lift", 3.6]]}
    weighed = {"weight_n": 7.8, "moment_nm": 0.37, "put_back": True, "why": "not hanging free",
               "put_back_time": 13.88, "put_back_motion": {"duration_s": 3.88, "suction_intervals": [[0.0, 0.58]]}}
    action = {"type": "suction", "object": "track_1", "grip": "lift", "motion": motion, "weighed": weighed}
    (t0, d0, on0, act0, after0), (t1, d1, on1, act1, after1) = _segments({"time": 10.0}, action, {"type": "suction"},
                                                                         None)
    assert (t0, on0, after0) == (10.0, [(2.5, d0)], False) and d0 == pytest.approx(3.88)
    assert act0["put_back_at_s"] == pytest.approx(3.88)
    assert (t1, d1, on1, after1) == (13.88, 3.88, [(0.0, 0.58)], True) and act1["put_back_motion"]
    carried = {**action, "weighed": {"weight_n": 2.0, "moment_nm": 0.1, "put_back": False}}
    assert len(_segments({"time": 10.0}, carried, {"type": "suction"}, None)) == 1
    with pytest.raises(TrialFileError, match="put-back lift's record is malformed"):
        _segments({"time": 10.0}, {**action, "weighed": {"put_back": True}}, {}, "t.json")
