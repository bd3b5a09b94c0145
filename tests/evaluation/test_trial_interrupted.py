"""A trial whose files are being written when the user presses Ctrl-C leaves no complete-looking trial.json."""

from __future__ import annotations

import json

import numpy as np
import pytest

from slax_drake.evaluation.trial import TrialRecord, write_trial
from slax_drake.systems import step_figure


def _record(steps: int = 2) -> TrialRecord:
    data = {"success": True, "result": "revealed", "steps": steps,
            "steps_log": [{"time": float(k)} for k in range(steps)]}
    images = [(k, np.zeros((4, 4)), np.zeros((4, 4), int), None, None) for k in range(steps)]
    return TrialRecord(data, images)


def test_ctrl_c_while_the_step_images_are_written_leaves_no_trial_json(tmp_path, monkeypatch):
    (tmp_path / "trial.json").write_text(json.dumps({"success": True, "from": "an earlier trial"}))
    drawn = []

    def png(record, step, *args):
        if drawn:
            raise KeyboardInterrupt
        drawn.append(step)
        return b"png"

    monkeypatch.setattr(step_figure, "step_png_of_record", png)
    with pytest.raises(KeyboardInterrupt):
        write_trial(_record(), tmp_path)
    assert (tmp_path / "step_00.png").exists()
    assert not (tmp_path / "trial.json").exists()


def test_trial_json_is_written_after_everything_it_describes(tmp_path, monkeypatch):
    monkeypatch.setattr(step_figure, "step_png_of_record", lambda *args: b"png")
    written = write_trial(_record(), tmp_path)
    assert written[0] == tmp_path / "trial.json"
    assert json.loads((tmp_path / "trial.json").read_text())["success"] is True
    newest = max(p.stat().st_mtime_ns for p in written)
    assert (tmp_path / "trial.json").stat().st_mtime_ns == newest


def test_an_older_trials_object_poses_are_not_left_beside_a_new_record(tmp_path, monkeypatch):
    monkeypatch.setattr(step_figure, "step_png_of_record", lambda *args: b"png")
    (tmp_path / "object_poses.npz").write_bytes(b"an earlier trial's")
    write_trial(_record(), tmp_path)
    assert not (tmp_path / "object_poses.npz").exists()
