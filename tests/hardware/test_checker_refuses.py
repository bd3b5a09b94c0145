"""check-trajectory trusts nothing it checks: motions and scenes built to fool it, each rejected with its reason."""

import copy
import dataclasses
import json

import numpy as np
import pytest
from trial_records import fake_trial

from slax_drake.cli import main
from slax_drake.hardware.check import check_trajectory
from slax_drake.hardware.collision import CollisionWorld
from slax_drake.hardware.export import export_trial
from slax_drake.hardware.fetch_limits import FETCH_JOINTS
from slax_drake.hardware.trajectory_file import ExportedTrajectory, Motion, load_trajectory, save_trajectory

J = {n: i for i, n in enumerate(FETCH_JOINTS)}
STATION = "sim_configs/station_sim_shelf.yaml"


@pytest.fixture(scope="module")
def traj():
    return export_trial(fake_trial())


@pytest.fixture(scope="module")
def scene():
    from slax_drake.config import load_scenario
    from slax_drake.scene.sampling import sample_scene

    return sample_scene(load_scenario("sim_configs/sim_shelf.yaml"), 2, seed=3)


@pytest.fixture(scope="module")
def world(scene):
    from slax_drake.station.scenario import load_station_scenario

    return CollisionWorld(load_station_scenario(STATION), scene)


def _kinds(report):
    return {v.kind for v in report.violations}


def _in_the_path(world, scene, traj):
    """The scene with object_1 standing where the tool is halfway through motion 0 (tall enough to reach it)."""
    m = traj.motions[0]
    world.set_robot(m.q[len(m.times) // 2])
    p = (world.X_WS.inverse() @ world.tool_pose()).translation()
    objects = []
    for o in scene.objects:
        if o.name == "object_1":
            X = np.array(o.X_SO)
            X[:3, 3] = (p[0], p[1], (p[2] + 0.1) / 2)
            o = dataclasses.replace(o, X_SO=X, size=(o.size[0], o.size[1], p[2] + 0.1))
        objects.append(o)
    return scene.with_objects(objects)


def test_the_scene_given_is_the_world_not_the_files_objects_before(world, scene, traj):
    from slax_drake.station.scenario import load_station_scenario

    t = copy.deepcopy(traj)
    original = {o.name: {"x": float(o.center[0]), "y": float(o.center[1]), "yaw": float(o.yaw)} for o in scene.objects}
    for m in t.motions:
        m.objects_before = original  # the file claims object_1 stands where it was sampled
    assert check_trajectory(t, world, collision_step=0.02).ok
    moved = CollisionWorld(load_station_scenario(STATION), _in_the_path(world, scene, t))
    report = check_trajectory(t, moved, collision_step=0.02)
    hits = [v for v in report.violations if v.kind == "collision"]
    assert hits and all(v.what.endswith("/object_1") for v in hits), report.summary()
    assert "objects_before lie up to" in report.summary()


def test_a_lost_claim_never_removes_an_object(world, scene, traj):
    from slax_drake.station.scenario import load_station_scenario

    t = copy.deepcopy(traj)
    for m in t.motions:
        m.lost = ["object_1"]
    moved = CollisionWorld(load_station_scenario(STATION), _in_the_path(world, scene, t))
    report = check_trajectory(t, moved, collision_step=0.02)
    hits = [v for v in report.violations if v.kind == "collision"]
    assert hits and all(v.what.endswith("/object_1") for v in hits), report.summary()
    assert report.checked["claimed_lost"] == ["object_1"] and "checked anyway" in report.summary()


def test_a_chattering_joint_with_the_original_fields_is_refused(traj):
    t = copy.deepcopy(traj)
    m = t.motions[0]
    # tool_shaft_joint +-0.01 rad every 10 ms: about 400 rad/s^2 against 10; the fields keep the smooth profile
    m.q[20:60, J["tool_shaft_joint"]] += 0.01 * (-1.0) ** np.arange(40)
    report = check_trajectory(t)
    kinds = _kinds(report)
    assert {"fields", "acceleration", "jerk"} <= kinds, report.summary()
    worst = max((v for v in report.violations if v.kind == "acceleration"), key=lambda v: abs(v.value))
    assert worst.what == "tool_shaft_joint" and abs(worst.value) > 100 and "from positions" in worst.message


def test_zero_velocity_and_acceleration_fields_while_moving_are_refused(traj):
    t = copy.deepcopy(traj)
    for m in t.motions:
        m.v[:] = 0.0
        m.a[:] = 0.0
    report = check_trajectory(t)
    fields = [v for v in report.violations if v.kind == "fields"]
    assert _kinds(report) == {"fields"}, report.summary()
    assert {v.what for v in fields} == {n for n in FETCH_JOINTS}  # every joint moves in the fake motions
    assert "contradict its positions" in fields[0].message


def test_clean_motions_pass_the_derivative_and_field_checks(traj):
    report = check_trajectory(traj)
    assert report.ok, report.summary()
    assert "derivatives from positions" in report.checked["checks"]


def test_the_touched_object_rests_on_the_estimate_not_on_a_name(world, scene):
    o0 = next(o for o in scene.objects if o.name == "object_0")
    estimate = {"shape": o0.shape, "size": list(o0.size), "x": float(o0.center[0]) + 0.01,
                "y": float(o0.center[1]) - 0.01, "yaw": float(o0.yaw)}
    world.place_objects(None)
    # a segment-named action (the camera's name) is associated by its estimate
    assert world.associate({"type": "push", "object": "segment_4", "d": 0.1, "estimate": estimate})[0] == "object_0"
    # a scene object's name without an estimate exempts nothing
    name, why = world.associate({"type": "push", "object": "object_0", "d": 0.1})
    assert name is None and "no estimate" in why
    # the name of another object does not matter: the estimate decides
    assert world.associate({"type": "push", "object": "object_1", "d": 0.1, "estimate": estimate})[0] == "object_0"
    # a recorded association that the geometry contradicts exempts nothing
    name, why = world.associate({"type": "push", "object": "segment_4", "d": 0.1, "estimate": estimate,
                                 "scene_object": "object_1"})
    assert name is None and "matches 'object_0'" in why
    # an estimate far from every object exempts nothing
    far = dict(estimate, x=estimate["x"] + 1.0)
    assert world.associate({"type": "push", "object": "segment_4", "d": 0.1, "estimate": far})[0] is None


def test_a_file_with_no_motion_is_refused(traj, tmp_path, capsys):
    path = tmp_path / "empty.json"
    save_trajectory(ExportedTrajectory([], dict(traj.metadata)), path)
    assert main(["check-trajectory", str(path), "--no-collision"]) == 2
    err = capsys.readouterr().err
    assert "no motion" in err and len(err.strip().splitlines()) == 1
    with pytest.raises(Exception, match="no motion"):
        check_trajectory(ExportedTrajectory([], {}))


@pytest.mark.parametrize("margin", ["10", "0.2", "1e9"])
def test_a_margin_that_leaves_no_room_is_refused(traj, tmp_path, capsys, margin):
    path = tmp_path / "t.json"
    save_trajectory(traj, path)
    assert main(["check-trajectory", str(path), "--no-collision", "--margin", margin]) == 2
    err = capsys.readouterr().err
    assert "--margin" in err and "torso_lift_joint" in err and len(err.strip().splitlines()) == 1


def test_nan_in_objects_before_is_refused_naming_the_field(traj, tmp_path, capsys):
    path = tmp_path / "t.json"
    save_trajectory(traj, path)
    doc = json.loads(path.read_text())
    doc["motions"][1]["objects_before"] = {"object_0": {"x": float("nan"), "y": 0.0, "yaw": 0.0}}
    path.write_text(json.dumps(doc))  # Python writes NaN
    assert main(["check-trajectory", str(path)]) == 2
    err = capsys.readouterr().err
    assert "motions[1].objects_before.object_0.x is not finite" in err and len(err.strip().splitlines()) == 1


@pytest.mark.parametrize("field,value,expected", [
    ("estimate", {"shape": "box", "size": [0.1, 0.1], "x": 0, "y": 0, "yaw": 0}, "estimate.size"),
    ("d", float("inf"), "action.d is not finite"),
    ("type", "throw", "action.type must be push or suction"),
])
def test_a_malformed_action_is_refused(traj, tmp_path, capsys, field, value, expected):
    path = tmp_path / "t.json"
    save_trajectory(traj, path)
    doc = json.loads(path.read_text())
    doc["motions"][0]["action"][field] = value
    path.write_text(json.dumps(doc))
    assert main(["check-trajectory", str(path), "--no-collision"]) == 2
    assert expected in capsys.readouterr().err


def test_the_skipped_self_collision_pair_is_explained(world, traj):
    report = check_trajectory(traj, world, collision_step=0.0)
    assert report.checked["structural_pairs"] == [("torso_fixed_link", "torso_lift_link")]
    reason = report.checked["structural_reasons"]["torso_fixed_link/torso_lift_link"]
    assert "torso_lift_joint (prismatic)" in reason and "across torso_lift_joint's range" in reason
    assert reason in report.summary()


def test_structural_pairs_come_from_the_station_not_from_the_file(world, traj):
    from trial_records import FOLDED_INTO_TORSO

    t = copy.deepcopy(traj)
    for m in t.motions:
        m.q[0] = FOLDED_INTO_TORSO  # a file that starts inside the torso exempts nothing by doing so
    t.metadata["initial_positions"] = FOLDED_INTO_TORSO
    report = check_trajectory(t, world, collision_step=0.0)
    assert report.checked["structural_pairs"] == [("torso_fixed_link", "torso_lift_link")]
    assert any(v.kind == "collision" and v.time == 0.0 for v in report.violations)


def test_the_bag_written_by_export_is_checked(traj, tmp_path, scene, capsys):
    from rosbags.rosbag2 import Reader
    from rosbags.typesys import Stores, get_typestore

    from slax_drake.hardware.rosbag_export import ROS_DISTRO, robot_description, write_trial_bag
    from slax_drake.station.scenario import load_station_scenario

    data = {k: v for k, v in fake_trial().items() if k != "full_trajectory"}
    urdf = robot_description(load_station_scenario(STATION))
    write_trial_bag(data, tmp_path / "bag", scene=scene, robot_description=urdf)
    back = load_trajectory(tmp_path / "bag")
    assert len(back.motions) == len(traj.motions)
    for a, b in zip(back.motions, traj.motions):
        assert np.array_equal(a.q, b.q) and np.array_equal(a.v, b.v) and np.allclose(a.times, b.times, atol=1e-9)
        assert a.suction_events == b.suction_events and a.action == b.action
    assert back.metadata["scene"]["objects"]
    assert main(["check-trajectory", str(tmp_path / "bag")]) == 0
    assert main(["check-trajectory", str(tmp_path / "bag" / "bag.mcap"), "--no-collision"]) == 0
    assert f"ros_distro: {ROS_DISTRO}" in (tmp_path / "bag" / "metadata.yaml").read_text()
    store = get_typestore(Stores.ROS2_JAZZY)
    with Reader(tmp_path / "bag") as reader:
        conns = [c for c in reader.connections if c.topic == "/robot_description"]
        assert conns and "transient_local" in str(conns[0].ext.offered_qos_profiles).lower()
        (conn, _, raw), = list(reader.messages(connections=conns))
        assert store.deserialize_cdr(raw, conn.msgtype).data == urdf and "<robot" in urdf


def test_objects_before_that_do_not_name_the_scenes_objects_are_a_world_violation(traj, scene, tmp_path, capsys):
    from slax_drake.scene.io import save_scene

    t = copy.deepcopy(traj)
    for m in t.motions:
        m.objects_before = {"segment_9": {"x": 0.0, "y": 0.0, "yaw": 0.0}}
    path = tmp_path / "t.json"
    save_trajectory(t, path)
    save_scene(scene, tmp_path / "scene.json")
    assert main(["check-trajectory", str(path), "--scene", str(tmp_path / "scene.json"), "--collision-step", "0.05",
                 "--json", str(tmp_path / "report.json")]) == 1
    out = capsys.readouterr().out
    assert "world: 1 in 1" in out and "has no pose for object_" in out  # the second motion; the first uses the scene
    report = json.loads((tmp_path / "report.json").read_text(), parse_constant=lambda c: pytest.fail(c))
    world = [v for v in report["violations"] if v["kind"] == "world"]
    assert len(world) == 1 and world[0]["motion"] == 1 and world[0]["value"] is None


def test_a_carried_object_must_clear_the_shelf_and_the_other_objects(scene):
    """A suction motion built for the purpose: the cup reaches object_0 at the observation pose, the suction comes
    on, and the arm swings; object_1 stands where the carried object passes."""
    from slax_drake.station.scenario import load_station_scenario

    traj = export_trial(fake_trial())
    m = copy.deepcopy(traj.motions[1])  # the suction motion of the fake trial
    station = load_station_scenario(STATION)
    probe = CollisionWorld(station, scene)
    probe.set_robot(m.q[0])
    cup = probe.X_WS.inverse() @ probe.tool_pose()
    tip = cup.translation() + cup.rotation().matrix()[:, 0] * 0.42  # the cup's tip, 0.42 m along the shaft
    k = int(np.argmax(np.linalg.norm(m.q - m.q[0], axis=1)))  # the farthest configuration
    probe.set_robot(m.q[k])
    far = probe.X_WS.inverse() @ probe.tool_pose()
    far_tip = far.translation() + far.rotation().matrix()[:, 0] * 0.42
    objects = []
    for o in scene.objects:
        X = np.array(o.X_SO)
        size = (0.05, 0.05, 2 * max(tip[2], far_tip[2]) + 0.1)
        if o.name == "object_0":  # touching the cup's tip
            X[:3, 3] = (tip[0], tip[1] + 0.025, size[2] / 2)
        else:  # where the carried object will be at the farthest configuration
            X[:3, 3] = (far_tip[0], far_tip[1] + 0.025, size[2] / 2)
        objects.append(dataclasses.replace(o, X_SO=X, shape="box", size=size))
    built = scene.with_objects(objects)
    m.suction_events = [(0.0, True), (m.duration, False)]
    m.action = {"type": "suction", "object": "segment_1", "dx": 0.0, "dz": 0.0,
                "estimate": {"shape": "box", "size": list(objects[0].size), "x": float(tip[0]),
                             "y": float(tip[1] + 0.025), "yaw": 0.0}}
    t = ExportedTrajectory([m], {})
    report = check_trajectory(t, CollisionWorld(station, built), collision_step=0.02)
    assert report.checked["objects"]["motions"][0]["touched"] == "object_0"
    hits = {v.what for v in report.violations if v.kind == "collision"}
    assert "object_0/object_1" in hits, report.summary()


@pytest.mark.parametrize("rate", [1000.0, 250.0, 30.0, 7.0])
def test_resampled_exports_keep_fields_that_agree_with_their_positions(rate):
    report = check_trajectory(export_trial(fake_trial(), rate=rate))
    assert report.ok, report.summary()


def test_a_push_is_allowed_only_along_the_commanded_direction(scene):
    """A push motion built for the purpose: the fake push swings the tool 16 mm along -x_S and back along +x_S
    (its shaft lies along x_S); checked from the turn on, with a small box 0.5 mm beyond the cup's tip (+x) there.
    Commanded d > 0 the tool pushes it (and it moves); commanded d < 0 the same contact is a collision."""
    from pydrake.math import RigidTransform

    from slax_drake.station.scenario import load_station_scenario

    traj = export_trial(fake_trial())
    m = traj.motions[0]
    station = load_station_scenario(STATION)
    size = (0.03, 0.03, 0.3)
    objects = []
    for o in scene.objects:
        X = np.eye(4)
        X[:3, 3] = (5.0, 5.0, size[2] / 2)  # out of the way until placed below
        objects.append(dataclasses.replace(o, X_SO=X, shape="box", size=size))
    world = CollisionWorld(station, scene.with_objects(objects))
    xs = []
    for q in m.q:
        world.set_robot(q)
        xs.append((world.X_WS.inverse() @ world.tool_pose()).translation()[0])
    turn = int(np.argmin(xs))  # from here the tool moves along +x_S: the motion checked starts here
    m = Motion(0.0, m.times[turn:] - m.times[turn], m.q[turn:], m.v[turn:], m.a[turn:])
    world.set_robot(m.q[0])
    tip = (world.X_WS.inverse() @ world.tool_pose() @ RigidTransform([0.42, 0.0, 0.0])).translation()
    touching = lambda x: (world.set_planar("object_0", x, tip[1], 0.0),  # noqa: E731
                          any(world.object_of_geometry.get(b) == "object_0" for _, b, _, _ in world._penetrations()))[1]
    lo, hi = tip[0], tip[0] + 0.2  # find the box's x where it first touches the tool, coming from +x
    assert touching(lo) and not touching(hi), "the probe must straddle the tool"
    for _ in range(30):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if touching(mid) else (lo, mid)
    x0 = hi + 0.0005
    objects[0] = dataclasses.replace(objects[0], X_SO=np.array([[1, 0, 0, x0], [0, 1, 0, tip[1]],
                                                                  [0, 0, 1, size[2] / 2], [0, 0, 0, 1.0]]))
    world = CollisionWorld(station, scene.with_objects(objects))
    estimate = {"shape": "box", "size": list(size), "x": x0, "y": float(tip[1]), "yaw": 0.0}
    results = {}
    for d in (0.05, -0.05):
        m.action = {"type": "push", "object": "segment_1", "d": d, "estimate": estimate}
        results[d] = check_trajectory(ExportedTrajectory([m], {}), world, collision_step=0.0)
    entry = results[0.05].checked["objects"]["motions"][0]
    assert entry["touched"] == "object_0" and entry["pushed_m"] > 0.005, results[0.05].summary()
    assert not [v for v in results[0.05].violations if v.what.endswith("/object_0")], results[0.05].summary()
    hits = [v for v in results[-0.05].violations if v.kind == "collision" and v.what.endswith("/object_0")]
    assert hits and results[-0.05].checked["objects"]["motions"][0]["pushed_m"] == 0.0, results[-0.05].summary()


def test_a_guarded_window_excuses_only_what_follows_the_first_object_contact_inside_it():
    """A guarded push-in (a motion's action.guarded_push_in) cannot hide a collision: one before
    the window, one with the shelf inside it, and a window outside the motion stay violations; only what follows the
    first contact with an object inside the window is left out (the guard stops there)."""
    from types import SimpleNamespace

    from slax_drake.hardware.check import Violation, _guarded_stop

    def hit(t, what, motion=0):
        return Violation("collision", motion, t, what, 0.01, 0.0, f"{what} at {t}")

    motion = SimpleNamespace(duration=10.0)
    window = {"t_start_s": 4.0, "t_end_s": 8.0, "stop_force_n": 5.0}
    before = hit(3.0, "object_0/object_2")
    shelf = hit(4.5, "object_0/shelf_back")
    first = hit(5.0, "object_0/object_2")
    later = [hit(5.5, "object_0/object_2"), hit(9.0, "wrist_roll_link/object_3"), hit(6.0, "object_0/object_1", 1)]
    limit = Violation("velocity", 0, 6.0, "shoulder_pan_joint", 2.0, 1.0, "too fast")
    checked = {}
    others = {"object_1", "object_2", "object_3"}  # the scene's objects but the carried object_0
    kept = _guarded_stop([before, shelf, first, *later, limit], window, 0, motion, others, checked)
    assert kept == [before, shelf, later[2], limit]
    (stop,) = checked["guarded_stops"]
    assert stop["time_s"] == 5.0 and stop["bodies"] == "object_0/object_2" and stop["motion"] == 0
    # nothing met inside the window: every violation stays
    checked = {}
    assert _guarded_stop([before, shelf], window, 0, motion, others, checked) == [before, shelf]
    assert checked["guarded_stops"][0]["time_s"] is None
    # a window the motion does not hold is itself a violation
    kept = _guarded_stop([first], {"t_start_s": 11.0, "t_end_s": 12.0}, 0, motion, others, {})
    assert kept[:1] == [first] and kept[1].kind == "world" and "outside the motion" in kept[1].message


def test_only_a_motion_that_a_guard_stopped_inside_its_window_may_end_moving():
    from types import SimpleNamespace

    from slax_drake.hardware.check import _stopped_by_guard

    def motion(**guarded):
        return SimpleNamespace(duration=5.0, action={"type": "suction", "object": "o", "guarded_push_in": {
            "t_start_s": 4.0, "t_end_s": 8.0, **guarded}})

    assert _stopped_by_guard(motion(stopped_at_s=5.0))
    assert not _stopped_by_guard(motion())  # a guarded push-in that was not stopped ends at rest
    assert not _stopped_by_guard(motion(stopped_at_s=4.5))  # the claimed stop is not where the motion ends
    assert not _stopped_by_guard(motion(stopped_at_s=5.0, t_start_s=5.5))  # nor inside the window
    assert not _stopped_by_guard(SimpleNamespace(duration=5.0, action={"type": "push", "object": "o", "d": 0.1}))


def _press_world(scene, gap):
    """object_0 standing 1.5 mm ahead of the cup's tip at the suction motion's first configuration (the cup holds it
    from there, CUP_REACH), and object_1 ``gap`` m behind it along S's y; the tip's position as a function of q."""
    from slax_drake.station.scenario import load_station_scenario

    q0 = export_trial(fake_trial()).motions[1].q[0]
    station = load_station_scenario(STATION)
    probe = CollisionWorld(station, scene)

    def tip(q):
        probe.set_robot(q)
        X = probe.X_WS.inverse() @ probe.tool_pose()
        return X.translation() + X.rotation().matrix()[:, 0] * 0.42  # the cup's tip, 0.42 m along the shaft

    p = tip(q0)
    size = (0.05, 0.05, 2 * p[2] + 0.1)
    objects = []
    for o, y in zip(scene.objects, (p[1] + 0.0015 + 0.025, p[1] + 0.0015 + 0.05 + gap + 0.025)):
        X = np.eye(4)
        X[:3, 3] = (p[0], y, size[2] / 2)
        objects.append(dataclasses.replace(o, X_SO=X, shape="box", size=size))
    return CollisionWorld(station, scene.with_objects(objects)), q0, tip


def _along_y(tip, q0, dys):
    """Configurations moving the cup's tip from q0 by each of ``dys`` (m) along S's y (a finite-difference Jacobian's
    least-squares step from the previous one)."""
    qs, q = [], np.array(q0, dtype=float)
    for dy in dys:
        for _ in range(3):  # Newton steps toward the tip at q0's + (0, dy, 0)
            err = tip(q0) + np.array([0.0, dy, 0.0]) - tip(q)
            J = np.column_stack([(tip(q + e) - tip(q)) / 1e-6 for e in np.eye(len(q)) * 1e-6])
            q = q + np.linalg.lstsq(J, err, rcond=None)[0]
        qs.append(q.copy())
    return qs


@pytest.mark.parametrize("gap,press,refused", [(0.0, 0.003, False), (0.0, 0.008, True), (0.007, 0.009, True)])
def test_the_seal_may_press_its_object_against_a_neighbour_by_at_most_the_cups_press(scene, gap, press, refused):
    """The cup takes object_0 CUP_REACH before meeting it and presses on: object_0 is pressed against object_1, which
    stands ``gap`` behind it (a guarded placement leaves them touching), then pulled 30 mm back. A press of up to
    CUP_PRESS (5 mm) against a neighbour it stood within CUP_PRESS of is the cup's bellows giving way; a deeper one,
    or one against an object that stood farther, is a collision."""
    from types import SimpleNamespace

    from slax_drake.hardware.collision import _Suction

    world, q0, tip = _press_world(scene, gap)
    path = [press * k / 10 for k in range(11)] + [press - 0.03 * k / 10 for k in range(1, 11)]
    qs = _along_y(tip, q0, path)
    moved = [tip(q)[1] - tip(q0)[1] for q in qs]
    assert max(moved) == pytest.approx(press, abs=2e-4) and moved[-1] == pytest.approx(press - 0.03, abs=5e-4)
    model = _Suction(world, "object_0", SimpleNamespace(suction_events=[(0.0, True)], duration=float(len(qs)),
                                                        action={"type": "suction"}), 0, None, [])
    hits = []
    for t, q in enumerate(qs):
        world.set_robot(q)
        hits += [(world.body_name[a], world.body_name.get(b), depth) for a, b, depth, _ in model.resolve(float(t))]
    entry = {}
    model.finish(entry)
    assert entry["carried"]
    pairs = {(a, b) for a, b, _ in hits}
    if refused:
        assert pairs == {("object_0", "object_1")}, hits
    else:
        assert not hits and entry["seal_pressed"]["object_1"] == pytest.approx(press, abs=1e-3)
