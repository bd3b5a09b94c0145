"""slax-drake replay: the exported commands fed open loop to the station; the full trial round trip (slow)."""

import numpy as np
import pytest
from trial_records import fake_trial

from slax_drake.hardware.export import export_trial
from slax_drake.hardware.replay import ReplaySource


def test_replay_source_feeds_the_points_and_the_suction_events():
    trial = fake_trial()
    traj = export_trial(trial)
    source = ReplaySource(traj)
    full = trial["full_trajectory"]
    for m in traj.motions:
        for t, q in zip(m.times + m.start_time, m.q):
            np.testing.assert_allclose(source.command(t)[0], q, atol=1e-12, rtol=0)
    # between records too: the 1 ms trajectory within 2e-6 (quintic Hermite of the 10 ms records)
    ts = np.arange(0.0, full.times[-1], 0.003)
    commanded = np.array([source.command(t)[0] for t in ts])
    k = np.rint(ts / 0.001).astype(int)
    np.testing.assert_allclose(commanded, full.q[k], atol=2e-6, rtol=0)
    m = traj.motions[1]
    on = [source.command(m.start_time + s)[2] for s in (0.0, 0.269, 0.2705, 0.5, 0.6295, 0.6305, 0.8)]
    assert on == [False, False, True, True, True, False, False]


@pytest.mark.slow
def test_trial_export_replay_round_trip(tmp_path):
    """A short trial, exported (JSON and CSV at the trial's records) and replayed: the commands reproduce the
    trial's joint positions within 1e-6 and the final object poses within 5 mm; the checker passes its limits."""
    from slax_drake.hardware.check import check_trajectory
    from slax_drake.hardware.export import trial_scene
    from slax_drake.hardware.replay import compare_final_objects, replay
    from slax_drake.hardware.trajectory_file import load_trajectory, save_trajectory
    from slax_drake.station.scenario import load_station_scenario
    from slax_drake.evaluation.trial import TrialOptions, run_trial

    record = run_trial(TrialOptions(objects=2, seed=7, out=None))
    data = record.data
    assert data["actions"], "the trial made no motion"
    scene = trial_scene(data)
    traj = export_trial(data, scene=scene)
    for ext in ("json", "csv"):
        save_trajectory(traj, tmp_path / f"t.{ext}")
    back = load_trajectory(tmp_path / "t.csv")
    source = ReplaySource(back)
    et = data["executed_trajectory"]
    commanded = np.array([source.command(t)[0] for t in et["times"]])
    assert np.abs(commanded - np.array(et["positions"])).max() <= 1e-6
    assert check_trajectory(back).ok
    result = replay(back, load_station_scenario(data["station"]), scene)
    diffs = compare_final_objects(result.final_objects, data["final_objects"])
    assert set(diffs) == set(data["final_objects"])
    assert max(d["xyz_m"] for d in diffs.values()) <= 0.005, diffs
