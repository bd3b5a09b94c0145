"""slax-drake check-trajectory: the independent checker passes clean motions and catches each kind of violation."""

import copy

import pytest
from trial_records import FOLDED_INTO_TORSO, fake_trial

from slax_drake.cli import main
from slax_drake.hardware.check import check_trajectory
from slax_drake.hardware.collision import CollisionWorld
from slax_drake.hardware.export import export_trial
from slax_drake.hardware.fetch_limits import FETCH_JOINTS
from slax_drake.hardware.trajectory_file import save_trajectory


@pytest.fixture(scope="module")
def traj():
    return export_trial(fake_trial())


@pytest.fixture(scope="module")
def world(traj):
    from slax_drake.config import load_scenario
    from slax_drake.scene.sampling import sample_scene
    from slax_drake.station.scenario import load_station_scenario

    scene = sample_scene(load_scenario("sim_configs/sim_shelf.yaml"), 2, seed=3)
    return CollisionWorld(load_station_scenario("sim_configs/station_sim_shelf.yaml"), scene)


def _kinds(report):
    return {v.kind for v in report.violations}


def test_clean_ruckig_motions_pass_every_check(traj, world):
    report = check_trajectory(traj, world)
    assert report.ok, report.summary()
    assert report.checked["collision_configurations"] > sum(len(m.times) for m in traj.motions)


J = {n: i for i, n in enumerate(FETCH_JOINTS)}


def _edited(traj, edit):
    t = copy.deepcopy(traj)
    edit(t.motions[0])
    return t


@pytest.mark.parametrize("kind,edit", [
    ("position", lambda m: m.q.__setitem__((slice(40, 60), J["torso_lift_joint"]), 0.3865)),
    ("velocity", lambda m: m.v.__setitem__((30, J["shoulder_pan_joint"]), 1.3)),
    ("acceleration", lambda m: m.a.__setitem__((slice(30, 40), J["shoulder_lift_joint"]), 1.05)),
    ("jerk", lambda m: m.a.__setitem__((31, J["wrist_flex_joint"]), m.a[31, J["wrist_flex_joint"]] + 0.3)),
    ("discontinuity", lambda m: m.q.__setitem__((slice(50, None), J["elbow_flex_joint"]),
                                                m.q[50:, J["elbow_flex_joint"]] + 0.02)),
])
def test_each_limit_violation_is_caught_alone(traj, kind, edit):
    report = check_trajectory(_edited(traj, edit))
    kinds = _kinds(report)
    # an edited field also contradicts the positions ("fields"); a position or acceleration step also shows as a
    # discontinuity or a jerk, a position step as derivatives from positions; the others come alone
    assert kind in kinds and (kinds - {"fields"} == {kind} or kind in ("position", "acceleration", "discontinuity")), \
        report.summary()
    v = report.violations[0]
    assert v.motion == 0 and kind in report.summary()


def test_position_margin_and_torso_limit(traj):
    # the fake motion keeps the torso >= 3.7 mm from 0: a 5 mm margin catches it, 1 mm does not
    assert check_trajectory(traj, margin=0.001).ok
    assert "position" in _kinds(check_trajectory(traj, margin=0.005))


def test_discontinuity_between_motions_and_not_at_rest(traj):
    t = copy.deepcopy(traj)
    t.motions[1].q[:, J["wrist_roll_joint"]] += 0.001
    report = check_trajectory(t)
    assert _kinds(report) == {"discontinuity"} and any("motion 0's end" in v.message for v in report.violations)
    t = copy.deepcopy(traj)
    t.motions[0].v[-1, 3] = 0.01
    assert any("not at rest" in v.message for v in check_trajectory(t).violations)


def test_collision_with_the_robot_itself_is_caught(traj, world):
    t = copy.deepcopy(traj)
    m = t.motions[0]
    m.q[40:43] = FOLDED_INTO_TORSO
    m.v[40:43] = 0.0
    m.a[40:43] = 0.0
    report = check_trajectory(t, world, collision_step=0.0)
    hits = [v for v in report.violations if v.kind == "collision"]
    assert hits and {"torso_lift_link"} & set(hits[0].what.split("/")), report.summary()


def test_cli_exit_codes(traj, tmp_path, capsys):
    good = tmp_path / "good.json"
    save_trajectory(traj, good)
    assert main(["check-trajectory", str(good), "--no-collision"]) == 0
    bad = tmp_path / "bad.csv"
    save_trajectory(_edited(traj, lambda m: m.v.__setitem__((30, 1), 1.3)), bad)
    capsys.readouterr()
    assert main(["check-trajectory", str(bad), "--no-collision", "--json", str(tmp_path / "r.json")]) == 1
    out = capsys.readouterr().out
    assert "FAILED" in out and "shoulder_pan_joint velocity" in out
    assert (tmp_path / "r.json").is_file()
