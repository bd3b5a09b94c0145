"""What a user of ``slax-drake trial`` reads and looks at: the closing summary block, the step PNGs (fixed label
colours, depth colour bar, both distributions, the action drawn, the target outlined) and, slow, the HTML replay
opening into the bay (a headless-Chromium screenshot) with a quiet Drake log."""

import json
import shutil
import subprocess

import cv2
import numpy as np
import pytest

from slax_drake.systems.step_figure import (
    ACTION_COLOR, TARGET_COLOR, columns_to_shelf_x, label_image_rgb, step_figure, step_png,
)
from slax_drake.systems.trial_summary import trial_summary


def _record(result="revealed", actions=None, horizon=6):
    actions = actions if actions is not None else [
        {"type": "push", "object": "object_0", "q": [0.04, -0.04, 0.04], "d": -0.12, "planning_s": 0.58,
         "motion": {"duration_s": 16.7}, "rejected_before": []},
        {"type": "suction", "object": "object_2", "q": [0.11, -0.01, 0.09], "dx": -0.2, "dz": 0.1,
         "planning_s": 1.2, "motion": {"duration_s": 25.0}, "rejected_before": [{"reason": "insert"}]},
    ]
    pushes = sum(a["type"] == "push" for a in actions)
    return {"success": result == "revealed", "result": result, "steps": len(actions),
            "cost": round(pushes + 1.3 * (len(actions) - pushes), 6), "horizon": horizon,
            "visible_fraction": 0.93 if result == "revealed" else 0.2, "sim_time_s": 42.0, "wall_s": 20.0,
            "real_time_factor": 2.1, "tool_rules": {"max_suction_moment": 0.4}, "actions": actions}


def _written(tmp_path, html=True):
    out = tmp_path / "trial"
    out.mkdir()
    files = [out / "trial.json", out / "scene.json", out / "step_00.png", out / "step_01.png", out / "step_02.png"]
    if html:
        files.append(tmp_path / "trial.html")
    for f in files:
        f.write_bytes(b"x" * 2048)
    return files


def test_summary_block_says_outcome_steps_cost_files_and_how_to_view(tmp_path):
    written = _written(tmp_path)
    html = written[-1]
    text = trial_summary(_record(), written, html=str(html))
    assert "revealed (revealed)" not in text
    assert "outcome: target revealed (93% of it visible at the end)" in text
    assert "steps:   2 actions (1 push, 1 suction) of at most 6" in text
    assert "cost:    2.3 (1 per push, 1.3 per suction)" in text
    assert "1. push object_0 (d=-0.120 m)" in text and "after 1 rejected candidate" in text
    for f in written[:2]:
        assert str(f) in text
    assert f"{written[2]} .. step_02.png" in text and "(3 images)" in text
    assert f"open {html} in a web browser ({html.resolve().as_uri()})" in text
    assert "localhost" not in text
    assert text.count("== trial summary ==") == 1


@pytest.mark.parametrize("result, phrase", [
    ("horizon", "target not revealed: the horizon of 6 actions was spent"),
    ("no feasible motion", "target not revealed: no candidate action had a collision-free motion"),
    ("time limit", "target not revealed: the simulated-time limit (--max-sim-time) ran out"),
])
def test_summary_says_why_the_target_was_not_revealed(tmp_path, result, phrase):
    text = trial_summary(_record(result), _written(tmp_path, html=False))
    assert f"outcome: {phrase} (20% of it visible at the end)" in text
    assert "slax-drake view-trial" in text and "(no simulation)" in text  # no replay written: say how to get one


def test_summary_says_how_far_a_move_pushed_the_target(tmp_path):
    record = _record()
    record["target_moved_m"] = 0.0645
    text = trial_summary(record, _written(tmp_path, html=False))
    assert "outcome: target revealed (93% of it visible at the end; a move pushed the target 6.5 cm)" in text
    record["target_moved_m"] = 0.004  # under a centimetre: not worth a word
    again = tmp_path / "again"
    again.mkdir()
    assert "(93% of it visible at the end)" in trial_summary(record, _written(again, html=False))


def test_summary_says_the_live_view_dies_with_the_process(tmp_path):
    text = trial_summary(_record(), _written(tmp_path), html=str(tmp_path / "trial.html"),
                         meshcat_url="http://localhost:7000")
    assert "http://localhost:7000 closes when this command ends" in text


def test_label_colours_are_the_same_in_every_step():
    """A label's colour depends on the label and the object count, not on which labels an image holds (the
    old figure normalised a colour map over each image's own labels, so object_1 changed colour when object_0
    left the view)."""
    n = 3
    first = np.array([[-1, 0, 1, 2]])
    later = np.array([[0, 2, 3, 4]])  # object_0 gone from view, object_2 and the target seen
    a, b = label_image_rgb(first, n), label_image_rgb(later, n)
    assert np.array_equal(a[0, 3], b[0, 1])  # object_1 (label 2)
    assert np.array_equal(a[0, 1], b[0, 0])  # the shelf
    assert np.array_equal(b[0, 3], TARGET_COLOR)
    colours = {tuple(c) for c in label_image_rgb(np.arange(-1, n + 2)[None], n)[0]}
    assert len(colours) == n + 3  # background, shelf, three objects and the target all differ


@pytest.fixture(scope="module")
def scene():
    from slax_drake.config import load_scenario
    from slax_drake.scene.sampling import sample_scene

    return sample_scene(load_scenario("sim_configs/sim_shelf.yaml"), 3, seed=7)


def _images(scene, target_visible=False, w=160, h=120):
    """Synthetic depth and labels of the shelf (label 0) below row h/3 and background above."""
    depth = np.full((h, w), 0.8, dtype=np.float32)
    labels = np.zeros((h, w), dtype=np.int32)
    labels[: h // 3] = -1
    depth[: h // 3] = 0.0
    if target_visible:
        labels[60:70, 70:80] = len(scene.objects) + 1
    return depth, labels


def _png_pixels(png: bytes) -> np.ndarray:
    return cv2.cvtColor(cv2.imdecode(np.frombuffer(png, np.uint8), cv2.IMREAD_COLOR), cv2.COLOR_BGR2RGB).astype(int)


def _count(pixels, rgb, tol=12):
    return int(np.count_nonzero(np.all(np.abs(pixels - np.array(rgb) * 255) <= tol, axis=-1)))


@pytest.mark.parametrize("action", [
    {"type": "push", "object": "object_0", "q": [0.04, -0.04, 0.04], "d": -0.12},
    {"type": "suction", "object": "object_2", "q": [0.11, -0.01, 0.09], "dx": -0.2, "dz": 0.1},
])
def test_step_png_draws_the_chosen_action(scene, action):
    depth, labels = _images(scene)
    p = np.linspace(0.0, 1.0, 40)
    with_action = _png_pixels(step_png(0, depth, labels, p, p, scene, action=action, object_y=0.06))
    without = _png_pixels(step_png(0, depth, labels, p, p, scene))
    assert _count(without, ACTION_COLOR) == 0
    assert _count(with_action, ACTION_COLOR) > 100  # drawn on the depth and the label panels


def test_step_png_outlines_the_target_when_visible(scene):
    p = np.ones(40) / 40
    depth_panel = slice(0, 400)  # the left of the 1280 px wide figure: the depth image, drawn in viridis
    hidden = _png_pixels(step_png(1, *_images(scene), p, None, scene))[:, depth_panel]
    seen = _png_pixels(step_png(1, *_images(scene, target_visible=True), p, None, scene))[:, depth_panel]
    assert _count(hidden, TARGET_COLOR, tol=30) == 0
    assert _count(seen, TARGET_COLOR, tol=30) > 20


def test_step_figure_axes(scene):
    """Depth colour bar; both distributions drawn; x axes in image columns, the shelf's metres on top."""
    depth, labels = _images(scene)
    fig = step_figure(0, depth, labels, np.full(40, 0.01), np.full(40, 0.02), scene)
    try:
        depth_ax, labels_ax, dist_ax = fig.axes[:3]
        assert any(ax.get_ylabel() == "depth (m)" for ax in fig.axes[3:])  # the colour bar
        assert dist_ax.get_xlabel() == depth_ax.get_xlabel() == "image column u (px)"
        assert dist_ax.get_xlim() == pytest.approx((-0.5, 159.5))
        names = [t.get_text() for t in dist_ax.get_legend().get_texts()]
        assert names[0] == "P_t" and names[1].startswith("P'_t")
        assert any("shelf x (m)" in ax.get_xlabel() for ax in dist_ax.child_axes)
    finally:
        import matplotlib.pyplot as plt

        plt.close(fig)


def test_columns_to_shelf_x_matches_the_camera(scene):
    cam = scene.camera.with_resolution(160, 120)
    slope, offset = columns_to_shelf_x(cam, scene.shelf)
    for x in (-0.2, 0.0, 0.25):
        assert slope * x + offset == pytest.approx(cam.project(np.array([x, 0.0, 0.0]))[0], abs=1e-6)
    assert slope > 0  # x to the right as seen from the camera


SHORT = ["--objects", "2", "--seed", "7"]  # the shelf simulator reveals this scene with one push


@pytest.mark.slow
def test_trial_cli_summary_quiet_log_and_replay_opening_into_the_bay(tmp_path, capfd):
    """The CLI prints one summary block naming the HTML replay, no Drake INFO lines and no localhost address;
    headless Chromium draws the replay's last frame with the target in view (target red in the picture)."""
    from slax_drake.cli import main

    browser = shutil.which("chromium") or shutil.which("chromium-browser")
    if browser is None:
        pytest.skip("Debian's chromium package is not installed (apt-get install chromium)")
    html = tmp_path / "trial.html"
    assert main(["trial", *SHORT, "--html", str(html), "--out", str(tmp_path / "out")]) == 0
    captured = capfd.readouterr()
    assert "Allocating contexts" not in captured.err and "INFO:drake" not in captured.err
    assert "localhost" not in captured.out + captured.err
    assert captured.out.count("== trial summary ==") == 1
    assert "outcome: target revealed" in captured.out and "revealed (revealed)" not in captured.out
    assert f"open {html} in a web browser" in captured.out
    assert json.loads((tmp_path / "out" / "trial.json").read_text())["success"] is True

    shot = tmp_path / "shot.png"
    # WebGL in headless Chromium needs ANGLE's software rasteriser. The virtual-time budget runs the recording
    # (about 20 s of simulated time, played at real time) to its end.
    subprocess.run([browser, "--headless", "--no-sandbox", "--use-angle=swiftshader", "--enable-unsafe-swiftshader",
                    "--disable-background-networking", "--disable-component-update", "--disable-sync",
                    "--no-first-run", f"--user-data-dir={tmp_path / 'chromium'}", "--window-size=800,600",
                    "--virtual-time-budget=60000", f"--screenshot={shot}", html.as_uri()],
                   check=True, timeout=180, capture_output=True)
    image = cv2.imread(str(shot))
    assert image is not None
    b, g, r = (image[..., i].astype(int) for i in range(3))
    target_red = (r > 150) & (g < 90) & (b < 90)  # the target is (0.9, 0.2, 0.2), shaded; nothing else is red
    assert np.count_nonzero(target_red) > 50


def test_step_figure_names_objects_as_the_tracker_and_trial_json_do(scene):
    """With the decision's tracks, the legend and the action name each object by its track name and its true
    object ("track_3 (= object_0)"), the names of trial.json and the step lines; without, the true names alone."""
    depth, labels = _images(scene)
    labels[80:90, 10:30] = 1  # object_0 in view
    p = np.ones(40) / 40
    action = {"type": "push", "object": "track_3", "q": [0.04, -0.04, 0.04], "d": -0.12}
    fig = step_figure(0, depth, labels, p, p, scene, action, 0.06, None, tracks={"object_0": "track_3"})
    texts = [t.get_text() for t in fig.axes[1].get_legend().get_texts()]
    assert "track_3 (= object_0)" in texts and "push track_3 (= object_0) d=-0.120 m" in texts
    plain = step_figure(0, depth, labels, p, p, scene)
    assert "object_0" in [t.get_text() for t in plain.axes[1].get_legend().get_texts()]
