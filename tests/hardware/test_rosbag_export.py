"""``slax-drake export --format mcap``: a hand-made trial (tests/trial_records.py, two Ruckig-timed motions,
no Drake simulation) written as a ROS 2 bag and read back with rosbags; slow: a real trial end to end."""

import json
import math

import numpy as np
import pytest

from rosbags.rosbag2 import Reader
from rosbags.typesys import Stores, get_typestore
from trial_records import fake_trial

from slax_drake.cli import main
from slax_drake.hardware.fetch_limits import FETCH_JOINTS
from slax_drake.hardware.rosbag_export import STEP_DEPTH_FILE, StepDepth, write_trial_bag

TYPESTORE = get_typestore(Stores.ROS2_JAZZY)


def _scene(objects=2, seed=3):
    from slax_drake.config import load_scenario
    from slax_drake.scene.sampling import sample_scene

    return sample_scene(load_scenario("sim_configs/sim_shelf.yaml"), objects, seed=seed)


@pytest.fixture(scope="module")
def trial_files(tmp_path_factory):
    """trial.json (two motions, two decisions with object poses, a final decision, final poses), step_depth.npz
    (a 32x24 depth image per decision) and scene.json in one folder."""
    from slax_drake.scene.io import save_scene

    scene = _scene()
    data = {k: v for k, v in fake_trial(objects=2, seed=3).items() if k != "full_trajectory"}
    poses = {o.name: {"x": round(float(o.center[0]), 5), "y": round(float(o.center[1]), 5),
                      "yaw": round(float(o.yaw), 5)} for o in scene.objects}
    for k, entry in enumerate(data["steps_log"]):
        entry["poses_before"] = {n: dict(p, x=p["x"] + 0.01 * k) for n, p in poses.items()}
    t_end = data["executed_trajectory"]["times"][-1]
    data["steps_log"].append({"step": 2, "time": round(t_end - 0.1, 4), "lost": [], "final": True,
                              "result": "revealed", "poses_before": poses})
    data["sim_time_s"] = round(t_end, 3)
    data["final_objects"] = {n: dict(p, z=0.05, upright=True, inside=True) for n, p in poses.items()}
    folder = tmp_path_factory.mktemp("trial")
    (folder / "trial.json").write_text(json.dumps(data))
    rng = np.random.default_rng(0)
    depth = rng.uniform(0.3, 1.2, size=(len(data["steps_log"]), 24, 32)).astype(np.float32)
    depth[0, 0, 0] = np.inf
    times = np.array([e["time"] for e in data["steps_log"]])
    np.savez_compressed(folder / STEP_DEPTH_FILE, times=times, depth=depth)
    save_scene(scene, folder / "scene.json")
    return folder, data, scene, StepDepth(times, depth)


def _read(bag):
    """{topic: [(log time ns, message)]} in the order the reader returns them, and that order's log times."""
    out, order = {}, []
    with Reader(bag) as reader:
        for conn, t, raw in reader.messages():
            out.setdefault(conn.topic, []).append((t, TYPESTORE.deserialize_cdr(raw, conn.msgtype)))
            order.append(t)
    return out, order


def _file_order(bag):
    """Log times of the messages in the order they are stored in the .mcap file (rosbags' Reader sorts by time;
    its MCAP reader's sequential scan does not)."""
    from rosbags.rosbag2.storage_mcap import McapReader

    reader = McapReader(bag / f"{bag.name}.mcap")
    reader.open()
    try:
        return [t for _, t, _ in reader.messages_scan(reader.connections)]
    finally:
        reader.close()


def _stamp(msg):
    return msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec


@pytest.fixture(scope="module")
def bag(trial_files, tmp_path_factory):
    folder, data, scene, depth = trial_files
    out = tmp_path_factory.mktemp("bags") / "trial_bag"
    summary = write_trial_bag(data, out, scene=scene, depth=depth, X_WS=np.eye(4), X_WB=np.eye(4),
                              source="trial.json")
    return out, summary


def test_bag_is_a_rosbag2_mcap_folder_with_every_topic(trial_files, bag):
    folder, data, scene, depth = trial_files
    out, summary = bag
    assert sorted(p.name for p in out.iterdir()) == ["metadata.yaml", "trial_bag.mcap"]
    assert not [p for p in out.parent.iterdir() if p.name.startswith(".")]  # no staging folder left behind
    msgs, order = _read(out)
    n_records = len(data["executed_trajectory"]["times"])
    expected = {"/joint_states": n_records, "/planned_trajectory": 2, "/suction_command": 1 + 2, "/tf_static": 1,
                "/tf": 3 + 1, "/camera/depth/image": 3, "/camera/depth/camera_info": 3, "/slax_drake/trajectory": 1}
    assert {t: len(m) for t, m in msgs.items()} == expected == summary.counts
    stored = _file_order(out)
    assert len(stored) == len(order) and stored == sorted(stored)
    with Reader(out) as reader:
        types = {c.topic: c.msgtype for c in reader.connections}
        assert reader.message_count == sum(expected.values())
    assert types["/suction_command"] == "std_msgs/msg/Bool"
    assert types["/tf"] == types["/tf_static"] == "tf2_msgs/msg/TFMessage"
    for topic, entries in msgs.items():
        for t, m in entries:  # header stamps are the log times (the trial's simulation time)
            stamps = [_stamp(x) for x in m.transforms] if topic.startswith("/tf") else \
                [_stamp(m)] if hasattr(m, "header") else [t]
            assert all(s == t for s in stamps), topic


def test_joint_states_are_the_trial_records(trial_files, bag):
    folder, data, scene, depth = trial_files
    msgs, _ = _read(bag[0])
    et = data["executed_trajectory"]
    js = msgs["/joint_states"]
    assert [t for t, _ in js] == [int(round(t * 1e9)) for t in et["times"]]
    assert np.all(np.diff([t for t, _ in js]) > 0)
    for k in (0, len(js) // 2, len(js) - 1):
        m = js[k][1]
        assert list(m.name) == list(FETCH_JOINTS) == et["joint_names"]
        assert np.array_equal(m.position, et["positions"][k]) and np.array_equal(m.velocity, et["velocities"][k])


def test_planned_trajectories_start_at_the_decisions(trial_files, bag):
    folder, data, scene, depth = trial_files
    msgs, _ = _read(bag[0])
    starts = [e["time"] for e in data["steps_log"] if "action" in e]
    et = data["executed_trajectory"]
    times = np.array(et["times"])
    for (t, m), t0, action in zip(msgs["/planned_trajectory"], starts, data["actions"]):
        assert t == int(round(t0 * 1e9)) and m.header.frame_id == "base_link"
        assert list(m.joint_names) == list(FETCH_JOINTS)
        tfs = [p.time_from_start.sec + 1e-9 * p.time_from_start.nanosec for p in m.points]
        assert tfs[0] == 0.0 and np.all(np.diff(tfs) > 0)
        assert tfs[-1] == pytest.approx(action["motion"]["duration_s"], abs=1e-9)
        k = int(np.argmin(np.abs(times - (t0 + tfs[3]))))  # a point is the trial's record at its time
        assert times[k] == pytest.approx(t0 + tfs[3], abs=1e-6)
        assert np.allclose(m.points[3].positions, et["positions"][k], atol=1e-12)
    suction = [(t, m.data) for t, m in msgs["/suction_command"]]
    on, off = data["actions"][1]["motion"]["suction_intervals"][0]
    assert suction == [(0, False), (int(round((starts[1] + on) * 1e9)), True), (int(round((starts[1] + off) * 1e9)), False)]


def test_tf_places_objects_in_the_shelf_frame(trial_files, bag):
    folder, data, scene, depth = trial_files
    msgs, _ = _read(bag[0])
    (t0, static), = msgs["/tf_static"]
    pairs = {(x.header.frame_id, x.child_frame_id) for x in static.transforms}
    assert pairs == {("world", "base_link"), ("world", "shelf"), ("shelf", "camera_optical_frame"), ("shelf", "target")}
    cam = next(x for x in static.transforms if x.child_frame_id == "camera_optical_frame").transform
    assert [cam.translation.x, cam.translation.y, cam.translation.z] == pytest.approx(scene.camera.X_SC[:3, 3].tolist())
    sizes = {o.name: o.size for o in scene.objects}
    tf = msgs["/tf"]
    assert [t for t, _ in tf] == [int(round(e["time"] * 1e9)) for e in data["steps_log"]] + [int(round(data["sim_time_s"] * 1e9))]
    for (t, m), entry in zip(tf, data["steps_log"]):
        assert {x.child_frame_id for x in m.transforms} == {"object_0", "object_1"}
        for x in m.transforms:
            p = entry["poses_before"][x.child_frame_id]
            r = x.transform.rotation
            assert x.header.frame_id == "shelf"
            assert (x.transform.translation.x, x.transform.translation.y, x.transform.translation.z) == pytest.approx(
                (p["x"], p["y"], sizes[x.child_frame_id][2] / 2))
            assert (r.x, r.y, abs(r.z), abs(r.w)) == pytest.approx(
                (0.0, 0.0, abs(math.sin(p["yaw"] / 2)), abs(math.cos(p["yaw"] / 2))), abs=1e-12)
            assert 2 * math.atan2(r.z, r.w) == pytest.approx(p["yaw"], abs=1e-9) or \
                abs(abs(2 * math.atan2(r.z, r.w) - p["yaw"]) - 2 * math.pi) < 1e-9
    assert all(x.transform.translation.z == 0.05 for x in tf[-1][1].transforms)  # the final poses' own z


def test_depth_images_and_camera_info(trial_files, bag):
    folder, data, scene, depth = trial_files
    msgs, _ = _read(bag[0])
    images, infos = msgs["/camera/depth/image"], msgs["/camera/depth/camera_info"]
    assert [t for t, _ in images] == [t for t, _ in infos] == [int(round(t * 1e9)) for t in depth.times]
    for k, (t, m) in enumerate(images):
        assert (m.encoding, m.height, m.width, m.step, m.is_bigendian) == ("32FC1", 24, 32, 128, 0)
        assert m.header.frame_id == "camera_optical_frame"
        assert np.array_equal(np.frombuffer(m.data.tobytes(), "<f4").reshape(24, 32), depth.depth[k])
    info = infos[0][1]
    cam = scene.camera.with_resolution(32, 24)  # the intrinsics at the images' resolution
    assert (info.width, info.height) == (32, 24)
    assert list(info.k) == pytest.approx([cam.fx, 0, cam.cx, 0, cam.fy, cam.cy, 0, 0, 1])
    assert list(info.d) == [0.0] * 5 and info.distortion_model == "plumb_bob"


def test_cli_writes_the_bag_and_refuses_bad_input(trial_files, tmp_path, capsys):
    folder, data, scene, depth = trial_files
    out = tmp_path / "bag"
    assert main(["export", str(folder / "trial.json"), "--format", "mcap", "--scene", str(folder / "scene.json"),
                 "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "/joint_states" in printed and "Foxglove" in printed and "ros2 bag play" in printed
    msgs, _ = _read(out)
    (_, static), = msgs["/tf_static"]
    from slax_drake.station.plant import shelf_pose
    from slax_drake.station.scenario import load_station_scenario

    X_WS = shelf_pose(load_station_scenario(data["station"]), scene.camera).GetAsMatrix4()
    world_shelf = next(x for x in static.transforms if x.child_frame_id == "shelf").transform
    t, r = world_shelf.translation, world_shelf.rotation
    assert [t.x, t.y, t.z] == pytest.approx(X_WS[:3, 3].tolist(), abs=1e-9)
    assert t.x > 0.5  # the shelf stands in front of the robot (x forward)
    z_axis = [2 * (r.x * r.z + r.w * r.y), 2 * (r.y * r.z - r.w * r.x), 1 - 2 * (r.x ** 2 + r.y ** 2)]
    assert z_axis == pytest.approx(X_WS[:3, 2].tolist(), abs=1e-9)  # the quaternion's z axis is the shelf's
    before = sorted(p.name for p in out.iterdir())

    def refused(argv, words):
        capsys.readouterr()
        assert main(["export", *argv]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and all(w in err[0] for w in words), err

    refused([str(folder / "trial.json"), "--format", "mcap", "--out", str(out)], ["exists"])
    assert sorted(p.name for p in out.iterdir()) == before
    refused([str(tmp_path / "none.json"), "--format", "mcap", "--out", str(tmp_path / "b2")], ["no such file"])
    (tmp_path / "cut").mkdir()
    (tmp_path / "cut" / "trial.json").write_text((folder / "trial.json").read_text()[:-100])
    refused([str(tmp_path / "cut" / "trial.json"), "--format", "mcap", "--out", str(tmp_path / "b3")], ["not valid JSON"])
    (tmp_path / "bad").mkdir()
    (tmp_path / "bad" / "trial.json").write_text((folder / "trial.json").read_text())
    (tmp_path / "bad" / STEP_DEPTH_FILE).write_bytes(b"PK\x03\x04 not a zip")
    refused([str(tmp_path / "bad" / "trial.json"), "--format", "mcap", "--scene", str(folder / "scene.json"),
             "--out", str(tmp_path / "b4")], ["step depth"])
    refused([str(folder / "trial.json"), "--format", "mcap", "--scene", str(folder / "scene.json"),
             "--out", str(tmp_path / "b5.mcap")], ["folder"])
    assert not any((tmp_path / n).exists() for n in ("b2", "b3", "b4", "b5.mcap"))
    # a trial written before step_depth.npz existed: the bag without images, and the command says so
    (tmp_path / "old").mkdir()
    (tmp_path / "old" / "trial.json").write_text((folder / "trial.json").read_text())
    assert main(["export", str(tmp_path / "old" / "trial.json"), "--format", "mcap", "--scene",
                 str(folder / "scene.json"), "--out", str(tmp_path / "b6")]) == 0
    assert "no depth images" in capsys.readouterr().out
    msgs, _ = _read(tmp_path / "b6")
    assert "/camera/depth/image" not in msgs and len(msgs["/tf"]) == 4


def test_an_interrupted_write_leaves_nothing(trial_files, tmp_path, monkeypatch):
    from rosbags.rosbag2 import Writer

    folder, data, scene, depth = trial_files
    calls = []

    def failing(self, connection, timestamp, raw):
        calls.append(timestamp)
        if len(calls) > 5:
            raise RuntimeError("disk gone")

    monkeypatch.setattr(Writer, "write", failing)
    with pytest.raises(RuntimeError, match="disk gone"):
        write_trial_bag(data, tmp_path / "bag", scene=scene, depth=depth)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.slow
def test_a_real_trial_exports_to_a_bag(tmp_path):
    """slax-drake trial, then export --format mcap from its folder: one image per decision, one trajectory per action."""
    trial = tmp_path / "trial"
    assert main(["trial", "--objects", "2", "--seed", "7", "--out", str(trial)]) == 0
    d = json.loads((trial / "trial.json").read_text())
    assert main(["export", str(trial / "trial.json"), "--format", "mcap", "--out", str(tmp_path / "bag")]) == 0
    msgs, order = _read(tmp_path / "bag")
    stored = _file_order(tmp_path / "bag")
    assert len(stored) == len(order) and stored == sorted(stored)
    assert len(msgs["/planned_trajectory"]) == d["steps"] >= 1
    assert len(msgs["/camera/depth/image"]) == len(msgs["/camera/depth/camera_info"]) == len(d["steps_log"])
    assert len(msgs["/joint_states"]) == len(d["executed_trajectory"]["times"])
    image = msgs["/camera/depth/image"][0][1]
    assert (image.width, image.height) == (160, 120)  # the frame the planner read (the perception's resolution)
    info = msgs["/camera/depth/camera_info"][0][1]
    assert (info.width, info.height) == (160, 120)
    depth = np.frombuffer(image.data.tobytes(), "<f4")
    valid = np.isfinite(depth) & (depth > 0)  # 0: no return
    assert valid.mean() > 0.5 and 0.1 < depth[valid].min() < 2.0  # metres, the shelf's bay
